"""The half-space law of an FMU as plain data: contact, creep-force table, run-time law.

A scene that chooses ``contact_law = "halfspace"`` declares the contact (materials and
radii of body and substrate, optional layer compliances kb, ks), the friction
coefficient the table's range refers to, and the table's range and resolution
(``[halfspace]`` of the scene file; contact_fmu/scenario/schema.py). ``TableSpec`` is
that declaration, checked, with

* ``contact()``: the HalfSpaceContact it describes (direct solves: the references of
  the scenes use it);
* ``build()``: the creep-force table (``table.build_table``), tagged with the spec's
  content key so that a table and a spec can be matched later;
* ``load_law(path, P, mu)``: the run-time law read from a table file, checked against
  the spec (``TableLaw``).

Exact similarities used at run time (docs/halfspace.md, "The half-space law in the
FMU"): the discrete steady-rolling problem is homogeneous of degree one in (traction,
creepages, mu p), so the normalised table does not depend on mu, with or without
layers: the FMU's mu stays a free parameter. It does not depend on P either when there
are no layers (Kalker's similarity); with layers (kb + ks > 0) it does, and TableLaw
refuses a load outside the table's load nodes instead of extrapolating.

``python -m contact_fmu.halfspace build-table SPEC.json OUT.npz`` builds a table in a
process of its own (the FMU build uses it, with single-threaded BLAS).
"""

from __future__ import annotations

import hashlib
import json
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, replace
from functools import cached_property
from pathlib import Path
from typing import Any

import numpy as np

from .._validate import InputError, nonnegative, positive
from .contact import HalfSpaceContact
from .hertz import Material, relative_curvatures
from .table import CreepTable, TableData, build_table

SPEC_VERSION = 1
# Keys of the declaration (``[halfspace]`` of a scene) and of its two material tables.
KEYS = {
    "body",
    "substrate",
    "kb",
    "ks",
    "mu",
    "grid",
    "loads",
    "xi_max",
    "eta_max",
    "phi_max",
    "nodes",
    "stretch",
}
SOLID_KEYS = {"Rx", "Ry", "E", "nu"}
# Relative margin of the load range of a layered table (rounding of the load nodes).
LOAD_RTOL = 1e-12


def _radius(where: str, value: Any) -> float:
    """A radius of curvature (m): > 0, or inf (written "inf" in plain data) for flat."""
    if isinstance(value, str) and value.strip().lower() in ("inf", "+inf", "infinity"):
        return math.inf
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise InputError(where, value, 'a radius in m (> 0), or inf ("inf") for a flat direction')
    if not (value > 0.0):  # also NaN
        raise InputError(where, value, "> 0 (or inf for a flat direction)")
    return float(value)


