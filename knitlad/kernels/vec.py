"""Three-vector algebra on scalars, so inner loops allocate nothing."""

from numba import njit


@njit(cache=True, inline="always")
def dot(ax, ay, az, bx, by, bz):
    return ax * bx + ay * by + az * bz


@njit(cache=True, inline="always")
def cross(ax, ay, az, bx, by, bz):
    return ay * bz - az * by, az * bx - ax * bz, ax * by - ay * bx
