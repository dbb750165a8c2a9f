"""The accuracy presets: what each sets, chosen from the converged reference (docs/accuracy.md).

Each preset sets the resolution, the contact's sagitta correction
(:func:`knitlad.engine.contact.sagitta_corrected_radius`) and, for the laddering, the axial springs and
the step factor;
:mod:`knitlad.experiments.config` fills every setting of the chosen preset that a run does not give.
``fast`` is the model as it stood before the reference (24 nodes per stitch, capsules of the
yarn's radius). The errors quoted are those measured against the reference (docs/accuracy.md).
"""

from __future__ import annotations

SAGITTA_RADIUS_D = 11.0  # the stitch's contacts' radius of curvature for the sagitta correction, in d

# dt_safety: the laddering's step over its stability limit, chosen by paired runs at each resolution: 0.35 at
# 24 and 48 nodes per stitch, 0.7 at 96, where the step 0.7 x the (shorter) limit gives the ladder of
# 0.175 x it (docs/performance.md, "The accurate preset's step")
LADDER_PRESETS = {
    "fast": {"resolution": 24, "sagitta_radius": 0.0, "implicit_axial": False, "dt_safety": 0.35},
    "default": {"resolution": 48, "sagitta_radius": SAGITTA_RADIUS_D, "implicit_axial": True, "dt_safety": 0.35},
    "accurate": {"resolution": 96, "sagitta_radius": SAGITTA_RADIUS_D, "implicit_axial": True, "dt_safety": 0.7},
}
DYNAMICS_ONLY = ("implicit_axial", "dt_safety")  # settings of the laddering's dynamics, not of a stitch
STITCH_PRESETS = {name: {k: v for k, v in p.items() if k not in DYNAMICS_ONLY} for name, p in LADDER_PRESETS.items()}
LOOP_PRESETS = {"fast": {"resolution": 24}, "default": {"resolution": 36}, "accurate": {"resolution": 48}}

# each preset's measured error, for the help texts (the tables: docs/accuracy.md)
PRESET_HELP = (
    "accuracy preset, each with its error against the converged reference: fast (24 nodes per stitch, "
    "capsules of the yarn's radius: stitch tension at fixed geometry +33 to +136 %, knit 0.006-0.012 l0 "
    "narrow at a given tension, v_lad -9 to -14 %); default (48, the contact's sagitta correction, implicit "
    "axial springs: tension -3 to +6 %, width within 0.001 l0, v_lad -12 to -18 % at low tension, +7 % at "
    "high, about 2 x fast's cost); accurate (96, the same: tension -3 to 0 %, width within 0.0003 l0, v_lad "
    "-4 to -8 % at low tension, +2 % at high, stepping at 0.7 x its stability limit: about 7 x fast's cost) [-]"
)

# each preset's error against the converged reference, in one line (reports; docs/accuracy.md)
PRESET_ERRORS = {
    "fast": "v_lad/c_b -9 to -14 %, tension at fixed geometry +33 to +136 %",
    "default": "v_lad/c_b -12 to -18 % at low tension, +7 % at 13.6; tension at fixed geometry -3 to +6 %",
    "accurate": "v_lad/c_b -4 to -8 % at low tension, +2 % at 13.6; tension at fixed geometry -3 to 0 %",
}
