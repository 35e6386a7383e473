"""The settings swept for a scene, generated from the scene's own data.

A *family* fixes one value on each applicable axis (method, scheme, internal steps per
communication step, ...); its *points* are the rungs of the scene's *ladder*, the
setting refined along the family (``LADDERS``, the first that applies):

- ``grid`` (phase "transient"): the traction field's grid, nx = (scene's nx) x 1/2, 1,
  2 with the scene's ny/nx, at the scene's step h and cells_per_step (the internal
  step is refined with the cell); spacing dx/(2 a1) = 1/nx;
- ``table`` (contact mode, half-space law): the creep-force table's nodes along the
  creepages xi and eta, the node spacing halved from rung to rung ((n - 1)/2 + 1, n,
  2(n - 1) + 1 nodes; the spin axis kept), at the scene's step h; spacing
  ((n_xi - 1)(n_eta - 1))^(-1/2) of the table's uniform parameter;
- ``h`` (every other scene): the communication step, h = (scene step) x 2^k for k in
  LEVELS, so every coarser grid is a subset of the finest one.

Quick mode drops the finest rung (``h``: LEVELS_QUICK); a ladder with
``quick_steps`` also cuts the run to that many communication steps.

An axis says which of its values apply to a scene, how an FMU offering them is
configured, and which start values select one. Adding a setting compared across
families (a contact law, a stepper) is one more entry in ``AXES``: its ``configure``
returns the FMU configuration of the family, its ``start`` the parameters. A setting
whose refinement the report follows (a grid, a table's resolution) is a ``Ladder``:
its ``configure`` returns the FMU of a rung (one per rung when it changes the model).
Either way ``workprecision.REFERENCES`` (by mode, phase and method) or
``fmu.factory.FACTORIES`` (by contact law) needs a reference for it.
"""

from __future__ import annotations

import dataclasses
import itertools
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..dynamics.thin_layer_field import DEFAULT_NX, DEFAULT_NY, MIN_NX, MIN_NY
from ..fmu.config import SCHEMES, ModelConfig
from ..scenario.schema import Case, Scene
from .reference import quasistationary_allowed

FloatArray = NDArray[np.float64]

# Communication steps: the scene's step times 2^k for these k (coarse to fine).
LEVELS = (2, 1, 0, -1, -2)
LEVELS_QUICK = (1, 0)
# Internal stepper steps per communication step: h_max = h / n.
SUBSTEPS = (1, 4, 16)
SUBSTEPS_QUICK = (1, 4)
# Variables every point compares (added to the FMU's outputs where the scene lacks them);
# Ty too where the scene outputs it and the reference has it.
COMPARED = ("Tx", "vx")
# Quick mode of the transient phase: the first communication steps only (1 ms of
# fig12_transient, 1.2 contact lengths: the field forms and the body oscillates on the
# layer, where the errors are largest; measured, docs/performance.md).
QUICK_TRANSIENT_STEPS = 50


@dataclass(frozen=True)
class Axis:
    """One setting swept in the report.

    ``values(scene, quick)``: the values that apply to the scene (empty: not swept);
    ``configure(cfg, values, value)``: the FMU configuration for a family with
    ``value``, given every value swept (the same for all values when one FMU offers
    them all); ``start(value, h)``: FMU start values selecting it at step h.
    """

    name: str
    doc: str
    values: Callable[[Scene, bool], tuple[Any, ...]]
    configure: Callable[[ModelConfig, tuple[Any, ...], Any], ModelConfig]
    start: Callable[[Any, float], dict[str, Any]]
    label: Callable[[Any], str] = str


def _steady_body(scene: Scene) -> bool:
    """Steppers and schemes are the steady phase's (the transient phase has its own)."""
    return scene.config.mode == "body" and scene.config.phase == "steady"


def _methods(scene: Scene, quick: bool) -> tuple[str, ...]:
    if not _steady_body(scene):
        return ()
    grid = fine_grid(scene, LEVELS_QUICK if quick else LEVELS)
    qs = all(quasistationary_allowed(scene, c, grid) is None for c in scene.cases)
    return ("full", "quasistationary") if qs else ("full",)


def _offer(
    field: str, parameter: str
) -> Callable[[ModelConfig, tuple[Any, ...], Any], ModelConfig]:
    """An FMU that offers every swept value of a string parameter (one FMU, fair timing);
    its start value is kept if offered (the parameter exists with two values or more)."""

    def configure(cfg: ModelConfig, values: tuple[Any, ...], _value: Any) -> ModelConfig:
        starts = dict(cfg.starts)
        if len(values) < 2 or starts.get(parameter) not in values:
            starts.pop(parameter, None)
        return dataclasses.replace(cfg, **{field: tuple(values)}, starts=starts)

    return configure


