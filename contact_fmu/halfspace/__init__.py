"""Exact half-space theory (issue 4): Hertz, numerical normal contact, steady rolling
with Boussinesq-Cerruti influence and layers, and the creep-force table. See
docs/halfspace.md."""

from .contact import HalfSpaceContact
from .hertz import CombinedElastic, Hertz, Material, relative_curvatures
from .normal import solve_normal
from .railway import wheel_on_rail
from .rolling import RollingPatch, RollingSolution, ellipse_patch, solve_rolling
from .table import CreepTable, TableData, build_table

__all__ = [
    "CombinedElastic",
    "CreepTable",
    "HalfSpaceContact",
    "Hertz",
    "Material",
    "RollingPatch",
    "RollingSolution",
    "TableData",
    "build_table",
    "ellipse_patch",
    "relative_curvatures",
    "solve_normal",
    "solve_rolling",
    "wheel_on_rail",
]
