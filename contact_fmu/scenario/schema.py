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
    [checks]                            # plausibility warnings (plausibility.py):
    accept = ["Rx"]                     # keys whose questioned values are meant
    plausibility = true                 # false: no plausibility checks

Strict: [model] with its mode, [run] with stop_time, step and outputs, and the model's
physical parameters (``required_parameters``) are required; values have their declared
type (no string or bool for a number); each name must be a variable of the model in the
table it is written in. Every error is one line naming the file, the key as a TOML path,
the value and what is allowed (docs/scenes.md).

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
from types import SimpleNamespace
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .._validate import InputError
from ..fmu import variables as fv
from ..fmu.config import LAW_MODULES as LAWS
from ..fmu.config import METHODS, PHASES, SCHEMES, ModelConfig
from . import plausibility
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
    "checks",
}
# The FMU modes a scene runs (the third, rigid_body, is coupled to a contact-mode FMU:
# ``contact-fmu system``).
MODES = ("body", "contact")
MODEL_KEYS = {"mode", "contact_law", "phase", "method", "scheme", "vy", "spin"}
RUN_KEYS = {"stop_time", "step", "outputs", "field"}
FIELD_KEYS = {"times", "file"}
CASE_KEYS = {"name", "parameters", "inputs", "method", "scheme"}
REFERENCE_KEYS = {"file", "source", "note", "tolerance", "cases", "options"}
PLOT_KEYS = {"x", "panels", "scale"}
SWEEP_KEYS = {"vary", "metrics", "plot", "trajectories"}
METRIC_KEYS = {"name", "of", "reduce", "per", "after", "tol", "threshold"}
SWEEP_PLOT_KEYS = {"metric", "x", "y"}
CHECKS_KEYS = {"plausibility", "accept"}
# Longest value an error message shows (it stays one line).
SHOW_MAX = 80
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
    """A scene file is malformed; the message, one line, names the file, the key, the
    value and what is allowed."""

    def __init__(self, message: str) -> None:
        super().__init__(" ".join(message.split("\n")))


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
class Checks:
    """[checks]: whether the plausibility checks run (``plausibility``), and the keys
    whose values they question but that the scene means as written (``accept``)."""

    plausibility: bool = True
    accept: tuple[str, ...] = ()


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
    checks: Checks = _field(default_factory=Checks)
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


def _show(value: Any) -> str:
    """A value as the scene wrote it, on one line and at most SHOW_MAX characters."""
    text = repr(value).replace("\n", " ")
    return text if len(text) <= SHOW_MAX else text[: SHOW_MAX - 3] + "..."


def _err(path: Path, where: str, msg: str) -> ScenarioError:
    return ScenarioError(f"{path}: {where}: {msg}")


def _bad(path: Path, where: str, value: Any, allowed: str) -> ScenarioError:
    """The key ``where`` (a dotted TOML path) has ``value``, which is not ``allowed``."""
    return ScenarioError(f"{path}: {where} = {_show(value)} is invalid: must be {allowed}")


def _missing(path: Path, where: str, what: str) -> ScenarioError:
    return ScenarioError(f"{path}: {where} is missing: {what}")


def _hint(v: Any) -> str:
    """Why a value that looks like a number is none (TOML keeps strings and booleans)."""
    if isinstance(v, str):
        return " (a string is not a number: write it without quotes)"
    if isinstance(v, bool):
        return " (true/false is not a number)"
    return ""


def _is_number(v: Any) -> bool:
    """An int or float as TOML gives them; bool is an int in Python and is refused."""
    return isinstance(v, int | float) and not isinstance(v, bool)


def _table(path: Path, where: str, d: Any, allowed: set[str]) -> dict[str, Any]:
    if not isinstance(d, dict):
        raise _bad(path, where, d, "a table")
    extra = sorted(set(d) - allowed)
    if extra:
        shown = ", ".join(f"{k} = {_show(d[k])}" for k in extra)
        raise _err(path, where, f"unknown key(s) {extra} ({shown}); allowed: {sorted(allowed)}")
    return d


def _section(
    path: Path, raw: dict[str, Any], key: str, allowed: set[str], what: str | None = None
) -> dict[str, Any]:
    """The table [key]; a missing one is an error when ``what`` (its content) is given."""
    if key not in raw:
        if what is not None:
            raise _missing(path, f"[{key}]", what)
        return {}
    return _table(path, key, raw[key], allowed)