AXES: tuple[Axis, ...] = (
    Axis(
        "method",
        "stepper: the stiff slip equation (Eq. 20) or its quasistationary limit (Eqs. 26, "
        "28-30), the latter where the loads stay admissible (Eq. 27) and no lateral "
        "dynamics enter",
        _methods,
        _offer("methods", "method"),
        lambda v, h: {"method": v},
    ),
    Axis(
        "scheme",
        "integrator scheme (Lobatto IIIC, SDIRK2)",
        lambda s, q: SCHEMES if _steady_body(s) else (),
        _offer("schemes", "scheme"),
        lambda v, h: {"scheme": v},
    ),
    Axis(
        "substeps",
        "internal steps per communication step, h_max = h / n (the transient phase's "
        "internal step is set by cells_per_step and refined with its grid)",
        lambda s, q: (SUBSTEPS_QUICK if q else SUBSTEPS) if _steady_body(s) else (),
        lambda cfg, values, v: cfg,
        lambda v, h: {"h_max": h / v},
        lambda v: f"n={v}",
    ),
)


@dataclass(frozen=True)
class Family:
    """One combination of axis values; its points differ by the communication step."""

    settings: tuple[tuple[str, Any], ...]
    default: str = "law evaluation"

    @property
    def label(self) -> str:
        if not self.settings:
            return self.default
        by_name = {a.name: a for a in AXES}
        return " ".join(by_name[n].label(v) for n, v in self.settings)

    def value(self, name: str, default: Any = None) -> Any:
        return dict(self.settings).get(name, default)


def families(scene: Scene, quick: bool = False) -> tuple[list[Family], ModelConfig]:
    """Every family of the scene and the FMU configuration offering them (one FMU; a
    ladder that changes the model configures one per rung from it, ``Ladder.configure``).
    The FMU outputs the COMPARED variables."""
    swept = [(a, a.values(scene, quick)) for a in AXES]
    swept = [(a, v) for a, v in swept if v]
    cfg = scene.config
    for a, values in swept:
        cfg = a.configure(cfg, values, values[0])
    missing = tuple(v for v in COMPARED if v not in cfg.outputs)
    if missing:
        cfg = dataclasses.replace(cfg, outputs=tuple(cfg.outputs) + missing)
    combos = itertools.product(*[[(a.name, v) for v in values] for a, values in swept])
    default = ladder(scene).family
    return [Family(tuple(c), default) for c in combos], cfg


# ---- ladders: the setting refined along a family ------------------------------------------
@dataclass(frozen=True)
class Rung:
    """One point of a family: its communication step h (s), the ladder's value, the
    spacing the observed order refers to, and a label."""

    level: int
    h: float
    value: Any
    spacing: float
    label: str


@dataclass(frozen=True)
class Ladder:
    """The setting refined along a family.

    ``applies(scene)``; ``values(scene)``: coarse to fine (quick mode drops the finest);
    ``spacing(value)``: the discretisation length the observed order refers to;
    ``configure(cfg, value)``: the FMU configuration of a rung (the same FMU unless the
    value is structural); ``start(value)``: its start values; ``reading``: the inputs
    of the reference, "continuous" (the zero-order hold counts as error) or "held" (as
    the FMU receives them: the ladder refines the model, not the communication);
    ``growth``: the nominal cost ratio of consecutive rungs, ``budget_scale``: the
    factor on the report's budget per point (a short ladder of costly rungs);
    ``quick_steps``: quick mode's communication steps (None: the whole run).
    """

    name: str
    doc: str
    family: str
    applies: Callable[[Scene], bool]
    values: Callable[[Scene], tuple[Any, ...]]
    spacing: Callable[[Any], float]
    label: Callable[[Any], str]
    configure: Callable[[ModelConfig, Any], ModelConfig]
    start: Callable[[Any], dict[str, Any]]
    reading: str
    growth: float = 2.0
    budget_scale: float = 1.0
    quick_steps: int | None = None


def _field_grids(scene: Scene) -> tuple[tuple[int, int], ...]:
    """(nx, ny) at 1/2, 1, 2 times the scene's cells, ny/nx kept (Eqs. 15, 31: the field's
    grid; docs/transient.md)."""
    p = scene.cases[0].parameters
    nx0, ny0 = int(p.get("nx", DEFAULT_NX)), int(p.get("ny", DEFAULT_NY))
    out = []
    for f in (0.5, 1.0, 2.0):
        nx = max(MIN_NX, int(round(nx0 * f)))
        out.append((nx, max(MIN_NY, int(round(nx * ny0 / nx0)))))
    return tuple(dict.fromkeys(out))


