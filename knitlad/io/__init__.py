"""Writers: HDF5 trajectories and summaries, written atomically."""