def _positive(path: Path, where: str, v: Any, unit: str = "") -> float:
    if not _is_number(v) or not (math.isfinite(v) and v > 0):
        raise _bad(path, where, v, f"a finite number > 0{f' ({unit})' if unit else ''}{_hint(v)}")
    return float(v)


def _required(path: Path, d: dict[str, Any], where: str, key: str, what: str) -> Any:
    if key not in d:
        raise _missing(path, f"{where}.{key}" if where else key, what)
    return d[key]


def _string(path: Path, where: str, v: Any, what: str = "a string") -> str:
    if not isinstance(v, str):
        raise _bad(path, where, v, what)
    return v


def _choice(path: Path, where: str, v: Any, allowed: tuple[str, ...]) -> str:
    if v not in allowed or not isinstance(v, str):
        raise _bad(path, where, v, f"one of {list(allowed)}")
    return v


def _lateral(path: Path, key: str, v: Any, eq: str) -> tuple[str, float | None]:
    if v == eq:
        return eq, None
    if not _is_number(v) or not math.isfinite(v):
        raise _bad(path, f"model.{key}", v, f"a number (held ratio) or {eq!r}{_hint(v)}")
    return ("zero", None) if v == 0 else ("ratio", float(v))


def _halfspace(path: Path, d: Any) -> dict[str, Any]:
    """[halfspace] as plain data; its keys and values are checked by the model config
    (contact_fmu.halfspace.spec.TableSpec), whose errors name them."""
    if not isinstance(d, dict):
        raise _bad(path, "halfspace", d, "a table")
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
        raise _bad(path, "run.field.times", times, "a non-empty list of times (s)")
    for t in times:
        if not _is_number(t) or not 0.0 <= t <= stop:
            raise _bad(path, "run.field.times", t, f"a time in [0, stop_time] (s){_hint(t)}")
    name = d.get("file")
    if not isinstance(name, str) or not name or Path(name).name != name:
        raise _bad(path, "run.field.file", name, "a file name (no folders)")
    return FieldRequest(tuple(sorted(float(t) for t in times)), name)


# ---- FMU variables in the scene: where each belongs ----------------------------------------
# The model structure a variable needs, in the scene's words (variables.CONDITIONS).
NEEDS_TEXT = {
    "vy": "model.vy other than 0",
    "vy_eq10": 'model.vy = "eq10"',
    "vy_ratio": "model.vy a held ratio (it sets vy_ratio)",
    "spin": "model.spin other than 0",
    "spin_eq11": 'model.spin = "eq11"',
    "spin_ratio": "model.spin a held ratio (it sets spin_ratio)",
    "lateral": "model.vy or model.spin other than 0",
    "methods": "cases with different methods",
    "schemes": "cases with different schemes",
    "transient": 'model.phase = "transient"',
}
# The parameter that gives an output's initial value (body mode).
INITIAL = {"Vx": "Vx0", "vx": "vx0", "Vy": "Vy0", "Omega_z": "Omega_z0", "Omega_y": "Vx0, vx0"}
# String parameters the scene sets through its own keys, not [parameters].
SET_BY = {
    "method": "model.method or a case's method",
    "scheme": "model.scheme or a case's scheme",
    "field_file": "run.field",
    "field_times": "run.field",
}
# The inputs each mode needs (the model's own check: fmu.config.ModelConfig).
REQUIRED_INPUTS = {"body": ("P",), "contact": ("P", "Vx", "Omega_y")}
# Parameters that the half-space law takes from [halfspace] (mu may still be set).
FROM_HALFSPACE = ("mu", "Rx")
# Physical parameters a scene must give: their built-in defaults (the paper's example
# set: a 1 kg body, Rx = 0.05 m, ...) would otherwise run silently. The initial slip and
# lateral motion (vx0, Vy0, Omega_z0) default to none, and the numerical settings
# (h_max, nx, ny, cells_per_step) to their documented values.
PHYSICAL = ("mu", "Rx", "Ry", "k1", "k2", "kb", "ks", "M", "Iy", "Iz", "Vx0")


