"""Numba kernels: plain ``@njit(cache=True)`` functions over arrays.

They keep no module state and write into preallocated outputs. Array layout
(said once, used everywhere): node arrays are ``(n, 3)`` float64 in internal
units (:mod:`knitlad.engine.units`); edge arrays are indexed by edge id ``k`` joining
``edge_a[k] -> edge_b[k]`` (plus ``edge_shift[k]`` for the closing edge of a
periodised yarn); hinge arrays are indexed by bending hinge ``h`` between edges
``hinge_e0[h]`` (ending at the hinge node) and ``hinge_e1[h]`` (starting there).
"""
