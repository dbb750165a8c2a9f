"""One course of a small stretched knit pulled out at one end, step by step: the pull against its
displacement. Frictionless, the pull's work equals the knit's stored energy gained (statics, to the
trapezoid rule); with friction, the work exceeds it: the difference is dissipated. Public API only.

    python examples/pull_out.py
"""

import numpy as np

import knitlad as kl


def pull(mu=0.0, steps=10, step_m=2e-5, course=2):
    """(displacements [m], pulls [N], stored energies [J]) of a 4 x 4 knit's ``course`` pulled along +x."""
    knit = kl.stretch(kl.CutConfig(n_x=4, n_y=4, lx=0.36, preset="fast").stretch_settings())
    rods = knit.knit.rods.copy()
    contact = kl.ContactModel.for_knit(kl.NYLON, mu=mu)
    sim = kl.Simulation(rods, contact=contact)
    end = sim.nodes_of(knit.knit.courses[course], [-2, -1])                 # the clamp at its right end
    sim.release(end[:1])                                                    # the end node alone holds it
    sim.relax(force_tol_N=1e-8, max_steps=400_000)
    x, f, e = [0.0], [sim.reaction_forces_N()[end[1], 0]], [sim.energies_J()["total"]]
    for k in range(1, steps + 1):
        sim.move_held(end[1:], by_m=(step_m, 0.0, 0.0))
        out = (sim.relax(force_tol_N=1e-8, max_steps=400_000) if mu == 0 else      # statics; with friction,
               sim.settle(force_tol_N=1e-6, max_time_s=0.02, damping_per_s=2e4))  # damped dynamics
        assert out["converged"], out
        x.append(k * step_m)
        f.append(sim.reaction_forces_N()[end[1], 0])                        # the pull along +x
        e.append(sim.energies_J()["total"])
    return np.array(x), np.array(f), np.array(e)


if __name__ == "__main__":
    for mu in (0.0, 0.4):
        x, f, e = pull(mu)
        work = np.sum(0.5 * (f[1:] + f[:-1]) * np.diff(x))
        print(f"mu = {mu}: pull {f[0] * 1e3:.3f} -> {f[-1] * 1e3:.3f} mN over {x[-1] * 1e3:.2f} mm; "
              f"work {work * 1e9:.3f} nJ, stored energy gained {(e[-1] - e[0]) * 1e9:.3f} nJ")