def _structure(mode: str, law: str, phase: str, vy: str, spin: str, cases: list[dict]) -> Any:
    """The model structure (variables.Structure) before the model config is built."""
    return SimpleNamespace(
        mode=mode,
        contact_law=law,
        phase=phase,
        vy=vy,
        spin=spin,
        methods=tuple(dict.fromkeys(c["method"] for c in cases)),
        schemes=tuple(dict.fromkeys(c["scheme"] for c in cases)),
    )


def required_parameters(s: Any) -> tuple[str, ...]:
    """The parameters a scene of the model structure ``s`` must give (PHYSICAL, as far as
    the model has them; the half-space law's mu and Rx come from [halfspace])."""
    names = []
    for n in PHYSICAL:
        v = fv.BY_NAME[n]
        if fv.applicable(v, s) and v.causality[s.mode] == fv.PARAMETER:
            if not (s.contact_law == "halfspace" and n in FROM_HALFSPACE):
                names.append(n)
    return tuple(names)


def _misplaced(s: Any, name: str, want: str, inputs_at: str, parameters_at: str) -> str | None:
    """Why ``name`` is not a ``want`` (parameter, input or output) of the model ``s``, and
    where it belongs; None when it is one. ``inputs_at``, ``parameters_at``: the tables
    the scene gives inputs and parameters in, at this place."""
    var = fv.BY_NAME.get(name)
    allowed = fv.available(s, want)
    model = f"this {s.mode}-mode model"
    if var is None:
        return f"no FMU variable is called {name!r}; the {want}s of {model}: {allowed}"
    if want == fv.PARAMETER and name in SET_BY:
        return f"{name} is set by {SET_BY[name]}, not in [parameters]"
    if s.mode not in var.causality:
        return f"{name} is not a variable of a {s.mode}-mode model; its {want}s: {allowed}"
    if var.laws is not None and s.contact_law not in var.laws:
        return (
            f"{name} is a parameter of the {'/'.join(var.laws)} law: a {s.contact_law} model "
            "takes its contact from [halfspace]"
        )
    if not fv.applicable(var, s):
        return f"{name} is a variable of {model} only with {NEEDS_TEXT[var.needs]}"
    c = var.causality[s.mode]
    if c == want:
        return None
    if c == fv.OUTPUT:
        text = f"{name} is an output of {model}, not a {want}: list it in run.outputs to record it"
        if s.mode == "body" and name in INITIAL:
            text += f" (its initial value: the parameter(s) {INITIAL[name]})"
        return text
    if c == fv.INPUT:
        if want == fv.OUTPUT:
            return f"{name} is an input of {model}: every input is recorded anyway"
        return f"{name} is an input of {model}, not a {want}: it belongs in {inputs_at}"
    return f"{name} is a parameter of {model}, not an {want}: it belongs in {parameters_at}"


def _parameter(path: Path, where: str, var: fv.Var, v: Any) -> Any:
    """A parameter's value: its declared type (no string or bool for a number), then its
    declared range (variables.py: the ranges of the FMU's variables)."""
    unit = f" ({var.unit})" if var.unit not in (None, "1") else ""
    if var.type == "String":
        if not isinstance(v, str):
            raise _bad(path, where, v, "a string")
        return v
    if var.type == "Integer":
        if not isinstance(v, int) or isinstance(v, bool):
            raise _bad(path, where, v, f"an integer{_hint(v)}")
    elif not _is_number(v):
        raise _bad(path, where, v, f"a number{unit}{_hint(v)}")
    problem = var.check(v)
    if problem is not None:
        raise _bad(path, where, v, f"{problem}{unit}")
    return v


def _parameters(path: Path, where: str, d: Any, s: Any, inputs_at: str) -> dict[str, Any]:
    d = _table(path, where, d, set(d) if isinstance(d, dict) else set())
    for k, v in d.items():
        why = _misplaced(s, k, fv.PARAMETER, inputs_at, where)
        if why is not None:
            raise _err(path, f"{where}.{k} = {_show(v)}", why)
        _parameter(path, f"{where}.{k}", fv.BY_NAME[k], v)
    return d


def _inputs(path: Path, where: str, d: Any, s: Any, parameters_at: str) -> dict[str, Signal]:
    d = _table(path, where, d, set(d) if isinstance(d, dict) else set())
    out = {}
    for k, v in d.items():
        why = _misplaced(s, k, fv.INPUT, where, parameters_at)
        if why is not None:
            raise _err(path, f"{where}.{k} = {_show(v)}", why)
        out[k] = parse(k, v, where=f"{where}.{k}")
    return out


