"""Rolling/sliding contact of an elastic body on an elastic substrate (Spector & Batra 1995)."""

from ._validate import InputError
from .dynamics import Body, Lateral, Loads, load_utilisation
from .integrator import RollingBody
from .laws.thin_layer import LayerContact, TractionField
from .simulate import Trajectory, load_history, simulate
from .solvers import StageSolveError

__all__ = [
    "Body",
    "InputError",
    "Lateral",
    "LayerContact",
    "Loads",
    "RollingBody",
    "StageSolveError",
    "TractionField",
    "Trajectory",
    "load_history",
    "load_utilisation",
    "simulate",
]
