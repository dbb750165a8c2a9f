"""Layer 5, pictures: figures of runs and sweeps (``plots.py``) and renders and movies (``render.py``),
read from the files that ``io`` writes, never from a live simulation."""
