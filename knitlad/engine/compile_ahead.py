"""Compiling the step kernels on two cores: the first run of a fresh install, or the first after a kernel was
edited, compiles them (:mod:`knitlad.engine.kernels`), about two minutes on one core.

Numba compiles a kernel the first time it is called with new argument types, and the kernels a kernel calls as
it types them, on one thread. The step's two largest subtrees are independent: the contact
(:func:`compile_contact_kernels`: the pair list and the pair forces) and the rods' own forces
(:func:`compile_rod_kernels`: elasticity, twist, dissipation, the implicit axial springs), and on top of them
the statics (FIRE) and the dynamics (Verlet). :func:`compile_ahead` compiles the contact and the statics here
and the rods and the dynamics in a helper process at the same time, each on a scene of two crossing yarns
called with the argument types the step gives them (``kernels/options.py``: one type per argument); the run's
own compilation then finds them in the cache. A kernel typed differently here is compiled again later: slower,
never wrong.
"""

from __future__ import annotations

import subprocess
import sys
import time

import numpy as np

from knitlad.engine import units
from knitlad.engine.contact import ContactModel, make_contacts
from knitlad.engine.kernels import is_compiled
from knitlad.engine.state import Scene, Workspace, with_twist

HELPER_TIMEOUT_S = 600.0  # the helper's compilation, at most (a loaded machine)


def _crossing():
    """Two straight yarns crossing at right angles, pressed 5 % of d into each other; their contact buffers and
    workspace."""
    scene = Scene()
    d = units.NYLON.diameter
    t = np.linspace(-3 * d, 3 * d, 7)
    for k in range(2):
        x = np.zeros((7, 3))
        x[:, k] = t
        x[:, 2] = k * 0.95 * d
        scene.add_yarn(x)
    rods = scene.build()
    return rods, make_contacts(rods, ContactModel(stiffness=1e3, mu=0.4)), Workspace.for_model(rods.model)


def compile_contact_kernels() -> None:
    """The contact's subtree of the step (:func:`~knitlad.engine.kernels.integrate.compute_forces`): the pair list
    and the pair forces, with their argument types there."""
    from knitlad.engine.kernels.contact import contact_forces, refresh_contacts

    rods, c, w = _crossing()
    m, s = rods.model, rods.state
    refresh_contacts(s.x, m.edge_a, m.edge_b, m.edge_shift, c, s.v, 0.0)
    contact_forces(s.x, s.v, s.omega, 0, m.mass, m.edge_a, m.edge_b, m.edge_shift, c, 1e-6, w.force, w.torque, s.v,
                   s.omega, False, w.ledger)


def compile_rod_kernels() -> None:
    """The rods' own subtree of the step: stretching and bending, twist (frame-free and framed), the viscoelastic
    branches and the air, the implicit axial springs, with their argument types there; and the energies (the
    ledger reads them), which the contact's part would leave to the end."""
    from knitlad.engine.kernels import integrate as k

    rods, c, w = _crossing()
    k.potential_energy(rods.model, rods.state, w, c, 0, True)
    k.kinetic_energy(rods.model, rods.state)
    twisted = with_twist(rods, units.NYLON.twisting_stiffness / units.NYLON.bending_stiffness)
    for r in (rods, twisted):
        m, s = r.model, r.state
        w = Workspace.for_model(m)
        k.elastic_forces_by_yarn(m, s, w, True, s.v, 1e-6)
        k.straight_twisting_forces_by_yarn(m, s, w, True, s.v, 1e-6)
        k.framed_forces_by_yarn(m, s, w, True, s.v, 1e-6)
        k.dissipative_forces_by_yarn(m, w, s.v, 0.1, 0.9, 1e-7, 1.2, 1.5e-5, 1.0, 1e-6)
        k.implicit_stretching_by_yarn(m, s, w, 1e-6)


def _simulation():
    """A simulation of the crossing yarns with contact and friction, as the laddering builds one."""
    from knitlad.engine.simulation import Simulation

    rods, _, _ = _crossing()
    return Simulation(rods, contact=ContactModel(stiffness=1e3, mu=0.4), implicit_axial=True)


def _other_subtree_or_timeout(timeout_s: float = HELPER_TIMEOUT_S) -> None:
    """Wait until the cache holds both subtrees (the other process's too), at most ``timeout_s``."""
    end = time.monotonic() + timeout_s
    while not compiled_ahead() and time.monotonic() < end:
        time.sleep(0.5)


def compile_statics() -> None:
    """The contact's subtree; once the rods' is in the cache too, the step's forces and FIRE (a stretch) on top."""
    compile_contact_kernels()
    _other_subtree_or_timeout()
    _simulation().relax(max_steps=2)


def compile_dynamics() -> None:
    """The rods' subtree; once the contact's is in the cache too, the step's forces and Verlet (a ladder) on top."""
    compile_rod_kernels()
    _other_subtree_or_timeout()
    _simulation().step(2)


PARTS = {"statics": compile_statics, "dynamics": compile_dynamics}


def compiled_ahead() -> bool:
    """Whether both subtrees are in the cache, compiled from the present kernel sources."""
    from knitlad.engine.kernels.contact import contact_forces
    from knitlad.engine.kernels.integrate import framed_forces_by_yarn

    return is_compiled(contact_forces) and is_compiled(framed_forces_by_yarn)


def compile_ahead() -> None:
    """Compile the contact here and the rods' kernels in a helper process at once, then wait for it; nothing if
    both are cached. A helper that fails or hangs is left: the step compiles what it did not."""
    if compiled_ahead():
        return
    helper = subprocess.Popen([sys.executable, "-m", "knitlad.engine.compile_ahead", "dynamics"],
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        compile_statics()
        helper.wait(timeout=HELPER_TIMEOUT_S)
    except subprocess.TimeoutExpired:
        helper.kill()
    except BaseException:  # Ctrl-C: the helper goes with us
        helper.kill()
        raise


if __name__ == "__main__":  # python -m knitlad.engine.compile_ahead PART
    PARTS[sys.argv[1]]()
