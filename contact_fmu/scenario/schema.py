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
    [sweep]                             # a parameter study (``contact-fmu sweep``):
    vary = { mu = "0.1:0.5:9", "My_ex.sine.amplitude" = [0.0, 1.9] }
                                        # parameters, inputs (held at the value) or an
                                        # input's piece field; a list or "start:stop:n"
    metrics = [{ name = "peak", of = "Tx", reduce = "max_abs", per = ["mu", "P"] }]
                                        # summary values of each run (``Metric``)
    plot = { metric = "peak", x = "mu", y = "My_ex.sine.amplitude" }
    trajectories = false                # also every run's recorded columns

The runner uses only what is here; how a reference was produced is recorded in its
``source`` and options, and ``references.py`` reproduces it.
"""

from __future__ import annotations

import math
import re
import tomllib
from dataclasses import dataclass, field
from dataclasses import field as _field  # Scene has a field named 'field'
from decimal import Decimal
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
    "sweep",
}
MODEL_KEYS = {"mode", "contact_law", "phase", "method", "scheme", "vy", "spin"}
RUN_KEYS = {"stop_time", "step", "outputs", "field"}
FIELD_KEYS = {"times", "file"}
CASE_KEYS = {"name", "parameters", "inputs", "method", "scheme"}
REFERENCE_KEYS = {"file", "source", "note", "tolerance", "cases", "options"}
PLOT_KEYS = {"x", "panels", "scale"}
SWEEP_KEYS = {"vary", "metrics", "plot", "trajectories"}
METRIC_KEYS = {"name", "of", "reduce", "per", "after", "tol", "threshold"}
SWEEP_PLOT_KEYS = {"metric", "x", "y"}
# Reductions of one recorded column over a run (contact_fmu.study.metrics); the
# last two need ``tol``, ``threshold`` (in the unit of the column divided by ``per``).
REDUCTIONS = ("max", "min", "max_abs", "mean", "final", "settle_time", "any_above", "any_below")
NEEDS = {"settle_time": "tol", "any_above": "threshold", "any_below": "threshold"}
# Signal pieces whose number fields a sweep may vary ("INPUT.piece.field").
PIECE_FIELDS = {
    "constant": (),
    "step": ("time", "height"),
    "ramp": ("start", "duration", "height"),
    "sine": ("amplitude", "period", "phase", "start"),
}
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
class Vary:
    """A varied name and its values: an FMU parameter, an input (held constant at the
    value) or a number field of an input's piece, "INPUT.piece.field"."""

    name: str
    values: tuple[float, ...]


@dataclass(frozen=True)
class Metric:
    """A summary value of a run: ``reduce`` of the recorded column ``of`` divided,
    sample by sample, by the product of ``per`` (parameters or recorded columns),
    over the samples with time >= ``after`` (s)."""

    name: str
    of: str
    reduce: str
    per: tuple[str, ...] = ()
    after: float = 0.0
    tol: float | None = None
    threshold: float | None = None


@dataclass(frozen=True)
class Sweep:
    """[sweep]: the varied names (every combination runs every case), the metrics of
    each run, the plot (a metric over one or two varied names) and whether the full
    recorded columns are kept."""

    vary: tuple[Vary, ...] = ()
    metrics: tuple[Metric, ...] = ()
    plot: dict[str, str] = field(default_factory=dict)
    trajectories: bool = False


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
    sweep: Sweep = _field(default_factory=Sweep)
    source: dict[str, Any] = _field(default_factory=dict, repr=False, compare=False)

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
    return from_data(path, raw)


def from_data(path: str | Path, raw: dict[str, Any]) -> Scene:
    """Check the scene's TOML data ``raw`` (read from ``path``, which names it in errors
    and locates its references)."""
    path = Path(path)
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
    sweep = _sweep(path, raw.get("sweep", {}), config, raw, cases, recorded)
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
        sweep=sweep,
        source=raw,
    )


def sweep_values(where: str, v: Any) -> tuple[float, ...]:
    """Values of a varied name: a list of numbers, or a string "a,b,c" (a list) or
    "start:stop:n" (n >= 2 equally spaced values, both ends included)."""
    if isinstance(v, str):
        text = v.strip()
        try:
            if ":" in text:
                parts = text.split(":")
                if len(parts) != 3:
                    raise ValueError
                a, b, n = Decimal(parts[0].strip()), Decimal(parts[1].strip()), parts[2].strip()
                if not n.isdigit() or int(n) < 2:
                    raise InputError(where, v, '"start:stop:n" with a whole number n >= 2')
                # in decimal: 0.2:0.4:5 gives 0.25 and 0.3 as typed (linspace: 0.30000000000000004)
                m = int(n) - 1
                v = [float(a + (b - a) * i / m) for i in range(m + 1)]
            else:
                v = [float(x) for x in text.split(",")]
        except (ValueError, ArithmeticError):  # decimal.InvalidOperation: not a number
            raise InputError(where, v, 'a list "a,b,c" or a range "start:stop:n"') from None
    if not (isinstance(v, list) and v):
        raise InputError(where, v, 'a non-empty list of numbers or a range "start:stop:n"')
    for x in v:
        if isinstance(x, bool) or not isinstance(x, int | float) or not math.isfinite(x):
            raise InputError(where, x, "a finite number")
    if len(set(v)) != len(v):
        raise InputError(where, v, "distinct values")
    return tuple(float(x) for x in v)