def _coarser(n: int) -> int:
    """Nodes of an axis with about twice the spacing (odd, node 0 kept, >= 3)."""
    return max(3, ((n - 1) // 4) * 2 + 1)


def _table_nodes(scene: Scene) -> tuple[tuple[int, int, int], ...]:
    """The table's nodes along xi and eta at twice, once and half the scene's spacing;
    the spin axis as the scene's (the scenes without spin evaluate it at its node 0)."""
    n1, n2, n3 = (int(n) for n in scene.config.law_spec["nodes"])
    return (
        (_coarser(n1), _coarser(n2), n3),
        (n1, n2, n3),
        (2 * (n1 - 1) + 1, 2 * (n2 - 1) + 1, n3),
    )


def _with_nodes(cfg: ModelConfig, nodes: tuple[int, int, int]) -> ModelConfig:
    return dataclasses.replace(cfg, law_spec={**cfg.law_spec, "nodes": list(nodes)})


LADDERS: tuple[Ladder, ...] = (
    Ladder(
        "grid",
        "the traction field's grid nx x ny (cells along 2 a1, strips across 2 a2), "
        "internal steps of cells_per_step cells",
        "field grid",
        lambda s: s.config.mode == "body" and s.config.transient,
        _field_grids,
        lambda v: 1.0 / v[0],
        lambda v: f"{v[0]} x {v[1]}",
        lambda cfg, v: cfg,
        lambda v: {"nx": v[0], "ny": v[1]},
        "held",
        growth=4.0,
        budget_scale=10.0,
        quick_steps=QUICK_TRANSIENT_STEPS,
    ),
    Ladder(
        "table",
        "the creep-force table's nodes (xi x eta x spin)",
        "creep-force table",
        lambda s: s.config.mode == "contact" and s.config.has_table,
        _table_nodes,
        lambda v: 1.0 / math.sqrt((v[0] - 1) * (v[1] - 1)),
        lambda v: "x".join(str(n) for n in v),
        _with_nodes,
        lambda v: {},
        "held",
        growth=1.0,
    ),
)
STEP_LADDER = Ladder(
    "h",
    "the communication step h",
    "law evaluation",
    lambda s: True,
    lambda s: (),
    lambda h: h,
    lambda h: f"{h:.3g}",
    lambda cfg, v: cfg,
    lambda v: {},
    "continuous",
)


def ladder(scene: Scene) -> Ladder:
    """The scene's ladder: the first of LADDERS that applies, else the step's."""
    return next((lad for lad in LADDERS if lad.applies(scene)), STEP_LADDER)


def rungs(scene: Scene, quick: bool = False) -> tuple[Ladder, list[Rung]]:
    """The scene's ladder and its rungs, coarse to fine."""
    lad = ladder(scene)
    if lad is STEP_LADDER:
        out = []
        for k in levels(quick):
            h = step(scene, k)
            out.append(Rung(k, h, h, h, lad.label(h)))
        return lad, out
    values = lad.values(scene)
    if quick:
        values = values[:-1]
    return lad, [Rung(i, scene.step, v, lad.spacing(v), lad.label(v)) for i, v in enumerate(values)]


def for_report(scene: Scene, quick: bool) -> Scene:
    """The scene as the report runs it: in quick mode cut to the ladder's quick_steps."""
    n = ladder(scene).quick_steps
    if not quick or n is None or n >= scene.n_steps:
        return scene
    return dataclasses.replace(scene, stop_time=n * scene.step, field=None)


def levels(quick: bool) -> tuple[int, ...]:
    return LEVELS_QUICK if quick else LEVELS


def step(scene: Scene, level: int) -> float:
    return scene.step * 2.0**level


def fine_grid(scene: Scene, lv: tuple[int, ...]) -> FloatArray:
    """The grid of the finest level: every level's grid is a subset of it."""
    h = step(scene, min(lv))
    n = int(round(scene.stop_time / h))
    return np.arange(n + 1) * h


def point(
    scene: Scene, case: Case, cfg: ModelConfig, family: Family, h: float, extra: dict | None = None
):
    """(scene, case) that the runner simulates for one point of a family: its FMU
    configuration ``cfg``, step h and the start values ``extra`` of its rung."""
    n = int(round(scene.stop_time / h))
    if n < 1 or abs(n * h - scene.stop_time) > 1e-9 * scene.stop_time:
        raise ValueError(f"{scene.name}: stop_time {scene.stop_time} is not a multiple of {h}")
    starts: dict[str, Any] = {}
    by_name = {a.name: a for a in AXES}
    for name, v in family.settings:
        starts.update(by_name[name].start(v, h))
    starts.update(extra or {})
    method = starts.pop("method", case.method)
    scheme = starts.pop("scheme", case.scheme)
    c = dataclasses.replace(
        case, parameters={**case.parameters, **starts}, method=method, scheme=scheme
    )
    return dataclasses.replace(scene, step=h, config=cfg, outputs=tuple(cfg.outputs)), c
