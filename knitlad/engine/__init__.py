"""Layer 1, the rod engine: the internal units, the Numba kernels (``kernels/``), rods as a model and a
state (``state.py``), frictional contact, obstacles, the stability limits of the time step, and the
``Simulation`` that steps, relaxes and settles them, with the one run loop of every experiment
(``runloop.run_until``). Knows nothing of knitting; imports nothing else of knitlad."""
