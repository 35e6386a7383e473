"""The pythonfmu adapter: the only module of the project that imports pythonfmu.

``ContactSlave`` is one generic FMI 2.0 co-simulation slave. A built FMU subclasses it
with a ``CONFIG`` (a ``ModelConfig`` as plain data); the variables it registers and
the model it runs follow from that configuration and from ``variables.VARIABLES``.

Error handling. pythonfmu 0.7.0 answers fmi2Fatal for any Python exception and
fmi2Discard only when ``do_step`` returns False; setReal cannot answer anything but
fmi2OK or fmi2Fatal. So nothing here raises to pythonfmu:

- an inadmissible value (NaN/inf input, P <= 0, a parameter out of its range, a
  value other than the fixed one of a half-space FMU's Rx) is
  accepted by setReal with a logged message naming the variable and the value; while
  it is held, every doStep answers fmi2Discard with the same message and leaves the
  state untouched; once the value is corrected the instance steps normally;
- doStep with a non-positive or non-finite step, or one that does not start at the
  FMU's time, answers fmi2Discard;
- a failing step (stage solve, non-finite result) restores the state taken before it
  and answers fmi2Discard;
- parameters are fixed: once the model is set up, setting one is ignored with a
  logged error; while it cannot be set up (bad parameters) they may still be set.

FMU state (get/set) holds everything: the model's snapshot, parameter and input values,
outputs, time and flags; get state, step, set state, step again repeats bit for bit.
Serialized (``state_bytes``), it restores into another instance of the same FMU, in
this process or another. Bytes that are not a state of this FMU cannot be refused at
fmi2DeSerializeFMUstate (pythonfmu knows only fmi2Fatal there): setFMUstate with them
logs an error, leaves the state as it is, and every doStep answers fmi2Discard naming
the reason until a valid state is set.

Compiled step: where the model offers one (``model.fast()``; the body model on the
compiled stepper's path, contact_fmu/native), doStep makes the checks above and one C
call, and the state and outputs stay in its struct; whatever it declines (a new load,
the cap on internal steps, a failing step) takes the Python path above, with the state
handed over (``_fast_pull``/``_fast_push``) and the same results.
"""

from __future__ import annotations

import copy
import importlib
import math
from functools import partial
from operator import getitem, itemgetter
from pathlib import Path
from typing import Any, ClassVar

from pythonfmu import (
    DefaultExperiment,
    Fmi2Causality,
    Fmi2Initial,
    Fmi2Slave,
    Fmi2Variability,
    Integer,
    Real,
    String,
)
from pythonfmu.enums import Fmi2Status

from . import state_bytes
from . import variables as fv
from .config import ModelConfig

# Relative tolerance between doStep's currentCommunicationPoint and the FMU's time
# (masters convert integer nanoseconds or accumulate steps: rounding only).
TIME_RTOL = 1e-9
_INF = math.inf

# the FMI calls a compiled binding takes over (native/fmi.c)
_FMI_CALLS = ("do_step", "set_real", "get_real")
_CAUSALITY = {
    fv.PARAMETER: Fmi2Causality.parameter,
    fv.INPUT: Fmi2Causality.input,
    fv.OUTPUT: Fmi2Causality.output,
}
_TYPES = {"Real": Real, "Integer": Integer, "String": String}
# This FMU's package (cfmu_<content hash> when built): the owner named in its state bytes
_PACKAGE = __name__.split(".")[0]
# the entry of _bad that a refused FMU state holds (no variable has this name)
_STATE = "FMU state"


