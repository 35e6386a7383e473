"""Rolling/sliding contact of an elastic body on an elastic substrate (Spector & Batra 1995).

The package's layout (docs/develop/architecture.md): ``laws/`` (the contact laws),
``dynamics/`` (the rolling body and its steppers), ``halfspace/`` (the exact half-space
theory), ``native/`` (the C core), ``fmu/`` (what an FMU runs), and the applications
``scenario/``, ``study/``, ``report/``, ``figures/``, ``cli.py``.
"""

import sys as _sys

from . import _moved
from ._validate import InputError
from .dynamics.body import Body, Lateral, Loads, load_utilisation
from .dynamics.integrator import RollingBody
from .dynamics.simulate import Trajectory, load_history, simulate
from .dynamics.solvers import StageSolveError
from .dynamics.thin_layer_field import TransientRollingBody
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
    "TransientRollingBody",
    "load_history",
    "load_utilisation",
    "simulate",
]


# the flat layout's module paths (contact_fmu.layer, ...) for one release: _moved.py
_moved.install()
_sys.modules[__name__].__class__ = _moved.Package


def __getattr__(name: str):  # noqa: ANN202
    """``contact_fmu.layer`` and the other old module paths as attributes (deprecated)."""
    old = f"{__name__}.{name}"
    if old in _moved.MOVED:
        return _moved.load(old)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