def _number(where: str, value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise InputError(where, value, "a number")
    return float(value)


def _plain(x: float) -> float | str:
    """A float as plain data that every writer keeps (inf as the string "inf")."""
    return "inf" if math.isinf(x) else x


@dataclass(frozen=True)
class Solid:
    """One body at the contact: principal radii Rx (along the rolling direction), Ry (m,
    inf for a flat direction) and its material."""

    Rx: float
    Ry: float
    material: Material

    @classmethod
    def from_dict(cls, where: str, d: Any) -> Solid:
        if not isinstance(d, Mapping):
            raise InputError(where, d, f"a table with the keys {sorted(SOLID_KEYS)}")
        extra, missing = set(d) - SOLID_KEYS, SOLID_KEYS - set(d)
        if extra or missing:
            raise InputError(
                where,
                dict(d),
                f"the keys {sorted(SOLID_KEYS)} (unknown {sorted(extra)}, "
                f"missing {sorted(missing)})",
            )
        Rx, Ry = _radius(f"{where}.Rx", d["Rx"]), _radius(f"{where}.Ry", d["Ry"])
        E = positive(f"{where}.E", _number(f"{where}.E", d["E"]))
        nu = _number(f"{where}.nu", d["nu"])
        if not -1.0 < nu <= 0.5:
            raise InputError(f"{where}.nu", nu, "in (-1, 0.5]")
        return cls(Rx, Ry, Material(E, nu))

    def to_dict(self) -> dict[str, Any]:
        return {
            "Rx": _plain(self.Rx),
            "Ry": _plain(self.Ry),
            "E": self.material.E,
            "nu": self.material.nu,
        }


@dataclass(frozen=True)
class TableSpec:
    """The half-space contact of an FMU and the range and resolution of its table.

    body, substrate: Solid (the body rolls along x on the substrate); kb, ks: tangential
    layer compliances (m/Pa) of Eqs. (6)-(7); mu: the friction coefficient the creepage
    range refers to (the FMU's mu may differ, see the module docstring); grid: solver
    elements per direction; loads: the table's load nodes (N; at least two with layers);
    xi_max, eta_max (-), phi_max (1/m): half-widths of the table's creepage box at the
    smallest load and at mu; nodes: odd node counts per axis (xi, eta, phi); stretch: the
    node distribution (``table.build_table``).
    """

    body: Solid
    substrate: Solid
    mu: float
    loads: tuple[float, ...]
    xi_max: float
    eta_max: float
    phi_max: float
    nodes: tuple[int, int, int]
    grid: int
    kb: float = 0.0
    ks: float = 0.0
    stretch: float = 2.0

    @classmethod
    def from_dict(cls, d: Any, where: str = "halfspace") -> TableSpec:
        """The spec from plain data (a scene's ``[halfspace]`` table); InputError naming
        the key ``where.key`` for anything missing or out of range."""
        if not isinstance(d, Mapping):
            raise InputError(where, d, f"a table with the keys {sorted(KEYS)}")
        extra = set(d) - KEYS
        if extra:
            raise InputError(where, sorted(extra), f"known keys: {sorted(KEYS)}")
        required = KEYS - {"kb", "ks", "stretch"}
        missing = required - set(d)
        if missing:
            raise InputError(where, sorted(missing), "given (required keys of the table)")
        body = Solid.from_dict(f"{where}.body", d["body"])
        substrate = Solid.from_dict(f"{where}.substrate", d["substrate"])
        try:
            relative_curvatures(body.Rx, body.Ry, substrate.Rx, substrate.Ry)
        except InputError as e:
            radii = (body.Rx, body.Ry, substrate.Rx, substrate.Ry)
            msg = f"radii of a closed contact ellipse ({e})"
            raise InputError(f"{where}.body/substrate", radii, msg) from e
        kb = nonnegative(f"{where}.kb", _number(f"{where}.kb", d.get("kb", 0.0)))
        ks = nonnegative(f"{where}.ks", _number(f"{where}.ks", d.get("ks", 0.0)))
        mu = positive(f"{where}.mu", _number(f"{where}.mu", d["mu"]))
        loads = d["loads"]
        if not isinstance(loads, list | tuple) or not loads:
            raise InputError(f"{where}.loads", loads, "a non-empty list of loads in N")
        loads = tuple(
            sorted(positive(f"{where}.loads", _number(f"{where}.loads", x)) for x in loads)
        )
        if len(set(loads)) != len(loads):
            raise InputError(f"{where}.loads", list(loads), "distinct")
        if kb + ks > 0.0 and len(loads) < 2:
            raise InputError(
                f"{where}.loads",
                list(loads),
                "at least two load nodes when kb + ks > 0 (layers break the load similarity)",
            )
        ranges = [
            positive(f"{where}.{k}", _number(f"{where}.{k}", d[k]))
            for k in ("xi_max", "eta_max", "phi_max")
        ]
        nodes = d["nodes"]
        if (
            not isinstance(nodes, list | tuple)
            or len(nodes) != 3
            or any(
                isinstance(n, bool) or not isinstance(n, int) or n < 3 or n % 2 == 0 for n in nodes
            )
        ):
            raise InputError(f"{where}.nodes", nodes, "three odd integers >= 3 (xi, eta, phi)")
        grid = d["grid"]
        if isinstance(grid, bool) or not isinstance(grid, int) or grid < 8:
            raise InputError(f"{where}.grid", grid, "an integer >= 8 (elements per direction)")
        stretch = nonnegative(
            f"{where}.stretch", _number(f"{where}.stretch", d.get("stretch", 2.0))
        )
        return cls(body, substrate, mu, loads, *ranges, tuple(nodes), grid, kb, ks, stretch)

    def to_dict(self) -> dict[str, Any]:
        """Plain data (JSON and Python literals: inf is written "inf")."""
        return {
            "body": self.body.to_dict(),
            "substrate": self.substrate.to_dict(),
            "kb": self.kb,
            "ks": self.ks,
            "mu": self.mu,
            "grid": self.grid,
            "loads": list(self.loads),
            "xi_max": self.xi_max,
            "eta_max": self.eta_max,
            "phi_max": self.phi_max,
            "nodes": list(self.nodes),
            "stretch": self.stretch,
        }

    @cached_property
    def key(self) -> str:
        """SHA-256 of the declaration (hex): tags the table built from it."""
        text = json.dumps({"version": SPEC_VERSION, **self.to_dict()}, sort_keys=True)
        return hashlib.sha256(text.encode()).hexdigest()

    @property
    def Rx(self) -> float:
        """The body's radius along the rolling direction (m): its rolling radius."""
        return self.body.Rx

    def contact(self, P: float | None = None, mu: float | None = None) -> HalfSpaceContact:
        """The contact by direct solves at load P (N; default the first load node) and
        friction mu (default the spec's), as the table is built: Kalker's quasi-identity
        (the pressure coupling B(p) off, exact for identical materials)."""
        return HalfSpaceContact(
            P=self.loads[0] if P is None else P,
            Rx=self.body.Rx,
            Ry=self.body.Ry,
            body=self.body.material,
            substrate=self.substrate.material,
            mu=self.mu if mu is None else mu,
            Rsx=self.substrate.Rx,
            Rsy=self.substrate.Ry,
            kb=self.kb,
            ks=self.ks,
            n=self.grid,
            coupling=False,
        )

    def build(
        self,
        progress: Callable[[int, int], None] | None = None,
        map_tasks: Callable[[Callable, list], list] | None = None,
    ) -> CreepTable:
        """The creep-force table (direct solves at its nodes; docs/halfspace.md gives the
        cost), its meta data tagged with ``key``; ``map_tasks``: see ``build_table``."""
        table = build_table(
            self.contact(),
            loads=self.loads,
            xi_max=self.xi_max,
            eta_max=self.eta_max,
            phi_max=self.phi_max,
            nodes=self.nodes,
            stretch=self.stretch,
            progress=progress,
            map_tasks=map_tasks,
        )
        meta = {**json.loads(table.data.meta), "spec": self.key}
        return CreepTable(replace(table.data, meta=json.dumps(meta)), table.P)

    def load_law(self, path: str | Path, P: float | None = None, mu: float | None = None):
        """The run-time law from the table file ``path`` at load P (N) and friction mu.

        InputError when the file is missing or was built from another declaration."""
        path = Path(path)
        if not path.is_file():
            raise InputError(
                "creep-force table",
                str(path),
                "an existing file (the FMU carries its table in its resources)",
            )
        data = TableData.load(path)
        tag = json.loads(data.meta).get("spec")
        if tag != self.key:
            raise InputError(
                "creep-force table",
                str(path),
                f"built for this FMU's contact (spec {self.key[:12]}), not for {str(tag)[:12]}",
            )
        return self.law(data, P, mu)

    def law(self, data: TableData, P: float | None = None, mu: float | None = None) -> TableLaw:
        """The run-time law of the table ``data`` at load P (N; default its first load
        node) and friction mu (default the table's)."""
        return TableLaw(data, float(data.P[0]) if P is None else float(P), friction=mu)


@dataclass(frozen=True)
class TableLaw(CreepTable):
    """CreepTable with the run-time rules of an FMU.

    ``friction``: the friction coefficient (-), None for the table's: exact, since the
    normalised table does not depend on mu (module docstring). With layers
    (kb + ks > 0) a load outside the table's load nodes is refused (InputError naming
    P) rather than extrapolated by similarity; without layers every P > 0 is exact.
    """

    friction: float | None = None

    def __post_init__(self) -> None:
        if self.friction is not None:
            positive("mu", self.friction)
        nonnegative("P", self.P)  # P = 0: lift-off, no contact (any table)
        lo, hi = self.load_range
        if self.P != 0.0 and not (lo * (1.0 - LOAD_RTOL) <= self.P <= hi * (1.0 + LOAD_RTOL)):
            raise InputError(
                "P",
                self.P,
                f"within the load range [{lo:g}, {hi:g}] N of the FMU's "
                "creep-force table (its layers, kb + ks > 0, break the load similarity)",
            )
        super().__post_init__()

    @property
    def mu(self) -> float:  # type: ignore[override]
        return self.data.mu if self.friction is None else self.friction

    @property
    def load_range(self) -> tuple[float, float]:
        """Admissible loads (N): the load nodes' span with layers, (0, inf) without."""
        if self.data.k > 0.0:
            return float(np.min(self.data.P)), float(np.max(self.data.P))
        return 0.0, math.inf

    def with_mu(self, mu: float) -> TableLaw:
        return self if mu == self.mu else replace(self, friction=positive("mu", mu))

    def __deepcopy__(self, memo: dict) -> TableLaw:
        """Immutable: a copy (e.g. in an FMU state) shares the table instead of copying
        its patches (megabytes)."""
        return self


def build_file(spec: Mapping[str, Any], out: str | Path) -> Path:
    """Build the table of the plain-data ``spec`` and write it to ``out`` (.npz)."""
    return TableSpec.from_dict(spec).build().save(out)