class ContactSlave(Fmi2Slave):
    """Rolling/sliding contact after Spector & Batra (1995); the model follows CONFIG."""

    CONFIG: ClassVar[dict[str, Any]] = {}
    author = "contact_fmu"
    license = "MIT"

    def __init__(self, **kwargs: Any) -> None:
        super().__init__(**kwargs)
        cfg = ModelConfig.from_dict(self.CONFIG)
        self.cfg = cfg
        self.description = cfg.description or f"Spector & Batra (1995) contact, {cfg.mode} mode"
        if cfg.experiment is not None:
            start, stop, step = cfg.experiment
            self.default_experiment = DefaultExperiment(start, stop, step_size=step)
        self._vars = {v.name: v for v in cfg.variables}
        self._causality = {n: v.causality[cfg.mode] for n, v in self._vars.items()}
        # parameter and input values; the inputs also by themselves, the argument of
        # every step (kept in step with _values by _set)
        self._values: dict[str, Any] = {
            n: cfg.start(v) for n, v in self._vars.items() if self._causality[n] != fv.OUTPUT
        }
        self._in = self._input_values()
        self._out: dict[str, float] = {
            n: float(v.start) for n, v in self._vars.items() if self._causality[n] == fv.OUTPUT
        }
        self._bad: dict[str, str] = {}  # inadmissible values held: name -> message
        self._model: Any = None
        self._model_params: dict[str, Any] | None = None
        # the model's compiled step (model.fast(), e.g. native.FastBody) or None; while
        # it steps, the state lives in its struct and the outputs in _fast_out
        self._fast: Any = None
        self._fast_out: Any = None
        self._fast_step: Any = None  # its step as one C call f(h), 0 when done
        self._fast_index: dict[str, int] = {}
        self._fast_io: Any = None  # the struct the compiled step reads its inputs from
        self._fast_inputs: frozenset[str] = frozenset()  # the inputs it reads
        self._fast_vr: dict[int, int] = {}  # value reference -> index in _fast_out
        self._fast_fmi: Any = None  # the C binding of the FMI calls (native/fmi.c) or None
        # get_real's readers of _fast_out, by the tuple of value references asked for
        self._fast_reads: dict[tuple[int, ...], Any] = {}
        self._out_stale = False  # _out behind _fast_out (after compiled steps)
        self._getters: dict[str, Any] = {}  # the Python getters of the Real outputs
        self._time = 0.0
        self._dirty = True  # inputs changed since the outputs were computed
        for v in self._vars.values():
            self.register_variable(self._fmi_variable(v))
        # value reference -> (name, min, max, open min) of the Real inputs that set_real
        # tests itself, Var.check's rules for a float (test_input_fast_check_is_var_check)
        self._input_slots = {
            vr: (
                var.name,
                -math.inf if v.min is None else v.min,
                math.inf if v.max is None else v.max,
                v.open_min,
            )
            for vr, var in self.vars.items()
            if (v := self._vars[var.name]).type == "Real"
            and self._causality[v.name] == fv.INPUT
            and v.name not in cfg.fixed
        }

    # ---- registration ------------------------------------------------------------------
    def _fmi_variable(self, v: fv.Var) -> Any:
        c = self._causality[v.name]
        if c == fv.PARAMETER:
            variability, initial = Fmi2Variability.fixed, None
        elif c == fv.INPUT:
            variability, initial = Fmi2Variability.continuous, None
        else:
            variability = (
                Fmi2Variability.continuous if v.type == "Real" else Fmi2Variability.discrete
            )
            initial = Fmi2Initial.calculated
        # the per-step calls (Real inputs and outputs) take no detour
        if c == fv.OUTPUT and v.type == "Real":
            # replaced by a read of the compiled step's outputs while it runs
            getter = self._getters[v.name] = lambda n=v.name: self._real_output(n)  # noqa: E731
        else:
            getter = lambda n=v.name: self._get(n)  # noqa: E731
        setter = lambda value, n=v.name: self._set(n, value)  # noqa: E731
        return _TYPES[v.type](
            v.name,
            causality=_CAUSALITY[c],
            variability=variability,
            initial=initial,
            description=v.description,
            getter=getter,
            setter=setter,
        )

    # ---- get/set -------------------------------------------------------------------------
    def _real_output(self, name: str) -> float:
        if self._dirty and self._model is not None and self._model.feedthrough:
            self._refresh()
        return self._out[name]  # floats, checked finite by _collect

    def _get(self, name: str) -> Any:
        var = self._vars[name]
        if self._causality[name] == fv.OUTPUT:
            self._sync_out()
            if self._dirty and self._model is not None and self._model.feedthrough:
                self._refresh()
            value = self._out[name]
        else:
            value = self._values[name]
        if var.type == "Integer":
            return int(value)
        if var.type == "String":
            return str(value)
        return float(value)

    def _set(self, name: str, value: Any) -> None:
        c = self._causality[name]
        if c == fv.OUTPUT:
            self._error(f"{name} is an output of this FMU: the value {value!r} set is ignored")
            return
        if c == fv.PARAMETER and self._model is not None:
            self._error(
                f"{name} is a fixed parameter and the model is initialised: "
                f"{name} = {value!r} is ignored ({name} stays {self._values[name]!r})"
            )
            return
        var = self._vars[name]
        problem = self.cfg.check(name, value)
        self._values[name] = (
            value if var.type == "String" or problem == "a number" else float(value)
        )
        if c == fv.INPUT:
            self._in[name] = self._values[name]
            if problem is None:
                self._to_fast(name, self._in[name])
        if problem is None:
            if self._bad:
                self._bad.pop(name, None)
        else:
            msg = f"{name} = {value!r} is invalid: must be {problem}"
            self._bad[name] = msg
            self.log(f"{msg}; doStep answers fmi2Discard until it is corrected", Fmi2Status.error)
        if c == fv.INPUT:
            self._dirty = True

    def set_real(self, vrs: list[int], values: list[float]) -> None:
        """fmi2SetReal, the per-step call: a Real input's float is tested here against
        its declared range (Var.check's rules) and stored; anything else (not a float,
        out of range, a parameter, an output) goes through its setter (_set)."""
        slots, io, fast_inputs = self._input_slots, self._fast_io, self._fast_inputs
        for vr, value in zip(vrs, values, strict=True):
            slot = slots.get(vr)
            if slot is None:
                super().set_real([vr], [value])
                continue
            name, lo, hi, open_lo = slot
            if not (
                type(value) is float
                and -_INF < value < _INF
                and (lo < value if open_lo else lo <= value)
                and value <= hi
            ):
                self._set(name, value)  # the general rules (Var.check) and their message
                continue
            self._values[name] = self._in[name] = value
            if self._bad:
                self._bad.pop(name, None)
            if io is not None and name in fast_inputs:
                setattr(io, name, value)
            self._dirty = True

    def get_real(self, vrs: list[int]) -> list[float]:
        """fmi2GetReal: while the compiled step runs, outputs straight from its struct
        (one C-level pass); otherwise, or for other variables, by their getters."""
        if self._fast_out is not None and vrs:
            key = tuple(vrs)
            read = self._fast_reads.get(key)
            if read is None and all(vr in self._fast_vr for vr in key):
                read = self._fast_reads[key] = itemgetter(*(self._fast_vr[vr] for vr in key))
            if read is not None:
                return list(read(self._fast_out)) if len(key) > 1 else [read(self._fast_out)]
        return super().get_real(vrs)

    def _inputs(self) -> dict[str, float]:
        return dict(self._in)

    def _input_values(self) -> dict[str, Any]:
        """The inputs among _values (what _in caches)."""
        return {n: v for n, v in self._values.items() if self._causality[n] == fv.INPUT}

    def _to_fast(self, name: str, value: float) -> None:
        """An input's admissible value into the compiled step's struct, if it reads it."""
        if self._fast_io is not None and name in self._fast_inputs:
            setattr(self._fast_io, name, value)

    def _params(self) -> dict[str, Any]:
        return {n: v for n, v in self._values.items() if self._causality[n] == fv.PARAMETER}

    def _data_dir(self) -> Path | None:
        """This instance's copy of the vendored package (in its resources folder): where
        the law's generated data lies. FMUs of one content key share their imported
        modules in a process but not their resources. None outside an FMU."""
        if not self.resources:
            return None
        return Path(self.resources) / __package__.split(".")[0]

    def _error(self, msg: str) -> None:
        self.log(msg, Fmi2Status.error)

    def _discard(self, msg: str) -> bool:
        self.log(msg, Fmi2Status.discard)
        return False

    # ---- model -----------------------------------------------------------------------------
    def _build(self) -> bool:
        """Set the model up from the current parameters and inputs; False with a message."""
        if self._bad:
            for msg in self._bad.values():
                self._error(f"cannot initialise the model: {msg}")
            return False
        try:
            module = importlib.import_module(f"..{self.cfg.model_module}", __package__)
            model = module.build(
                self.cfg, self._params(), self._inputs(), self._time, self._data_dir()
            )
            out = self._collect(model.outputs())
        except Exception as e:  # an exception reaching pythonfmu would be fmi2Fatal
            self._error(f"cannot initialise the model: {_describe(e)}")
            return False
        self._model, self._model_params, self._out, self._dirty = model, self._params(), out, False
        self._fast_enable()
        return True

    # ---- the compiled step --------------------------------------------------------------
    def _fast_enable(self) -> None:
        """Use the model's compiled step if it has one (and the FMU no feedthrough)."""
        fast = getattr(self._model, "fast", None)
        self._fast = fast() if fast is not None and not self._model.feedthrough else None
        self._fast_out, self._fast_step, self._out_stale = None, None, False
        self._fast_io, self._fast_inputs, self._fast_reads = None, frozenset(), {}
        for name in _FMI_CALLS:  # the class's methods again
            self.__dict__.pop(name, None)
        self._fast_fmi = None
        reals = {
            vr: v for vr, v in self.vars.items() if v.name in self._out and isinstance(v, Real)
        }
        if self._fast is None:
            for v in reals.values():
                v.getter = self._getters[v.name]
            return
        self._fast_out, self._fast_step = self._fast.io.out, self._fast.stepper()
        self._fast_io, self._fast_inputs = self._fast.io, frozenset(self._fast.INPUTS)
        self._fast_index = {n: self._fast.index(n) for n in self._out}
        self._fast_vr = {vr: self._fast_index[v.name] for vr, v in reals.items()}
        for v in reals.values():  # read straight from the struct: no Python frame per value
            v.getter = partial(getitem, self._fast_out, self._fast_index[v.name])
        self._fast_push()
        # the per-step FMI calls in C where the extension is built (native/fmi.c): on the
        # instance, in place of the class's methods, to which they hand all else (a step
        # to the Python path: the binding has just tried the compiled one)
        cls = type(self)
        methods = (self._python_step, cls.set_real.__get__(self), cls.get_real.__get__(self))
        slots = [(vr, *slot) for vr, slot in self._input_slots.items()]
        outs = [(vr, v.name) for vr, v in reals.items()]
        self._fast_fmi = self._fast.bind_fmi(self, methods, TIME_RTOL, slots, outs)
        if self._fast_fmi is not None:
            for name in _FMI_CALLS:
                setattr(self, name, getattr(self._fast_fmi, name))

    def _fast_push(self) -> None:
        """After Python changed the model: its state, the inputs and the outputs (those
        of _out, as Python computed them) into the compiled step's struct."""
        self._fast.push()
        for n, v in self._in.items():
            self._to_fast(n, v)
        for n, i in self._fast_index.items():
            self._fast_out[i] = self._out[n]

    def _fast_pull(self) -> None:
        """Before Python reads or steps the model: the state and outputs back."""
        if self._fast is not None:
            self._fast.pull()
            self._sync_out()

    def _sync_out(self) -> None:
        if self._out_stale:
            self._out = {n: self._fast_out[i] for n, i in self._fast_index.items()}
            self._out_stale = False

    def _collect(self, outputs: dict[str, float]) -> dict[str, float]:
        """The declared outputs, checked finite."""
        out = {}
        for name in self._out:
            value = float(outputs[name])
            if not math.isfinite(value):
                raise FloatingPointError(f"output {name} = {value!r} is not finite")
            out[name] = value
        return out

    def _refresh(self) -> None:
        """Direct feedthrough: outputs for the current inputs (kept while inputs are bad)."""
        if any(self._causality.get(n) == fv.INPUT for n in self._bad):
            return
        snap = self._model.snapshot()
        try:
            self._model.evaluate(self._inputs())
            self._out = self._collect(self._model.outputs())
            self._dirty = False
        except Exception as e:
            self._model.restore(snap)
            self._error(f"outputs not updated for the new inputs: {_describe(e)}")

    # ---- FMI calls --------------------------------------------------------------------------
    def setup_experiment(
        self, start_time: float, stop_time: float | None = None, tolerance: float | None = None
    ) -> None:
        start = float(start_time)
        if math.isfinite(start):
            self._time = start
        else:
            self._error(f"startTime = {start_time!r} is invalid: must be finite; using 0")

    def exit_initialization_mode(self) -> None:
        self._build()

    def do_step(self, current_time: float, step_size: float) -> bool:
        step = self._fast_step
        if step is not None and not self._bad:  # the compiled step: _do_step's checks
            t, h = current_time, step_size
            if (
                0.0 < h < _INF
                and abs(t - self._time) <= TIME_RTOL * max(1.0, abs(t), h)
                and step(h) == 0
            ):
                self._time, self._dirty, self._out_stale = t + h, False, True
                return True
        return self._python_step(current_time, step_size)

    def _python_step(self, t: float, h: float) -> bool:
        try:
            return self._do_step(float(t), float(h))
        except Exception as e:  # never let an exception reach pythonfmu (fmi2Fatal)
            return self._discard(f"doStep discarded: {_describe(e)}")

    def _do_step(self, t: float, h: float) -> bool:
        if not (math.isfinite(h) and h > 0.0):
            return self._discard(
                f"communicationStepSize = {h!r} is invalid: must be > 0 and finite"
            )
        if not math.isfinite(t) or abs(t - self._time) > TIME_RTOL * max(1.0, abs(t), h):
            return self._discard(
                f"currentCommunicationPoint = {t!r} is invalid: must be the FMU's time "
                f"{self._time!r}"
            )
        if self._model is None and not self._build():
            return self._discard(f"doStep at t = {t!r} discarded: the model is not initialised")
        if self._bad:
            return self._discard(
                f"doStep at t = {t!r} discarded, state unchanged: " + "; ".join(self._bad.values())
            )
        self._fast_pull()
        snap = self._model.snapshot()
        try:
            note = self._model.step(h, self._inputs())
            out = self._collect(self._model.outputs())
        except Exception as e:
            self._model.restore(snap)
            if self._fast is not None:  # the stepper may have stepped the struct too
                self._fast_push()
            return self._discard(
                f"doStep at t = {t!r} with h = {h!r} discarded, state unchanged: {_describe(e)}"
            )
        self._out, self._time, self._dirty = out, t + h, False
        if self._fast is not None:
            self._fast_push()
        if note:
            self.log(note, Fmi2Status.warning)
        return True

    # ---- FMU state ---------------------------------------------------------------------------
    def _get_fmu_state(self) -> dict[str, Any]:
        self._fast_pull()
        model = None
        if self._model is not None:
            model = (dict(self._model_params), self._model.snapshot())
        return copy.deepcopy(
            {
                "time": self._time,
                "values": self._values,
                "bad": self._bad,
                "out": self._out,
                "dirty": self._dirty,
                "model": model,
            }
        )

    def _set_fmu_state(self, state: dict[str, Any] | state_bytes.Unreadable) -> None:
        if isinstance(state, state_bytes.Unreadable):
            msg = f"the FMU state given to setFMUstate is refused: {state.reason}"
            self._fast_pull()  # the state stays; doSteps are refused until a valid one
            self._bad[_STATE] = msg
            self._error(msg + " (state unchanged; doStep refused until a valid state is set)")
            return
        s = copy.deepcopy(state)
        self._time, self._values, self._bad = s["time"], s["values"], s["bad"]
        self._in = self._input_values()
        if s["model"] is None:
            self._model = self._model_params = None
        else:
            params, snap = s["model"]
            if self._model is None or params != self._model_params:
                module = importlib.import_module(f"..{self.cfg.model_module}", __package__)
                self._model = module.build(
                    self.cfg, params, self._inputs(), self._time, self._data_dir()
                )
                self._model_params = params
            self._model.restore(snap)
        self._out, self._dirty = s["out"], s["dirty"]
        self._fast_enable()

    @staticmethod
    def _fmu_state_to_bytes(state: dict[str, Any]) -> bytes:
        return state_bytes.dumps(state, _PACKAGE)

    @staticmethod
    def _fmu_state_from_bytes(data: bytes) -> dict[str, Any] | state_bytes.Unreadable:
        return state_bytes.loads(data, _PACKAGE)


def _describe(e: Exception) -> str:
    """The message of an exception, with its type unless it is a plain input error."""
    name = type(e).__name__
    return str(e) if name == "InputError" else f"{name}: {e}"
