"""Normal contact laws: the spring of a touching pair of yarns, or of a node on an obstacle, chosen by a mode.

A law gives the normal spring's force f(delta) and its stored energy U(delta) = int_0^delta f for an
overlap delta >= 0, from two parameters: the stiffness k [force/length] and the reference overlap
delta_ref [length]. Every law passes through the same working point, f(delta_ref) = k delta_ref, so a
knit's contact set as "a contact carrying F overlaps by 5 % of d" (:meth:`ContactModel.for_force
<knitlad.engine.contact.ContactModel.for_force>`) carries F at 5 % of d whatever the law.

* LINEAR, the penalty spring of discrete elements (Cundall & Strack 1979) and of yarn contact
  (Durville 2010): f = k delta, U = k delta^2 / 2. delta_ref plays no part.
* HERTZ, the elastic contact of two cylinders of equal radius R crossing at right angles, which touch
  as a sphere of radius R on a plane (Johnson 1985, Contact Mechanics, sec. 4.2 and 4.3):
  f = (4/3) E* sqrt(R) delta^(3/2). Through the working point: f = k delta_ref (delta/delta_ref)^(3/2),
  U = 2 f delta / 5. Softer than the penalty below delta_ref, stiffer above it. (For the paper's Nylon,
  E* = E / 2(1 - nu^2) with nu = 0.4 gives 16 f0 at 5 % of d: the knit's 20 f0 there is close to it.)

The dashpot and the tangential spring stay linear in every law (:func:`knitlad.engine.kernels.contact.
pair_contact_forces`): a dashpot's ratio is a fraction of critical at k.

A new law is one branch in :func:`normal_spring` and :func:`normal_spring_energy` and one row in ``LAWS``
(its name and its largest slope for the time step); nothing outside this module changes.
"""

import math

from numba import njit

from knitlad.engine.kernels.options import INLINE_OPTS

LINEAR, HERTZ = 0, 1
# columns of a contact's law table (c, c, LAW_COLUMNS), one row per pair of edge classes (materials, and
# yarns of their own friction): k_n and k_t [mN/mm], the law's mode, delta_ref [mm], and the factor on the
# Coulomb coefficient mu of the pair (knitlad.engine.contact.pair_law_table)
K_NORMAL, K_TANGENT, LAW, REFERENCE_OVERLAP, FRICTION_FACTOR = range(5)
LAW_COLUMNS = 5
# the time step is stable for overlaps up to this many delta_ref (a contact then carries 8 x the working
# force under HERTZ): the stiffest slope df/d(delta) a law reaches there sets the contact's step
STEP_OVERLAP_OVER_REFERENCE = 4.0
# name -> (mode, largest slope over k for overlaps up to STEP_OVERLAP_OVER_REFERENCE delta_ref)
LAWS = {
    "linear": (LINEAR, 1.0),
    "hertz": (HERTZ, 1.5 * math.sqrt(STEP_OVERLAP_OVER_REFERENCE)),  # df/d(delta) = (3/2) k sqrt(delta/delta_ref)
}


def law_mode(name: str) -> int:
    """The kernels' mode of the law ``name`` (ValueError naming the laws if there is none)."""
    if name not in LAWS:
        raise ValueError(f"contact law must be one of {', '.join(LAWS)}, got {name!r}")
    return LAWS[name][0]


def largest_slope_factor(name: str) -> float:
    """The law's largest df/d(delta) over k for the overlaps the time step allows (STEP_OVERLAP_OVER_REFERENCE)."""
    law_mode(name)
    return LAWS[name][1]


@njit(**INLINE_OPTS)
def normal_spring(law, k, delta_ref, delta):
    """Normal spring force f(delta) of the law (module docstring) at an overlap delta > 0; NaN for a mode
    with no branch here, which the blow-up guard stops (never another law's force)."""
    if law == LINEAR:
        return k * delta
    if law == HERTZ:
        return k * delta * math.sqrt(delta / delta_ref)
    return math.nan


@njit(**INLINE_OPTS)
def normal_spring_energy(law, k, delta_ref, delta):
    """Stored energy U(delta) = int_0^delta f of the law's normal spring at an overlap delta >= 0 (NaN for a
    mode with no branch here)."""
    if law == LINEAR:
        return 0.5 * k * delta * delta
    if law == HERTZ:
        return 0.4 * k * delta * delta * math.sqrt(delta / delta_ref)
    return math.nan
