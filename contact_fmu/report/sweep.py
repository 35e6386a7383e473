"""The settings swept for a scene, generated from the scene's own data.

A *family* fixes one value on each applicable axis (method, scheme, internal steps per
communication step, ...); a *point* of a family is one communication step h. Levels
are h = (scene step) x 2^k, so every coarser grid is a subset of the finest one.

An axis says which of its values apply to a scene, how an FMU offering them is
configured, and which start values select one. Adding a setting (the contact law
``contact_law = "halfspace"``, a grid size for field-based laws, ``phase =
"transient"``) is one more entry in ``AXES``: its ``configure`` returns the FMU
configuration of the family (one FMU per value when the value changes the model), its
``start`` the parameters, and ``workprecision.REFERENCES`` (by mode, phase and method)
or ``reference.LAWS`` (by contact law) needs a reference for it.
"""

from __future__ import annotations

import dataclasses
import itertools
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

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
        "internal steps per communication step, h_max = h / n",
        lambda s, q: (SUBSTEPS_QUICK if q else SUBSTEPS) if s.config.mode == "body" else (),
        lambda cfg, values, v: cfg,
        lambda v, h: {"h_max": h / v},
        lambda v: f"n={v}",
    ),
)


@dataclass(frozen=True)
class Family:
    """One combination of axis values; its points differ by the communication step."""

    settings: tuple[tuple[str, Any], ...]

    @property
    def label(self) -> str:
        if not self.settings:
            return "law evaluation"
        by_name = {a.name: a for a in AXES}
        return " ".join(by_name[n].label(v) for n, v in self.settings)

    def value(self, name: str, default: Any = None) -> Any:
        return dict(self.settings).get(name, default)


def families(scene: Scene, quick: bool = False) -> tuple[list[Family], ModelConfig]:
    """Every family of the scene and the FMU configuration offering them (one FMU)."""
    swept = [(a, a.values(scene, quick)) for a in AXES]
    swept = [(a, v) for a, v in swept if v]
    cfg = scene.config
    for a, values in swept:
        cfg = a.configure(cfg, values, values[0])
    combos = itertools.product(*[[(a.name, v) for v in values] for a, values in swept])
    return [Family(tuple(c)) for c in combos], cfg


def levels(quick: bool) -> tuple[int, ...]:
    return LEVELS_QUICK if quick else LEVELS


def step(scene: Scene, level: int) -> float:
    return scene.step * 2.0**level


def fine_grid(scene: Scene, lv: tuple[int, ...]) -> FloatArray:
    """The grid of the finest level: every level's grid is a subset of it."""
    h = step(scene, min(lv))
    n = int(round(scene.stop_time / h))
    return np.arange(n + 1) * h


def point(scene: Scene, case: Case, cfg: ModelConfig, family: Family, h: float):
    """(scene, case) that the runner simulates for one point of a family."""
    n = int(round(scene.stop_time / h))
    if n < 1 or abs(n * h - scene.stop_time) > 1e-9 * scene.stop_time:
        raise ValueError(f"{scene.name}: stop_time {scene.stop_time} is not a multiple of {h}")
    starts: dict[str, Any] = {}
    by_name = {a.name: a for a in AXES}
    for name, v in family.settings:
        starts.update(by_name[name].start(v, h))
    method = starts.pop("method", case.method)
    scheme = starts.pop("scheme", case.scheme)
    c = dataclasses.replace(
        case, parameters={**case.parameters, **starts}, method=method, scheme=scheme
    )
    return dataclasses.replace(scene, step=h, config=cfg), c
