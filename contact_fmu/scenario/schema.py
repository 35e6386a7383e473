"""Scene files (scenarios/*.toml): loading and checking, read with tomllib.

A scene is data: the model structure, SI parameters, input signals, cases, the time
grid, the outputs to record, reference results with tolerances and a plot layout.

    name = "fig13"                      # identifier; names the FMU and the output files
    title = "..."
    [model]
    mode = "body"                       # body | contact
    contact_law = "layer"               # layer | halfspace (needs [halfspace])
    phase = "steady"                    # steady | transient (body mode, layer law: the
                                        # traction field as state; no method/scheme)
    method = "full"                     # full | quasistationary (a case may override)
    scheme = "lobatto3c"                # lobatto3c | sdirk2 (a case may override)
    vy = 0.0                            # Vy/Vx held at this value, or "eq10"
    spin = 0.0                          # Omega_z/Vx held (1/m), or "eq11"
    [run]
    stop_time = 0.056                   # s
    step = 1.75e-4                      # communication step (s)
    outputs = ["Tx", "vx"]
    field = { times = [1e-3], file = "f.csv" }  # phase = "transient": the field written
                                        # at these times, one file per case, under
                                        # out/scenes/<name>/fields/ (fmu/body_transient.py)
    [halfspace]                         # contact_law = "halfspace": materials, radii,
                                        # layers and the creep-force table's range and
                                        # resolution (contact_fmu.halfspace.spec.TableSpec)
    [parameters]                        # FMU parameters, SI (see contact_fmu.fmu.variables)
    [inputs]                            # FMU inputs as signals (see signals.py)
    [[cases]]                           # name, and overrides: parameters, inputs, method,
                                        # scheme
    [[reference]]                       # file (CSV next to the scene), source, tolerance,
                                        # cases, and options of the producing path
    [plot]                              # x, panels, scale

The runner uses only what is here; how a reference was produced is recorded in its
``source`` and options, and ``references.py`` reproduces it.
"""

from __future__ import annotations

import math
import re
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .._validate import InputError
from ..fmu import variables as fv
from ..fmu.config import ModelConfig
from .signals import Signal, SignalError, parse

TOP_KEYS = {
    "name",
    "title",
    "description",
    "model",
    "run",
    "parameters",
    "inputs",
    "cases",
    "reference",
    "plot",
    "halfspace",
}
MODEL_KEYS = {"mode", "contact_law", "phase", "method", "scheme", "vy", "spin"}
RUN_KEYS = {"stop_time", "step", "outputs", "field"}
FIELD_KEYS = {"times", "file"}
CASE_KEYS = {"name", "parameters", "inputs", "method", "scheme"}
REFERENCE_KEYS = {"file", "source", "note", "tolerance", "cases", "options"}
PLOT_KEYS = {"x", "panels", "scale"}
# The grid must hold a whole number of steps to this relative precision.
GRID_RTOL = 1e-9


class ScenarioError(ValueError):
    """A scene file is malformed; the message names the file and the key."""


@dataclass(frozen=True)
class Case:
    """One run of a scene: its full parameter set, input signals, stepper and scheme."""

    name: str
    parameters: dict[str, Any]
    inputs: dict[str, Signal]
    method: str
    scheme: str = "lobatto3c"


@dataclass(frozen=True)
class Reference:
    """A stored reference: CSV ``file`` (columns case, time, variables), the ``source``
    that produced it, absolute ``tolerance`` per variable (SI), the ``cases`` it covers
    and the ``options`` of the producing path."""

    file: Path
    source: str
    tolerance: dict[str, float]
    cases: tuple[str, ...]
    options: dict[str, Any]
    note: str = ""


@dataclass(frozen=True)
class FieldRequest:
    """[run].field: the traction field written at ``times`` (s) to ``file`` (a file name;
    the runner puts one per case under the run's output folder)."""

    times: tuple[float, ...]
    file: str

    def path(self, folder: Path, case: str) -> Path:
        """The file of one case under ``folder``: <stem>_<case as an identifier><suffix>."""
        stem, suffix = Path(self.file).stem, Path(self.file).suffix
        slug = re.sub(r"[^A-Za-z0-9]+", "_", case).strip("_") or "case"
        return Path(folder) / f"{stem}_{slug}{suffix}"


@dataclass(frozen=True)
class Plot:
    x: str = "time"
    panels: tuple[tuple[str, ...], ...] = ()
    scale: dict[str, tuple[float, str]] = field(default_factory=dict)


@dataclass(frozen=True)
class Scene:
    path: Path
    name: str
    title: str
    description: str
    model: dict[str, Any]
    stop_time: float
    step: float
    outputs: tuple[str, ...]
    cases: tuple[Case, ...]
    references: tuple[Reference, ...]
    plot: Plot
    config: ModelConfig
    field: FieldRequest | None = None

    @property
    def n_steps(self) -> int:
        return int(round(self.stop_time / self.step))

    @property
    def grid(self) -> NDArray[np.float64]:
        """Communication points 0, h, 2h, ... (s), as a master computes them."""
        return np.arange(self.n_steps + 1) * self.step

    @property
    def inputs(self) -> tuple[str, ...]:
        return self.config.inputs

    def case(self, name: str) -> Case:
        for c in self.cases:
            if c.name == name:
                return c
        raise KeyError(name)


