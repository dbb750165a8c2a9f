"""knitlad: discrete elastic rods with frictional contact, for knitted fabric."""

from knitlad.simulation import Simulation, SimulationBlowUp, UnstableTimeStep
from knitlad.state import RodModel, Rods, RodState, Scene
from knitlad.units import NYLON, Material, Scales

__version__ = "0.2.0"

__all__ = [
    "Material",
    "NYLON",
    "RodModel",
    "RodState",
    "Rods",
    "Scales",
    "Scene",
    "Simulation",
    "SimulationBlowUp",
    "UnstableTimeStep",
    "__version__",
]
