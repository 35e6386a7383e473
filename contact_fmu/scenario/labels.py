"""Axis labels with units: a recorded column, a varied name or a metric, as plots show it.

Units come from the variable table (``fmu.variables``: SI, written "N.m", "kg.m2"); a
dimensionless quantity is labelled "(-)". A metric's unit is its column's divided by
those of its ``per`` names, reduced through the base-unit exponents (``fv.UNITS``).
"""

from __future__ import annotations

from collections.abc import Iterable

from ..fmu import variables as fv
from .schema import Metric

# How a unit of the variable table is written on an axis.
SHOWN = {"1": "-", "N.m": "N m", "kg.m2": "kg m^2"}
# Units of the number fields of a signal piece ("INPUT.piece.field"); None: the input's.
PIECE_UNITS = {
    "time": "s",
    "start": "s",
    "duration": "s",
    "period": "s",
    "phase": "rad",
    "height": None,
    "amplitude": None,
}


def unit(name: str) -> str | None:
    """The SI unit of a recorded column, parameter, input or "INPUT.piece.field" as
    written in the variable table ("1": dimensionless); None when it has none (an integer
    code such as regime) or is unknown."""
    if name == "time":
        return "s"
    parts = name.split(".")
    if len(parts) == 3 and parts[0] in fv.BY_NAME and parts[1] != "constant":
        own = PIECE_UNITS.get(parts[2])
        return own if own is not None else fv.BY_NAME[parts[0]].unit
    var = fv.BY_NAME.get(name)
    return var.unit if var is not None else None


def _shown(u: str) -> str:
    return SHOWN.get(u, u)


def axis_label(name: str) -> str:
    """``name (unit)``; regime with its codes."""
    if name == "regime":
        return "regime (0: partial slip, 1: gross sliding)"
    u = unit(name)
    return f"{name} ({_shown(u)})" if u is not None else name


def axis_labels(names: Iterable[str]) -> str:
    """Several names on one axis: "Tx, Ty (N)" when they share a unit, else each with
    its own."""
    names = list(names)
    units = {unit(n) for n in names}
    if len(units) == 1 and None not in units:
        return f"{', '.join(names)} ({_shown(units.pop())})"
    return ", ".join(axis_label(n) for n in names)


def _exponents(u: str) -> dict[str, int] | None:
    return dict(fv.UNITS[u]) if u in fv.UNITS else None


def metric_unit(m: Metric) -> str | None:
    """The unit of a metric's values: its column's over those of ``per`` (a settle time
    in s; any_above/any_below 0 or 1)."""
    if m.reduce == "settle_time":
        return "s"
    if m.reduce in ("any_above", "any_below"):
        return "0/1"
    base = _exponents(unit(m.of) or "")
    if base is None:
        return None
    for p in m.per:
        e = _exponents(unit(p) or "")
        if e is None:
            return None
        for k, v in e.items():
            base[k] = base.get(k, 0) - v
    base = {k: v for k, v in base.items() if v}
    for name, e in fv.UNITS.items():
        if e == base:
            return name
    return None


def metric_label(m: Metric) -> str:
    """A metric with what it reduces and its unit: "peak: max_abs of Tx/(mu P) (-)"."""
    per = " ".join(m.per)
    of = m.of + (f"/({per})" if len(m.per) > 1 else f"/{per}" if m.per else "")
    u = metric_unit(m)
    return f"{m.name}: {m.reduce} of {of}" + (f" ({_shown(u)})" if u is not None else "")