def _piece_specs(spec: Any) -> list[Any]:
    return spec if isinstance(spec, list) else [spec]


def check_varied(path: Path, name: str, config: ModelConfig, raw: dict[str, Any]) -> None:
    """A varied ``name`` must be a parameter of the model, one of the scene's inputs,
    or "INPUT.piece.field" naming a number field of exactly one piece of that input
    (in [inputs] and in every case that overrides the input)."""
    params = {v.name for v in config.variables if v.causality[config.mode] == fv.PARAMETER}
    if name in params or name in config.inputs:
        return
    where = f"sweep.vary.{name}"
    parts = name.split(".")
    if len(parts) != 3 or parts[0] not in config.inputs:
        raise _err(
            path,
            where,
            f"not a parameter ({sorted(params)}), an input ({list(config.inputs)}) "
            "or INPUT.piece.field",
        )
    inp, kind, key = parts
    if key not in PIECE_FIELDS.get(kind, ()):
        raise _err(path, where, f"{kind}.{key} is not a number field of a signal piece")
    specs = [raw.get("inputs", {}).get(inp)]
    specs += [c.get("inputs", {}).get(inp) for c in raw.get("cases", [])]
    for spec in (s for s in specs if s is not None):
        n = sum(isinstance(p, dict) and kind in p for p in _piece_specs(spec))
        if n != 1:
            raise _err(path, where, f"inputs.{inp} has {n} '{kind}' pieces (one needed)")


def _sweep(
    path: Path,
    d: Any,
    config: ModelConfig,
    raw: dict[str, Any],
    cases: list[Case],
    recorded: set[str],
) -> Sweep:
    d = _table(path, "sweep", d, SWEEP_KEYS)
    vary = []
    for name, v in _table(path, "sweep.vary", d.get("vary", {}), set(d.get("vary", {}))).items():
        check_varied(path, name, config, raw)
        vary.append(Vary(name, sweep_values(f"sweep.vary.{name}", v)))
    metrics = []
    raw_metrics = d.get("metrics", [])
    if not isinstance(raw_metrics, list):
        raise _err(path, "sweep.metrics", "must be an array of tables")
    for i, m in enumerate(raw_metrics):
        metrics.append(_metric(path, f"sweep.metrics[{i}]", m, cases, recorded))
    if len({m.name for m in metrics}) != len(metrics):
        raise _err(path, "sweep.metrics", "metric names must be unique")
    plot = dict(_table(path, "sweep.plot", d.get("plot", {}), SWEEP_PLOT_KEYS))
    if plot and plot.get("metric") not in {m.name for m in metrics}:
        raise _err(path, "sweep.plot.metric", f"{plot.get('metric')!r} is not a metric")
    for k in ("x", "y"):
        if k in plot and plot[k] not in {v.name for v in vary}:
            raise _err(path, f"sweep.plot.{k}", f"{plot[k]!r} is not a varied name")
    trajectories = d.get("trajectories", False)
    if not isinstance(trajectories, bool):
        raise _err(path, "sweep.trajectories", f"{trajectories!r} must be true or false")
    return Sweep(tuple(vary), tuple(metrics), plot, trajectories)


def _metric(path: Path, where: str, m: Any, cases: list[Case], recorded: set[str]) -> Metric:
    m = _table(path, where, m, METRIC_KEYS)
    name, of, red = m.get("name"), m.get("of"), m.get("reduce")
    if not isinstance(name, str) or not name.isidentifier():
        raise _err(path, f"{where}.name", f"{name!r} must be an identifier")
    if of not in recorded:
        raise _err(path, f"{where}.of", f"{of!r} is not recorded (outputs, inputs or time)")
    if red not in REDUCTIONS:
        raise _err(path, f"{where}.reduce", f"{red!r} is not one of {list(REDUCTIONS)}")
    per = m.get("per", [])
    if not isinstance(per, list):
        raise _err(path, f"{where}.per", f"{per!r} must be a list of names")
    for p in per:
        if p not in recorded and not all(p in c.parameters for c in cases):
            raise _err(path, f"{where}.per", f"{p!r} is not recorded nor set in every case")
    after = m.get("after", 0.0)
    if isinstance(after, bool) or not isinstance(after, int | float) or not after >= 0:
        raise _err(path, f"{where}.after", f"{after!r} must be a time >= 0 (s)")
    extra = {}
    for k in ("tol", "threshold"):
        if k in m:
            if isinstance(m[k], bool) or not isinstance(m[k], int | float):
                raise _err(path, f"{where}.{k}", f"{m[k]!r} must be a number")
            extra[k] = float(m[k])
    need = NEEDS.get(red)
    if need is not None and need not in extra:
        raise _err(path, where, f"reduce = {red!r} needs '{need}'")
    if "tol" in extra and not extra["tol"] > 0:
        raise _err(path, f"{where}.tol", f"{extra['tol']!r} must be > 0")
    return Metric(name, of, red, tuple(per), float(after), **extra)


def discover(directory: str | Path) -> list[Path]:
    """The scene files of a directory, sorted."""
    return sorted(Path(directory).glob("*.toml"))