def _err(path: Path, where: str, msg: str) -> ScenarioError:
    return ScenarioError(f"{path}: {where}: {msg}")


def _table(path: Path, where: str, d: Any, allowed: set[str]) -> dict[str, Any]:
    if not isinstance(d, dict):
        raise _err(path, where, f"expected a table, got {d!r}")
    extra = set(d) - allowed
    if extra:
        raise _err(path, where, f"unknown key(s) {sorted(extra)}; allowed {sorted(allowed)}")
    return d


def _positive(path: Path, where: str, v: Any) -> float:
    if isinstance(v, bool) or not isinstance(v, int | float) or not (math.isfinite(v) and v > 0):
        raise _err(path, where, f"{v!r} must be a finite number > 0")
    return float(v)


def _lateral(path: Path, key: str, v: Any, eq: str) -> tuple[str, float | None]:
    if v == eq:
        return eq, None
    if isinstance(v, bool) or not isinstance(v, int | float) or not math.isfinite(v):
        raise _err(path, f"model.{key}", f"{v!r} must be a number (held ratio) or {eq!r}")
    return ("zero", None) if v == 0 else ("ratio", float(v))


def _halfspace(path: Path, d: Any) -> dict[str, Any]:
    """[halfspace] as plain data; its keys and values are checked by the model config
    (contact_fmu.halfspace.spec.TableSpec), whose errors name them."""
    if not isinstance(d, dict):
        raise _err(path, "halfspace", f"expected a table, got {d!r}")
    return dict(d)


def _field(path: Path, d: Any, config: ModelConfig, stop: float) -> FieldRequest | None:
    """[run].field: times within the run, a plain file name; phase "transient" only."""
    if d is None:
        return None
    d = _table(path, "run.field", d, FIELD_KEYS)
    if not config.transient:
        raise _err(path, "run.field", 'needs phase = "transient" (the field is its state)')
    times = d.get("times")
    if not (isinstance(times, list) and times):
        raise _err(path, "run.field.times", f"{times!r} must be a non-empty list of times (s)")
    for t in times:
        if isinstance(t, bool) or not isinstance(t, int | float) or not 0.0 <= t <= stop:
            raise _err(path, "run.field.times", f"{t!r} must be a time in [0, stop_time]")
    name = d.get("file")
    if not isinstance(name, str) or not name or Path(name).name != name:
        raise _err(path, "run.field.file", f"{name!r} must be a file name (no folders)")
    return FieldRequest(tuple(sorted(float(t) for t in times)), name)


def load(path: str | Path) -> Scene:
    """Read and check a scene file."""
    path = Path(path)
    try:
        with path.open("rb") as f:
            raw = tomllib.load(f)
    except OSError as e:
        raise ScenarioError(f"{path}: cannot read: {e}") from e
    except tomllib.TOMLDecodeError as e:
        raise ScenarioError(f"{path}: not valid TOML: {e}") from e
    try:
        return _scene(path, raw)
    except (InputError, SignalError) as e:
        raise ScenarioError(f"{path}: {e}") from e