def _located(path: Path, s: Any, e: InputError) -> ScenarioError:
    """An error of the model config (``name = value is invalid: must be ...``) at the
    scene key it comes from."""
    name = str(e.name)
    var = fv.BY_NAME.get(name)
    if name in MODEL_KEYS:
        where = f"model.{name}"
    elif name == "outputs":
        where = "run.outputs"
    elif var is not None and s.mode in var.causality:
        where = f"{'inputs' if var.causality[s.mode] == fv.INPUT else 'parameters'}.{name}"
    else:
        where = name
    _, sep, requirement = str(e).partition(" is invalid: must be ")
    if not sep:
        return ScenarioError(f"{path}: {e}")
    return _bad(path, where, e.value, requirement)


def load(path: str | Path) -> Scene:
    """Read and check a scene file; values that look like unit slips are reported as
    PlausibilityWarning (``plausibility.py``) unless the scene's [checks] accepts them."""
    path = Path(path)
    try:
        with path.open("rb") as f:
            raw = tomllib.load(f)
    except OSError as e:
        raise ScenarioError(f"{path}: cannot read: {e.strerror or e}") from e
    except tomllib.TOMLDecodeError as e:
        raise ScenarioError(f"{path}: not valid TOML: {e}") from e
    scene = from_data(path, raw)
    plausibility.warn(scene)
    return scene


def from_data(path: str | Path, raw: dict[str, Any]) -> Scene:
    """Check the scene's TOML data ``raw`` (read from ``path``, which names it in errors
    and locates its references). No plausibility warnings: ``load`` gives them."""
    path = Path(path)
    try:
        return _scene(path, raw)
    except (InputError, SignalError) as e:
        raise ScenarioError(f"{path}: {e}") from e


