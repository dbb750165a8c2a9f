"""Layer 4, what goes out: atomic writes and locked output folders, the HDF5 files (runs, stretched knits,
trajectories, protocol B), the ParaView file (``xdmf.py``), kept stretched knits, the summary table, the
code identity every output records (``provenance.py``) and progress lines and files (``progress.py``).
Imports the layers below; the experiments' values it writes are imported where they are read."""
