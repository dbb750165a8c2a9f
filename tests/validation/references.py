"""Independent references for the validation tests (plain numpy, no knitlad kernels)."""

from __future__ import annotations

import numpy as np

# The paper's 42 x 42 DER laddering runs (mu = 0.4, l_y/l0 = 0.25; appendix "Simulations"):
# (f_x^ini, v_lad/c_b). Fig. 5 shows more, undigitised; the two are joined by a straight line.
PAPER_DER_POINTS = ((1.58, 0.176), (15.67, 1.05))


def paper_der_line(fx: float) -> float:
    """v_lad/c_b on the straight line through the paper's two DER points (0.062 f_x + 0.078)."""
    (f1, v1), (f2, v2) = PAPER_DER_POINTS
    return v1 + (v2 - v1) * (fx - f1) / (f2 - f1)


def elastica_tip(load_parameter: float, n: int = 4000) -> tuple[float, float]:
    """Tip of an inextensible cantilever under a tip force normal to its clamp.

    Clamped at s = 0 along +x, force -P y_hat at s = L; with alpha = P L^2 / B and
    s in units of L the elastica is theta'' = alpha cos(theta) (from B theta' = M = -P (x_tip - x)), theta(0) = 0,
    theta'(1) = 0 (moment-free tip). Shooting on theta'(0) with RK4 and bisection.
    Returns (x_tip, y_tip) / L.
    """

    def integrate(k0: float) -> tuple[float, float, float]:
        h = 1.0 / n
        th, k, x, y = 0.0, k0, 0.0, 0.0

        def rhs(th_, k_):
            return k_, alpha * np.cos(th_)

        alpha = load_parameter
        for _ in range(n):
            a1 = rhs(th, k)
            a2 = rhs(th + 0.5 * h * a1[0], k + 0.5 * h * a1[1])
            a3 = rhs(th + 0.5 * h * a2[0], k + 0.5 * h * a2[1])
            a4 = rhs(th + h * a3[0], k + h * a3[1])
            # position from the same stages (Simpson on cos/sin of theta)
            x += h / 6 * (np.cos(th) + 2 * np.cos(th + 0.5 * h * a1[0]) + 2 * np.cos(th + 0.5 * h * a2[0]) + np.cos(th + h * a3[0]))
            y += h / 6 * (np.sin(th) + 2 * np.sin(th + 0.5 * h * a1[0]) + 2 * np.sin(th + 0.5 * h * a2[0]) + np.sin(th + h * a3[0]))
            th += h / 6 * (a1[0] + 2 * a2[0] + 2 * a3[0] + a4[0])
            k += h / 6 * (a1[1] + 2 * a2[1] + 2 * a3[1] + a4[1])
        return k, x, y

    # theta' = kappa decreases toward the tip (bending moment P (L - x) is largest at the clamp);
    # with the force along -y the curve turns clockwise: theta(s) < 0, theta'(0) = -kappa_0.
    lo, hi = -load_parameter * 1.5 - 1.0, 0.0
    for _ in range(80):
        mid = 0.5 * (lo + hi)
        k_end, _, _ = integrate(mid)
        if k_end > 0:
            hi = mid
        else:
            lo = mid
    _, x, y = integrate(0.5 * (lo + hi))
    return x, y
