"""knitlad.fabric.topology: piercings of a ring's spanning surface, against hand-built curves."""

from __future__ import annotations

import math

import numpy as np

from knitlad.fabric.topology import piercings


def ring(n: int = 24, r: float = 1.0) -> np.ndarray:
    phi = 2 * math.pi * np.arange(n) / n
    return np.column_stack([r * np.cos(phi), r * np.sin(phi), 0 * phi])


def test_a_straight_line_through_a_ring_pierces_it_once_with_the_sign_of_its_direction():
    up = np.array([[0.2, 0.1, -1.0], [0.2, 0.1, 1.0]])
    (n_up, sign_up), (n_down, sign_down) = piercings(ring(), up), piercings(ring(), up[::-1].copy())
    assert n_up == n_down == 1 and abs(sign_up) == 1 and sign_down == -sign_up
    assert piercings(ring(), up + [2.0, 0.0, 0.0]) == (0, 0)  # outside the ring


def test_a_u_threaded_through_a_ring_pierces_it_twice_with_opposite_signs_and_one_beside_it_never():
    s = np.linspace(0, math.pi, 30)
    u = np.column_stack([0.5 * np.cos(s), 0 * s, -np.sin(s) + 0.5])  # dips through the ring's plane twice
    assert piercings(ring(), u) == (2, 0)
    assert piercings(ring(), u + [3.0, 0.0, 0.0]) == (0, 0)  # the same U beside the ring
    assert piercings(ring(), u + [0.0, 0.0, 2.0]) == (0, 0)  # above it, not through
