"""Exact half-space theory: Hertz, numerical normal contact, steady rolling with
Boussinesq-Cerruti influence and layers, Kalker's FASTSIM beside it, line contact,
transient rolling, the creep-force table and its spec, and the mapping to CONTACT's
conventions. Every public class and function is exported here. See docs/halfspace.md."""

import importlib
from typing import Any

from . import conventions
from .contact import CreepCoefficients, HalfSpaceContact
from .fastsim import Fastsim, kalker_coefficients
from .hertz import CombinedElastic, Hertz, Material, UnitWarning, relative_curvatures
from .influence import Grid
from .line import LineContact
from .normal import NormalSolution, solve_normal
from .plotting import plot_creep_curves
from .railway import STEEL, wheel_on_rail
from .rolling import Continuation, RollingPatch, RollingSolution, ellipse_patch, solve_rolling
from .spec import Solid, TableLaw, TableSpec, build_file
from .table import CreepTable, TableData, build_table

# The transient classes load on first use: transient.py imports the body dynamics and
# the integrator, which an FMU of the half-space law (it vendors this package's
# __init__ and what it imports, fmu_build/sources.py) does not carry.
_LAZY = {
    name: "transient"
    for name in (
        "CoulombSolution",
        "HalfSpaceField",
        "StepGeometry",
        "StepPatch",
        "StepGeometry",
        "StepPatch",
        "StepResult",
        "TransientHalfSpaceBody",
    )
}


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        return getattr(importlib.import_module(f".{_LAZY[name]}", __name__), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = [
    "STEEL",
    "CombinedElastic",
    "Continuation",
    "CreepCoefficients",
    "CoulombSolution",
    "CreepTable",
    "Fastsim",
    "Grid",
    "HalfSpaceContact",
    "HalfSpaceField",
    "Hertz",
    "LineContact",
    "Material",
    "NormalSolution",
    "RollingPatch",
    "RollingSolution",
    "Solid",
    "StepGeometry",
    "StepPatch",
    "StepResult",
    "TableData",
    "TableLaw",
    "TableSpec",
    "TransientHalfSpaceBody",
    "UnitWarning",
    "build_file",
    "build_table",
    "conventions",
    "ellipse_patch",
    "kalker_coefficients",
    "plot_creep_curves",
    "relative_curvatures",
    "solve_normal",
    "solve_rolling",
    "wheel_on_rail",
]
