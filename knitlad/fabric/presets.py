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
# crassous2023: the authors' engine (J. Crassous, Frictional-Fibers, commit b2c502d; Phys. Rev. E 107, 025003,
# 2023), each choice from its source, in its units (knitlad.engine.dissipation, the AUTHORS_ constants):
# - a segment as long as the yarn's radius (jersey.c: radius 1, l0 1): 140 nodes per stitch at d/l0 = 1/70;
#   capsules of the yarn's radius (kernel_contact_v9.6.cl), no sagitta correction;
# - a global drag on every node and on every segment's twist rate at the same lambda (kernel_le_force_v9.6.cl);
#   its value for the paper is not published: AUTHORS_DRAG_LAMBDA, the largest under the paper's own ceiling
#   (docs/paper_claims.md);
# - twist always on, a spin inertia twice a cylinder's (jersey.c: j = masse);
# - a normal contact dashpot absolute per contact, none along the surface (main.c: lambda_contact_n 1,
#   lambda_contact_t 0), every touching segment pair counted (kernel_CalculateContactForce);
# - an axial dashpot of 2.8 sqrt(EA rho_L), 1.98 x critical (main.c: lambda_internal 2.8).
# Not taken: their position Verlet with float32 forces (ours: velocity Verlet, float64, the axial springs
# implicit), their dashpot that may pull while a contact separates (ours never pulls), their contact stiffness
# (ours: KNIT_CONTACT_FORCE_F0 at KNIT_OVERLAP, which moves v_lad by under 5 %: docs/dissipation.md).
AUTHORS_DRAG_LAMBDA = 1e-4
LADDER_PRESETS = {
    "fast": {"resolution": 24, "sagitta_radius": 0.0, "implicit_axial": False, "dt_safety": 0.35},
    "default": {"resolution": 48, "sagitta_radius": SAGITTA_RADIUS_D, "implicit_axial": True, "dt_safety": 0.35},
    "accurate": {"resolution": 96, "sagitta_radius": SAGITTA_RADIUS_D, "implicit_axial": True, "dt_safety": 0.7},
    "crassous2023": {"resolution": 140, "sagitta_radius": 0.0, "implicit_axial": True, "dt_safety": 0.7,
                     "twist": True, "twist_inertia_factor": 2.0, "drag_lambda": AUTHORS_DRAG_LAMBDA,
                     "spin_drag": True, "contact_dashpot": "absolute", "contact_counting": "all_pairs",
                     "stretch_damping_ratio": 1.98},
}
# settings of the laddering's dynamics, not of a stitch
DYNAMICS_ONLY = ("implicit_axial", "dt_safety", "twist", "twist_inertia_factor", "drag_lambda", "spin_drag",
                 "contact_dashpot", "contact_counting", "stretch_damping_ratio")
STITCH_PRESETS = {name: {k: v for k, v in p.items() if k not in DYNAMICS_ONLY} for name, p in LADDER_PRESETS.items()}
LOOP_PRESETS = {"fast": {"resolution": 24}, "default": {"resolution": 36}, "accurate": {"resolution": 48},
                "crassous2023": {"resolution": 140}}

# each preset's measured error, for the help texts (the tables: docs/accuracy.md)
PRESET_HELP = (
    "accuracy preset, each with its error against the converged reference: fast (24 nodes per stitch, "
    "capsules of the yarn's radius: stitch tension at fixed geometry +33 to +136 %, knit 0.006-0.012 l0 "
    "narrow at a given tension, v_lad -9 to -14 %); default (48, the contact's sagitta correction, implicit "
    "axial springs: tension -3 to +6 %, width within 0.001 l0, v_lad -12 to -18 % at low tension, +7 % at "
    "high, about 2 x fast's cost); accurate (96, the same: tension -3 to 0 %, width within 0.0003 l0, v_lad "
    "-4 to -8 % at low tension, +2 % at high, stepping at 0.7 x its stability limit: about 7 x fast's cost); "
    "crassous2023 (the authors' engine as their code sets it: 140 nodes, twist, their drag on nodes and spin, "
    "their dashpots and contact counting; not converged, a comparison: docs/paper_claims.md) [-]"
)

# each preset's error against the converged reference, in one line (reports; docs/accuracy.md)
PRESET_ERRORS = {
    "fast": "v_lad/c_b -9 to -14 %, tension at fixed geometry +33 to +136 %",
    "default": "v_lad/c_b -12 to -18 % at low tension, +7 % at 13.6; tension at fixed geometry -3 to +6 %",
    "accurate": "v_lad/c_b -4 to -8 % at low tension, +2 % at 13.6; tension at fixed geometry -3 to 0 %",
    "crassous2023": "the authors' engine's model, drag included: a comparison, not a converged reference",
}