def _scene(path: Path, raw: dict[str, Any]) -> Scene:
    _table(path, "top level", raw, TOP_KEYS)
    name = _required(path, raw, "", "name", "an identifier: names the FMU and files")
    if not isinstance(name, str) or not name.isidentifier():
        raise _bad(path, "name", name, "an identifier (letters, digits, _)")
    title = _string(path, "title", raw.get("title", name))
    description = _string(path, "description", raw.get("description", ""))

    model = _section(path, raw, "model", MODEL_KEYS, 'the model structure (mode = "body" ...)')
    mode = _choice(
        path, "model.mode", _required(path, model, "model", "mode", "body | contact"), MODES
    )
    law = _choice(path, "model.contact_law", model.get("contact_law", "layer"), tuple(LAWS))
    phase = _choice(path, "model.phase", model.get("phase", "steady"), PHASES)
    default_method = _choice(path, "model.method", model.get("method", "full"), METHODS)
    default_scheme = _choice(path, "model.scheme", model.get("scheme", SCHEMES[0]), SCHEMES)
    vy, vy_ratio = _lateral(path, "vy", model.get("vy", 0.0), "eq10")
    spin, spin_ratio = _lateral(path, "spin", model.get("spin", 0.0), "eq11")

    run = _section(path, raw, "run", RUN_KEYS, "the time grid and outputs (stop_time, ...)")
    stop = _positive(path, "run.stop_time", _required(path, run, "run", "stop_time", "s"), "s")
    step = _positive(path, "run.step", _required(path, run, "run", "step", "s"), "s")
    n = round(stop / step)
    if n < 1 or abs(n * step - stop) > GRID_RTOL * stop:
        raise _bad(path, "run.step", step, f"stop_time/step whole >= 1 (is {stop / step!r})")
    outputs = _required(path, run, "run", "outputs", "the FMU outputs to record")
    if not (isinstance(outputs, list) and outputs and all(isinstance(o, str) for o in outputs)):
        raise _bad(path, "run.outputs", outputs, "a non-empty list of output names")

    cases_raw = raw.get("cases", [{"name": "default"}])
    if not isinstance(cases_raw, list) or not cases_raw:
        raise _bad(path, "cases", cases_raw, "a non-empty array of tables ([[cases]])")
    heads = []
    for i, c in enumerate(cases_raw):
        c = _table(path, f"cases[{i}]", c, CASE_KEYS)
        cname = _required(path, c, f"cases[{i}]", "name", "a non-empty string")
        if not isinstance(cname, str) or not cname:
            raise _bad(path, f"cases[{i}].name", cname, "a non-empty string")
        at = f"cases[{cname!r}]"
        method = _choice(path, f"{at}.method", c.get("method", default_method), METHODS)
        scheme = _choice(path, f"{at}.scheme", c.get("scheme", default_scheme), SCHEMES)
        heads.append({"name": cname, "at": at, "method": method, "scheme": scheme, "raw": c})
    names = [h["name"] for h in heads]
    if len(set(names)) != len(names):
        raise _bad(path, "cases", names, "cases with distinct names")
    s = _structure(mode, law, phase, vy, spin, heads)

    for o in outputs:
        why = _misplaced(s, o, fv.OUTPUT, "[inputs]", "[parameters]")
        if why is not None:
            raise _err(path, f"run.outputs = {_show(outputs)}", why)

    params = dict(_parameters(path, "parameters", raw.get("parameters", {}), s, "[inputs]"))
    if vy_ratio is not None:
        params.setdefault("vy_ratio", vy_ratio)
    if spin_ratio is not None:
        params.setdefault("spin_ratio", spin_ratio)
    base_inputs = _inputs(path, "inputs", raw.get("inputs", {}), s, "[parameters]")

    cases = []
    for h in heads:
        at, c = h["at"], h["raw"]
        cp = _parameters(path, f"{at}.parameters", c.get("parameters", {}), s, f"{at}.inputs")
        ci = _inputs(path, f"{at}.inputs", c.get("inputs", {}), s, f"{at}.parameters")
        cases.append(
            Case(h["name"], {**params, **cp}, {**base_inputs, **ci}, h["method"], h["scheme"])
        )

    need = required_parameters(s)
    for c in cases:
        lacking = [k for k in need if k not in c.parameters]
        if lacking:
            where = "[parameters]" if len(cases) == 1 else f"[parameters] (or cases[{c.name!r}])"
            raise _missing(
                path,
                f"{where} {', '.join(lacking)}",
                f"a {mode}-mode scene with the {law} law gives {', '.join(need)} "
                "(SI units; no built-in defaults)",
            )
    for k in REQUIRED_INPUTS.get(mode, ()):
        if k not in base_inputs and not all(k in c.inputs for c in cases):
            unit = fv.BY_NAME[k].unit
            raise _missing(
                path, f"inputs.{k}", f"a {mode}-mode scene drives {k} ({unit}), a signal"
            )
    input_names = tuple(v.name for v in fv.VARIABLES if any(v.name in c.inputs for c in cases))
    for c in cases:
        missing = sorted(set(input_names) - set(c.inputs))
        if missing:
            raise _missing(
                path,
                f"cases[{c.name!r}].inputs {', '.join(missing)}",
                "another case drives them: give a signal in [inputs] or in every case",
            )

    methods = tuple(dict.fromkeys(c.method for c in cases))
    schemes = tuple(dict.fromkeys(c.scheme for c in cases))
    starts = dict(params)
    starts.update({k: float(sig(np.zeros(1))[0]) for k, sig in base_inputs.items()})
    if len(methods) > 1:
        starts["method"] = methods[0]
    if len(schemes) > 1:
        starts["scheme"] = schemes[0]
    try:
        config = ModelConfig(
            name=name,
            mode=mode,
            inputs=input_names,
            outputs=tuple(outputs),
            contact_law=law,
            phase=phase,
            methods=methods,
            schemes=schemes,
            vy=vy,
            spin=spin,
            starts=starts,
            experiment=(0.0, stop, step),
            description=title,
            law_spec=_halfspace(path, raw.get("halfspace", {})),
        )
    except InputError as e:
        if str(e.name).startswith("halfspace"):
            raise
        raise _located(path, s, e) from e
    for c in cases:
        for k, v in c.parameters.items():
            problem = config.check(k, v)
            if problem is not None:
                raise _bad(path, f"cases[{c.name!r}].parameters.{k}", v, problem)

    recorded = set(outputs) | set(input_names) | {"time"}
    refs_raw = raw.get("reference", [])
    if not isinstance(refs_raw, list):
        raise _bad(path, "reference", refs_raw, "an array of tables ([[reference]])")
    refs = [_reference(path, i, r, cases, recorded) for i, r in enumerate(refs_raw)]

    field_req = _field(path, run.get("field"), config, stop)
    plot = _plot(path, _section(path, raw, "plot", PLOT_KEYS), outputs, recorded)
    checks = _checks(path, _section(path, raw, "checks", CHECKS_KEYS))
    sweep = _sweep(path, raw.get("sweep", {}), config, raw, cases, recorded)
    return Scene(
        path=path,
        name=name,
        title=title,
        description=description,
        model=dict(model),
        stop_time=stop,
        step=step,
        outputs=tuple(outputs),
        cases=tuple(cases),
        references=tuple(refs),
        plot=plot,
        config=config,
        field=field_req,
        sweep=sweep,
        checks=checks,
        source=raw,
    )


