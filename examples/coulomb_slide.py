"""A yarn pressed on two crossing yarns and dragged along its axis: each sliding contact carries
mu times its normal force, opposite to the motion (Coulomb). Per-contact read-out, public API only.

    python examples/coulomb_slide.py
"""

import numpy as np

import knitlad as kl


def drag(mu=0.4, press=0.2, speed=1.0, steps=100):
    """Per-contact (normal, friction) magnitudes [N] and sliding flags after ``steps`` of 1 us of drag."""
    d = kl.NYLON.diameter
    t = np.linspace(-10 * d, 10 * d, 21)
    scene = kl.Scene(kl.NYLON)
    dragged = scene.add_yarn(np.column_stack([t, 0 * t, np.full_like(t, (1 - press) * d)]))
    scene.hold(dragged, range(t.size), velocity=(speed, 0.0, 0.0))       # moved rigidly along x
    for x0 in (-3 * d, 3 * d):                                          # two yarns across, held rigid
        scene.hold(scene.add_yarn(np.column_stack([np.full_like(t, x0), t, 0 * t])), range(t.size))
    contact = kl.ContactModel(stiffness=1e3, mu=mu)               # N/m; the overlap is press * d
    sim = kl.Simulation(scene.build(), contact=contact, dt_s=1e-6)      # all held: any step is stable
    sim.step(steps)
    pairs = sim.contact_pairs()
    return np.linalg.norm(pairs.normal_N, axis=1), np.linalg.norm(pairs.friction_N, axis=1), pairs


if __name__ == "__main__":
    fn, ft, pairs = drag()
    for n, f, sliding, fx in zip(fn, ft, pairs.sliding, pairs.friction_N[:, 0]):
        print(f"normal {n * 1e3:.3f} mN, friction {f * 1e3:.3f} mN = {f / n:.4f} x normal, "
              f"{'sliding' if sliding else 'sticking'}, along x {fx * 1e3:+.3f} mN")
