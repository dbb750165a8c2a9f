"""knitlad: discrete elastic rods with frictional contact, for knitted fabric.

The public surface is the names in ``__all__`` (listed with their promise in ``docs/api.md``;
changes in ``CHANGELOG.md``). The rod engine is imported at once; the laddering experiment's
names load on first use, so that ``import knitlad`` stays light.
"""

import importlib

from knitlad.engine.contact import ContactModel, ContactPairs, ContactStats
from knitlad.engine.dissipation import AirDrag, EnergyLedger, MaterialDamping
from knitlad.engine.obstacles import Cylinder, Plane
from knitlad.engine.simulation import MovingSupportWarning, Simulation, SimulationBlowUp, UnstableTimeStep
from knitlad.engine.state import RodModel, Rods, RodState, Scene
from knitlad.engine import units  # the internal unit system (knitlad.units.LENGTH, ...), as before the folders
from knitlad.engine.units import NYLON, Material, Scales

__version__ = "0.14.0"

# the laddering experiment: name -> module that defines it (loaded on first use, PEP 562)
_EXPERIMENT = {
    "CutConfig": "knitlad.experiments.config",
    "StitchConfig": "knitlad.experiments.config",
    "LoopConfig": "knitlad.experiments.config",
    "LADDER_PRESETS": "knitlad.fabric.presets",
    "StretchedKnit": "knitlad.fabric.preparation",
    "Laddering": "knitlad.experiments.laddering",
    "LadderTrace": "knitlad.experiments.laddering",
    "LadderResult": "knitlad.experiments.laddering",
    "stretch": "knitlad.fabric.preparation",
    "cut": "knitlad.experiments.laddering",
    "propagate": "knitlad.experiments.laddering",
    "analyse": "knitlad.experiments.laddering",
    "run_ladder": "knitlad.experiments.laddering",
    "read_stretched_knit": "knitlad.io.hdf5",
    "write_stretched_knit": "knitlad.io.hdf5",
    "TrajectoryRecorder": "knitlad.fabric.observers",
    "write_trajectory": "knitlad.io.hdf5",
}

__all__ = [
    "AirDrag",
    "ContactModel",
    "ContactPairs",
    "ContactStats",
    "Cylinder",
    "EnergyLedger",
    "Material",
    "MaterialDamping",
    "MovingSupportWarning",
    "NYLON",
    "Plane",
    "RodModel",
    "RodState",
    "Rods",
    "Scales",
    "Scene",
    "Simulation",
    "SimulationBlowUp",
    "UnstableTimeStep",
    "__version__",
    *_EXPERIMENT,
]


def __getattr__(name: str):
    if name in _EXPERIMENT:
        value = getattr(importlib.import_module(_EXPERIMENT[name]), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'knitlad' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_EXPERIMENT))
