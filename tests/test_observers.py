"""The stop rules and recorders of knitlad.observers."""

from __future__ import annotations

import numpy as np

from knitlad.observers import TOP_ROWS_HELD, Arrested, EdgeReached


def test_the_top_edge_is_the_row_below_the_held_course():
    """Rows of cells run from course 0 to the top free course; the cell of the top free course
    lies under the held top course and cannot ladder, so the row below it is the top edge."""
    undone = np.zeros((16, 16), dtype=bool)
    rule = EdgeReached()
    undone[5:15 - TOP_ROWS_HELD, 7] = True
    assert rule.check(0.0, undone) is None
    undone[15 - TOP_ROWS_HELD, 7] = True
    assert rule.check(0.0, undone) == "ladder reached an edge course"
    bottom = np.zeros((16, 16), dtype=bool)
    bottom[0, 3] = True
    assert rule.check(0.0, bottom) is not None


def test_arrest_is_declared_after_the_window_without_change():
    rule = Arrested(arrest_s=1e-3)
    undone = np.zeros((4, 4), dtype=bool)
    assert rule.check(0.0, undone) is None
    undone[1, 1] = True
    assert rule.check(0.5e-3, undone) is None
    assert rule.check(1.4e-3, undone) is None
    assert rule.check(1.5e-3, undone) is not None
