"""Rolling/sliding contact of an elastic body on an elastic substrate (Spector & Batra 1995)."""

from ._validate import InputError
from .dynamics.body import Body, Lateral, Loads, load_utilisation
from .dynamics.integrator import RollingBody
from .dynamics.simulate import Trajectory, load_history, simulate
from .dynamics.solvers import StageSolveError
from .laws.thin_layer import LayerContact, TractionField

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
