"""A simulation's checkpoint: everything a run changes, as named arrays, and its restoration.

A run's mutable state is spread over the rods' state (positions, velocities, twist), the
workspace (the forces of the last evaluation, which the next half kick uses; the viscoelastic
branches; the energy ledger), the contact list with each pair's tangential spring (the friction
history), the obstacles' springs, the held nodes and loads of the model (``hold``, ``release``,
``set_external_forces`` change them), and the clock. :meth:`Checkpointing.checkpoint` gathers them;
:meth:`Checkpointing.restore` puts them into a simulation built the same way (the same rods, contact,
obstacles and settings), which then continues to the bit as the first would have. Writing them is the
io layer's (:func:`knitlad.io.hdf5.write_arrays`); what they were built from is the caller's to keep.
"""

from __future__ import annotations

import numpy as np

# the model's arrays a run changes (hold, release, move_held's velocities, loads); the rest is built
MODEL_CHANGES = ("held", "v_prescribed", "f_ext", "theta_held")
# settings (mu is kept on its own; a checkpoint written before the law table has a "stiffness" nobody reads),
# and a rebuild's scratch
CONTACT_SKIPPED = ("params", "list_scratch", "union", "pair_law")
OBSTACLE_SKIPPED = ("law", "reference_overlap")  # settings no run changes (release zeroes the stiffnesses)
# arrays that gained columns (the ledger's owner_changes, a pair's union verdict): an older checkpoint's are padded
WIDENED = ("work/ledger", "contacts/slip", "contacts/pair_results")
# arrays added later (the rails' reactions): an older checkpoint has none, and they start at 0
ADDED_LATER = ("work/rail_reaction",)


class Checkpointing:
    """Mixin of :class:`knitlad.engine.simulation.Simulation`: :meth:`checkpoint` and :meth:`restore`."""

    def checkpoint(self) -> dict[str, np.ndarray]:
        """Copies of every array a run changes, by name (internal units), and the clock ("clock": time [ms],
        steps, the global drag, the ledger's start, the closing edges' drift, the energy breaks took)."""
        out = {f"state/{k}": np.array(v) for k, v in self.state._asdict().items()}
        out |= {f"work/{k}": np.array(v) for k, v in self.work._asdict().items()}
        out |= {f"model/{k}": np.array(getattr(self.model, k)) for k in MODEL_CHANGES}
        if self.has_contact:
            out |= {f"contacts/{k}": np.array(v) for k, v in self.contacts._asdict().items()
                    if k not in CONTACT_SKIPPED}
            out["contacts/mu"] = np.array(self.contacts.params.mu)
        if self.obstacles is not None:
            out |= {f"obstacles/{k}": np.array(v) for k, v in self.obstacles._asdict().items()
                    if k not in OBSTACLE_SKIPPED}
        out["clock"] = np.array([self.time, self.steps, self.drag, *self._ledger_start, self._shift_drift,
                                 self._fracture_J],
                                dtype=np.float64)
        return out

    def restore(self, checkpoint: dict[str, np.ndarray]) -> None:
        """Put a :meth:`checkpoint` of a simulation built the same way into this one. ValueError, naming the
        array, if it does not fit (another scene, resolution or contact)."""
        from knitlad.engine.contact import make_contacts

        def fit(name: str, like: np.ndarray) -> np.ndarray:
            if name not in checkpoint and name in ADDED_LATER:
                return np.zeros_like(like)
            if name not in checkpoint:
                raise ValueError(f"the checkpoint has no {name}: it was made by another kind of simulation")
            value = np.asarray(checkpoint[name])
            if name in WIDENED and value.ndim == 2 and value.shape[1] < np.shape(like)[1]:
                # written before the array had its last columns (those start at 0)
                value = np.pad(value, ((0, 0), (0, np.shape(like)[1] - value.shape[1])))
            if value.shape != np.shape(like):
                raise ValueError(f"the checkpoint's {name} has shape {value.shape}, this simulation's "
                                 f"{np.shape(like)}: it was made from another scene or resolution")
            return value

        for group, arrays in (("state", self.state), ("work", self.work)):
            for k, a in arrays._asdict().items():
                a[...] = fit(f"{group}/{k}", a)
        self.rods = self.rods.replace_model(**{k: fit(f"model/{k}", getattr(self.model, k)).copy()
                                               for k in MODEL_CHANGES})
        if self.has_contact:
            capacity = int(np.shape(checkpoint.get("contacts/pairs", np.zeros((0, 2))))[0])
            if capacity != self.contacts.pairs.shape[0]:  # the first run had grown its buffer
                self.contacts = make_contacts(self.rods, self.contact_model, capacity=capacity)
            for k, a in self.contacts._asdict().items():
                if k not in CONTACT_SKIPPED:
                    a[...] = fit(f"contacts/{k}", a)
            self.set_friction(float(fit("contacts/mu", np.zeros(()))))
        if self.obstacles is not None:
            for k, a in self.obstacles._asdict().items():
                if k not in OBSTACLE_SKIPPED:
                    a[...] = fit(f"obstacles/{k}", a)
        older = np.shape(checkpoint.get("clock")) == (6,)  # written before breaks were booked: none were
        clock = np.append(fit("clock", np.zeros(6)), 0.0) if older else fit("clock", np.zeros(7))
        time, steps, drag, ledger_stored, ledger_time, drift, fracture = clock
        self.time, self.steps, self.drag = float(time), int(steps), float(drag)
        self._ledger_start, self._shift_drift = (float(ledger_stored), float(ledger_time)), float(drift)
        self._fracture_J = float(fracture)
