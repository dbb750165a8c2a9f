"""Layer 6, many runs: the sweep registry (one entry per sweepable scene), YAML sweeps expanded into jobs,
their runner (process pool or Dask, resumable, locked), batch clusters, and paired ensembles for studies
of one ladder's scatter."""
