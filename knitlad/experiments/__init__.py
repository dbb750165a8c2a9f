"""Layer 3, the experiments: each goes config -> settings -> a prepared value -> a run under observers and
stop rules (the engine's ``run_until``) -> a result whose summary is read from its fields. The laddering
(``laddering.py``), protocol B's loading cycles (``cycling.py``), the periodised stitch, the single loop in
its two geometries, the rod demo, and their pydantic configs (``config.py``). Imports the engine and the
fabric."""