def _scene(path: Path, raw: dict[str, Any]) -> Scene:
    _table(path, "top level", raw, TOP_KEYS)
    name = raw.get("name")
    if not isinstance(name, str) or not name.isidentifier():
        raise _err(path, "name", f"{name!r} must be an identifier (letters, digits, _)")
    model = _table(path, "model", raw.get("model", {}), MODEL_KEYS)
    run = _table(path, "run", raw.get("run"), RUN_KEYS)
    stop = _positive(path, "run.stop_time", run.get("stop_time"))
    step = _positive(path, "run.step", run.get("step"))
    n = round(stop / step)
    if n < 1 or abs(n * step - stop) > GRID_RTOL * stop:
        raise _err(path, "run", f"stop_time/step = {stop / step!r} must be a whole number >= 1")
    outputs = run.get("outputs")
    if not (isinstance(outputs, list) and outputs and all(isinstance(o, str) for o in outputs)):
        raise _err(path, "run.outputs", f"{outputs!r} must be a non-empty list of names")

    vy, vy_ratio = _lateral(path, "vy", model.get("vy", 0.0), "eq10")
    spin, spin_ratio = _lateral(path, "spin", model.get("spin", 0.0), "eq11")
    params = dict(_table(path, "parameters", raw.get("parameters", {}), set(fv.BY_NAME)))
    if vy_ratio is not None:
        params.setdefault("vy_ratio", vy_ratio)
    if spin_ratio is not None:
        params.setdefault("spin_ratio", spin_ratio)
    inputs_raw = _table(path, "inputs", raw.get("inputs", {}), set(fv.BY_NAME))
    base_inputs = {k: parse(k, v) for k, v in inputs_raw.items()}
    default_method = model.get("method", "full")
    default_scheme = model.get("scheme", "lobatto3c")

    cases_raw = raw.get("cases", [{"name": "default"}])
    if not isinstance(cases_raw, list) or not cases_raw:
        raise _err(path, "cases", "must be a non-empty array of tables ([[cases]])")
    cases = []
    for i, c in enumerate(cases_raw):
        c = _table(path, f"cases[{i}]", c, CASE_KEYS)
        cname = c.get("name")
        if not isinstance(cname, str) or not cname:
            raise _err(path, f"cases[{i}].name", f"{cname!r} must be a non-empty string")
        cp = _table(path, f"cases[{i}].parameters", c.get("parameters", {}), set(fv.BY_NAME))
        ci = _table(path, f"cases[{i}].inputs", c.get("inputs", {}), set(fv.BY_NAME))
        signals = dict(base_inputs)
        signals.update({k: parse(k, v) for k, v in ci.items()})
        method = c.get("method", default_method)
        scheme = c.get("scheme", default_scheme)
        cases.append(Case(cname, {**params, **cp}, signals, method, scheme))
    if len({c.name for c in cases}) != len(cases):
        raise _err(path, "cases", "case names must be unique")

    methods = tuple(dict.fromkeys(c.method for c in cases))
    schemes = tuple(dict.fromkeys(c.scheme for c in cases))
    input_names = tuple(v.name for v in fv.VARIABLES if any(v.name in c.inputs for c in cases))
    for c in cases:
        missing = set(input_names) - set(c.inputs)
        if missing:
            raise _err(path, f"cases.{c.name}", f"no signal for input(s) {sorted(missing)}")
    starts = dict(params)
    starts.update({k: float(s(np.zeros(1))[0]) for k, s in base_inputs.items()})
    if len(methods) > 1:
        starts["method"] = methods[0]
    if len(schemes) > 1:
        starts["scheme"] = schemes[0]
    config = ModelConfig(
        name=name,
        mode=model.get("mode", "body"),
        inputs=input_names,
        outputs=tuple(outputs),
        contact_law=model.get("contact_law", "layer"),
        phase=model.get("phase", "steady"),
        methods=methods,
        schemes=schemes,
        vy=vy,
        spin=spin,
        starts=starts,
        experiment=(0.0, stop, step),
        description=str(raw.get("title", name)),
        law_spec=_halfspace(path, raw.get("halfspace", {})),
    )
    fmu_params = {v.name for v in config.variables if v.causality[config.mode] == fv.PARAMETER}
    for c in cases:
        for k, v in c.parameters.items():
            if k not in fmu_params:
                raise _err(
                    path,
                    f"cases.{c.name}.parameters.{k}",
                    f"not a parameter of this model ({sorted(fmu_params)})",
                )
            problem = fv.BY_NAME[k].check(v)
            if problem is not None:
                raise _err(path, f"cases.{c.name}.parameters.{k}", f"{v!r} must be {problem}")

    recorded = set(outputs) | set(input_names) | {"time"}
    refs = []
    for i, r in enumerate(raw.get("reference", [])):
        r = _table(path, f"reference[{i}]", r, REFERENCE_KEYS)
        if not isinstance(r.get("file"), str) or not isinstance(r.get("source"), str):
            raise _err(path, f"reference[{i}]", "needs 'file' and 'source' (strings)")
        tol = _table(path, f"reference[{i}].tolerance", r.get("tolerance"), recorded)
        tol = {k: _positive(path, f"reference[{i}].tolerance.{k}", v) for k, v in tol.items()}
        rcases = tuple(r.get("cases", [c.name for c in cases]))
        unknown = set(rcases) - {c.name for c in cases}
        if unknown:
            raise _err(path, f"reference[{i}].cases", f"unknown case(s) {sorted(unknown)}")
        refs.append(
            Reference(
                path.parent / r["file"],
                r["source"],
                tol,
                rcases,
                dict(r.get("options", {})),
                str(r.get("note", "")),
            )
        )

    field_req = _field(path, run.get("field"), config, stop)
    p = _table(path, "plot", raw.get("plot", {}), PLOT_KEYS)
    panels = tuple(tuple(panel) for panel in p.get("panels", [[outputs[0]]]))
    xs = p.get("x", "time")
    for var in [xs, *(v for panel in panels for v in panel)]:
        if var not in recorded:
            raise _err(path, "plot", f"{var!r} is not recorded (outputs, inputs or time)")
    scale = {}
    for k, s in _table(path, "plot.scale", p.get("scale", {}), recorded).items():
        s = _table(path, f"plot.scale.{k}", s, {"factor", "label"})
        scale[k] = (
            _positive(path, f"plot.scale.{k}.factor", s.get("factor")),
            str(s.get("label", k)),
        )
    return Scene(
        path=path,
        name=name,
        title=str(raw.get("title", name)),
        description=str(raw.get("description", "")),
        model=dict(model),
        stop_time=stop,
        step=step,
        outputs=tuple(outputs),
        cases=tuple(cases),
        references=tuple(refs),
        plot=Plot(xs, panels, scale),
        config=config,
        field=field_req,
    )


def discover(directory: str | Path) -> list[Path]:
    """The scene files of a directory, sorted."""
    return sorted(Path(directory).glob("*.toml"))