def _names(path: Path, where: str, v: Any, allowed: set[str], what: str) -> list[str]:
    """A list of names, each in ``allowed``."""
    if not isinstance(v, list) or not all(isinstance(x, str) for x in v):
        raise _bad(path, where, v, f"a list of {what}")
    for x in v:
        if x not in allowed:
            raise _bad(path, where, v, f"a list of {what}: {x!r} is none ({sorted(allowed)})")
    return v


def _reference(path: Path, i: int, r: Any, cases: list[Case], recorded: set[str]) -> Reference:
    at = f"reference[{i}]"
    r = _table(path, at, r, REFERENCE_KEYS)
    file = _string(
        path, f"{at}.file", _required(path, r, at, "file", "a CSV file next to the scene"),
        "a file name (a CSV next to the scene)",
    )  # fmt: skip
    source = _string(path, f"{at}.source", _required(path, r, at, "source", "its producing path"))
    tol = _table(
        path, f"{at}.tolerance", _required(path, r, at, "tolerance", "absolute, per variable"),
        recorded,
    )  # fmt: skip
    if not tol:
        raise _bad(path, f"{at}.tolerance", tol, "a table of variable = absolute tolerance")
    tol = {k: _positive(path, f"{at}.tolerance.{k}", v, "SI") for k, v in tol.items()}
    all_cases = {c.name for c in cases}
    rcases = _names(path, f"{at}.cases", r.get("cases", [c.name for c in cases]), all_cases,
                    "case names")  # fmt: skip
    options = r.get("options", {})
    if not isinstance(options, dict):
        raise _bad(path, f"{at}.options", options, "a table (options of the producing path)")
    note = _string(path, f"{at}.note", r.get("note", ""))
    return Reference(path.parent / file, source, tol, tuple(rcases), dict(options), note)


def _plot(path: Path, p: dict[str, Any], outputs: list[str], recorded: set[str]) -> Plot:
    xs = p.get("x", "time")
    if xs not in recorded:
        raise _bad(
            path, "plot.x", xs, f"a recorded name (outputs, inputs or time: {sorted(recorded)})"
        )
    panels_raw = p.get("panels", [[outputs[0]]])
    if not isinstance(panels_raw, list) or not panels_raw:
        raise _bad(path, "plot.panels", panels_raw, "a non-empty list of lists of names")
    panels = []
    for panel in panels_raw:
        if not isinstance(panel, list) or not panel:
            raise _bad(path, "plot.panels", panel, "a non-empty list of recorded names")
        panels.append(tuple(_names(path, "plot.panels", panel, recorded, "recorded names")))
    scale = {}
    for k, sc in _table(path, "plot.scale", p.get("scale", {}), recorded).items():
        sc = _table(path, f"plot.scale.{k}", sc, {"factor", "label"})
        factor = _positive(path, f"plot.scale.{k}.factor", sc.get("factor"))
        scale[k] = (factor, _string(path, f"plot.scale.{k}.label", sc.get("label", k)))
    return Plot(xs, tuple(panels), scale)


def _checks(path: Path, d: dict[str, Any]) -> Checks:
    on = d.get("plausibility", True)
    if not isinstance(on, bool):
        raise _bad(path, "checks.plausibility", on, "true or false")
    accept = d.get("accept", [])
    _names(path, "checks.accept", accept, set(plausibility.KEYS), "checked keys")
    return Checks(on, tuple(accept))


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
