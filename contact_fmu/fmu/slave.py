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
  Tunable parameters (``Var.tunable``: mu) go into the running model (``tune``) and
  apply from the next step (a force element's outputs follow at once).

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

import ctypes
import importlib
import math
import sys
from operator import itemgetter
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

from . import messages as words
from . import slave_core
from . import variables as fv
from .call_state import TIME_RTOL, CallState
from .config import ModelConfig
from .package_loader import PACKAGE as _PACKAGE
from .package_loader import load_package
from .slave_fast import FMI_CALLS, FastPathMixin
from .slave_state import FmuStateMixin, describe

# The value reference through which the FMU's binary (pythonfmu_shim.c, CF_CELL_VR)
# hands over the address of its status cell; no variable has it.
CELL_VR = 2147483647
_INF = math.inf

_CAUSALITY = {
    fv.PARAMETER: Fmi2Causality.parameter,
    fv.INPUT: Fmi2Causality.input,
    fv.OUTPUT: Fmi2Causality.output,
}
_TYPES = {"Real": Real, "Integer": Integer, "String": String}
# the String parameters' choices (integrator.RollingBody checks them at set-up; refused
# at once here, as by the native FMU, in RollingBody's words)
_CHOICES = {
    "method": (("full", "quasistationary"), words.METHOD_CHOICES()),
    "scheme": (("lobatto3c", "sdirk2"), words.SCHEME_CHOICES()),
}


class ContactSlave(FastPathMixin, FmuStateMixin, Fmi2Slave):
    """Rolling/sliding contact after Spector & Batra (1995); the model follows CONFIG."""

    CONFIG: ClassVar[dict[str, Any]] = {}
    CELL_VR: ClassVar[int] = CELL_VR
    author = "contact_fmu"
    license = "MIT"

    def __init__(self, **kwargs: Any) -> None:
        # the shim's status cell (set through CELL_VR); None under pythonfmu's binary alone
        self._cell: Any = None
        super().__init__(**kwargs)
        load_package(self.resources)
        cfg = ModelConfig.from_dict(self.CONFIG)
        self.cfg = cfg
        self.description = cfg.description or f"Spector & Batra (1995) contact, {cfg.mode} mode"
        if cfg.experiment is not None:
            start, stop, step = cfg.experiment
            self.default_experiment = DefaultExperiment(start, stop, step_size=step)
        self._vars = {v.name: v for v in cfg.variables}
        self._causality = {n: v.causality[cfg.mode] for n, v in self._vars.items()}
        # what every FMI call reads or changes, shared with the compiled calls (fmi.c):
        # parameter and input values; the inputs also by themselves, the argument of
        # every step (kept in step with values by _set); the values held bad; the time
        self._call = CallState(
            values={
                n: cfg.start(v) for n, v in self._vars.items() if self._causality[n] != fv.OUTPUT
            }
        )
        self._call.inputs = self._input_values()
        self._out: dict[str, float] = {
            n: float(v.start) for n, v in self._vars.items() if self._causality[n] == fv.OUTPUT
        }
        # the mu the outputs were computed with (a tuned mu applies from the next step)
        self._out_mu: float | None = self._call.values.get("mu")
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
        self._getters: dict[str, Any] = {}  # the Python getters of the Real outputs
        self._init_problem: str | None = None  # why exitInitializationMode failed
        self._reading = False  # in a get call, whose outputs are refreshed (_read)
        self._terminated = False
        self._undo: Any = None  # this model's snapshot while a state is being set
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
        # the FMU's C core, where it carries one: every FMI call goes to it (slave_core.py)
        self._core_calls: slave_core.CoreCalls | None = None
        found = slave_core.find(self.resources)
        if found is not None:
            try:
                self._core_calls = slave_core.CoreCalls(self, *found)
                self._core_calls.attach(self)
            except RuntimeError as e:  # it cannot start here: the Python path runs
                self.log(words.CORE_UNUSABLE(why=e), Fmi2Status.warning)

    # ---- registration ------------------------------------------------------------------
    def _fmi_variable(self, v: fv.Var) -> Any:
        c = self._causality[v.name]
        variability = Fmi2Variability[fv.variability(v, self.cfg.mode)]
        initial = Fmi2Initial.calculated if c == fv.OUTPUT else None
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

    # ---- statuses --------------------------------------------------------------------------
    def log(
        self,
        msg: str,
        status: Fmi2Status = Fmi2Status.ok,
        category: str | None = None,
        debug: Any = None,
    ) -> None:
        """pythonfmu's log, and the call's status raised to the message's in the shim's
        cell: the FMI call answers the worst status it logged (fmi2Error for an error)."""
        super().log(msg, status, category)
        cell = self._cell
        if cell is not None and status.value > cell.value:
            cell.value = status.value

    def _log_status(self, status: int, msg: str, category: str | None = None) -> None:
        """``log`` with the status as a number (FMI 2.0's: slave_core.py's core)."""
        self.log(msg, Fmi2Status(status), category)

    def _refuse(self, msg: str) -> None:
        """An error the current call must answer: fmi2Error through the shim; under
        pythonfmu's binary alone (no shim: Windows, or built without a C compiler) an
        exception, which pythonfmu answers with fmi2Fatal. Never fmi2OK."""
        self._error(msg)
        if self._cell is None:
            raise RuntimeError(msg)

    def _guarded(self, call: str, method: Any, vrs: list[int], *args: Any) -> Any:
        """A getter or setter of pythonfmu for value references that may not be of this
        FMU or of that type: an error naming them instead of pythonfmu's fmi2Fatal."""
        try:
            return method(vrs, *args)
        except (KeyError, TypeError) as e:
            self._refuse(words.GUARDED(call=call, vrs=list(vrs), why=describe(e)))
            return [0] * len(vrs) if call.startswith("get") else None

    def _take_cell(self, text: str) -> None:
        """The shim's cell, from its text "status cell <address>" (pythonfmu_shim.c)."""
        self._cell = ctypes.c_int.from_address(int(text.rsplit(" ", 1)[1], 16))

    def set_string(self, vrs: list[int], values: list[str]) -> None:
        if len(vrs) == 1 and vrs[0] == CELL_VR:  # the shim's cell (pythonfmu_shim.c)
            if values[0] != slave_core.RELEASE:  # nothing to free on the Python path
                self._take_cell(values[0])
            return
        self._guarded("setString", super().set_string, vrs, values)

    def set_integer(self, vrs: list[int], values: list[int]) -> None:
        self._guarded("setInteger", super().set_integer, vrs, values)

    def set_boolean(self, vrs: list[int], values: list[bool]) -> None:
        self._guarded("setBoolean", super().set_boolean, vrs, values)

    def get_integer(self, vrs: list[int]) -> list[int]:
        return self._read("getInteger", super().get_integer, vrs)

    def get_boolean(self, vrs: list[int]) -> list[bool]:
        return self._guarded("getBoolean", super().get_boolean, vrs)

    def get_string(self, vrs: list[int]) -> list[str]:
        out = self._guarded("getString", super().get_string, vrs)
        return [str(v) for v in out]

    # ---- get/set -------------------------------------------------------------------------
    def _read(self, call: str, method: Any, vrs: list[int]) -> Any:
        """A get call by pythonfmu's getters: direct feedthrough's outputs, where the call
        reads one, refreshed once for the call, not per value (a refusal is logged once,
        as by the native FMU)."""
        if self._stale() and any(
            vr in self.vars and self._causality[self.vars[vr].name] == fv.OUTPUT for vr in vrs
        ):
            self._refresh()
        self._reading = True
        try:
            return self._guarded(call, method, vrs)
        finally:
            self._reading = False

    def _stale(self) -> bool:
        """Outputs to refresh before a value is read outside a get call's own refresh."""
        return (
            self._call.dirty
            and not self._reading
            and self._model is not None
            and self._model.feedthrough
        )

    def _real_output(self, name: str) -> float:
        if self._stale():
            self._refresh()
        return self._out[name]  # floats, checked finite by _collect

    def _get(self, name: str) -> Any:
        var = self._vars[name]
        if self._causality[name] == fv.OUTPUT:
            self._sync_out()
            if self._stale():
                self._refresh()
            value = self._out[name]
        else:
            value = self._call.values[name]
            if name in self._call.bad:  # the value set was refused: not a value to use
                self._refuse(words.HELD_AT_GET(name=name, invalid=self._call.bad[name]))
        if var.type == "Integer":
            return int(value)
        if var.type == "String":
            return str(value)
        return float(value)

    def _set(self, name: str, value: Any) -> None:
        c = self._causality[name]
        if c == fv.OUTPUT:
            self._error(words.SET_OUTPUT(name=name, value=value))
            return
        var = self._vars[name]
        if c == fv.PARAMETER and self._model is not None and not var.tunable:
            self._error(words.SET_FIXED(name=name, value=value, now=self._call.values[name]))
            return
        problem = self.cfg.check(name, value)
        if problem is None and name in _CHOICES and value not in _CHOICES[name][0]:
            problem = _CHOICES[name][1]
        if c == fv.PARAMETER and self._model is not None:
            self._fast_pull()  # the outputs of the mu they were computed with (_out_mu)
        self._call.values[name] = (
            value if var.type == "String" or problem == "a number" else float(value)
        )
        if c == fv.INPUT:
            self._call.inputs[name] = self._call.values[name]
            if problem is None:
                self._to_fast(name, self._call.inputs[name])
        if problem is None:
            if self._call.bad:
                self._call.bad.pop(name, None)
        else:
            msg = words.INVALID(name=name, value=value, requirement=problem)
            self._call.bad[name] = msg
            self.log(words.HELD(invalid=msg, api=words.API), Fmi2Status.error)
        if c == fv.INPUT:
            self._call.dirty = True
        elif problem is None and self._model is not None:  # a tunable parameter
            self._tune(name, self._call.values[name])

    def _tune(self, name: str, value: Any) -> None:
        """A tunable parameter's new value into the running model (from the next step;
        a force element's outputs are recomputed); refused, nothing changed, if the model
        does not take it."""
        self._fast_pull()
        snap = self._model.snapshot()
        try:
            self._model.tune({name: value})
        except Exception as e:
            self._model.restore(snap)
            self._call.values[name] = self._model_params[name]
            self._refuse(words.TUNE_REFUSED(name=name, value=value, why=describe(e)))
            return
        finally:
            if self._fast is not None:
                self._fast_push()
        self._model_params = {**self._model_params, name: value}
        self._call.dirty = True

    def set_real(self, vrs: list[int], values: list[float]) -> None:
        """fmi2SetReal, the per-step call: a Real input's float is tested here against
        its declared range (Var.check's rules) and stored; anything else (not a float,
        out of range, a parameter, an output) goes through its setter (_set)."""
        slots, io, fast_inputs = self._input_slots, self._fast_io, self._fast_inputs
        for vr, value in zip(vrs, values, strict=True):
            slot = slots.get(vr)
            if slot is None:
                self._guarded("setReal", super().set_real, [vr], [value])
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
            self._call.values[name] = self._call.inputs[name] = value
            if self._call.bad:
                self._call.bad.pop(name, None)
            if io is not None and name in fast_inputs:
                setattr(io, name, value)
            self._call.dirty = True

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
        return self._read("getReal", super().get_real, vrs)

    def _inputs(self) -> dict[str, float]:
        return dict(self._call.inputs)

    def _input_values(self) -> dict[str, Any]:
        """The inputs among _values (what _in caches)."""
        return {n: v for n, v in self._call.values.items() if self._causality[n] == fv.INPUT}

    def _to_fast(self, name: str, value: float) -> None:
        """An input's admissible value into the compiled step's struct, if it reads it."""
        if self._fast_io is not None and name in self._fast_inputs:
            setattr(self._fast_io, name, value)

    def _params(self) -> dict[str, Any]:
        return {n: v for n, v in self._call.values.items() if self._causality[n] == fv.PARAMETER}

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
        if self._call.bad:
            for msg in self._call.bad.values():
                self._error(words.CANNOT_INITIALISE(why=msg))
            return False
        try:
            module = importlib.import_module(f"..{self.cfg.model_module}", __package__)
            model = module.build(
                self.cfg, self._params(), self._inputs(), self._call.time, self._data_dir()
            )
            out = self._collect(model.outputs())
        except Exception as e:  # an exception reaching pythonfmu would be fmi2Fatal
            self._error(words.CANNOT_INITIALISE(why=describe(e)))
            return False
        self._model, self._model_params, self._out = model, self._params(), out
        self._call.dirty = False
        self._out_mu = self._call.values.get("mu")
        self._fast_enable()
        return True

    def _collect(self, outputs: dict[str, float]) -> dict[str, float]:
        """The declared outputs, checked finite."""
        out = {}
        for name in self._out:
            value = float(outputs[name])
            if not math.isfinite(value):
                raise FloatingPointError(words.OUTPUT_NOT_FINITE(name=name, value=value))
            out[name] = value
        return out

    def _refresh(self) -> None:
        """Direct feedthrough: outputs for the current inputs. Where they cannot be had
        (an input held invalid, a failing evaluation) the call answers fmi2Error: the
        outputs kept are those of the last good inputs, never served as fmi2OK."""
        bad = [m for n, m in self._call.bad.items() if self._causality.get(n) == fv.INPUT]
        if bad:
            self._refuse(words.NO_OUTPUTS(why="; ".join(bad)))
            return
        snap = self._model.snapshot()
        try:
            self._model.evaluate(self._inputs())
            self._out = self._collect(self._model.outputs())
            self._out_mu = self._call.values.get("mu")
            self._call.dirty = False
        except Exception as e:
            self._model.restore(snap)
            self._refuse(words.NO_OUTPUTS(why=describe(e)))

    # ---- FMI calls --------------------------------------------------------------------------
    def setup_experiment(
        self, start_time: float, stop_time: float | None = None, tolerance: float | None = None
    ) -> None:
        start = float(start_time)
        if math.isfinite(start):
            self._call.time = start
        else:
            self._error(words.START_TIME(start=start_time))

    def exit_initialization_mode(self) -> None:
        """The model set up from the parameters and inputs; a model that cannot start
        answers fmi2Error (with the reasons logged) so that the importer stops."""
        self._init_problem = None
        built = self._build()
        # the compiled parts of the model (native, where the model imports it: not
        # imported here, so that FMUs without compiled parts do not carry it), loaded now
        # (a contact law loads its library at its first evaluation with spin) so that
        # what cannot load is reported here
        native = sys.modules.get(f"{_PACKAGE}.native")
        if native is not None:
            native.library()
        for problem in getattr(native, "PROBLEMS", ()):
            self.log(problem, Fmi2Status.warning)
        if not built:
            self._init_problem = "; ".join(self._call.bad.values()) or words.SEE_ABOVE()
            self._refuse(words.CANNOT_START(why=self._init_problem))

    def terminate(self) -> None:
        """No step after this: the compiled step's calls give way to the Python ones,
        which refuse it."""
        self._terminated = True
        self._fast_step = None
        for name in FMI_CALLS:
            self.__dict__.pop(name, None)

    def do_step(self, current_time: float, step_size: float) -> bool:
        step = self._fast_step
        if step is not None and not self._call.bad:  # the compiled step: _do_step's checks
            t, h = current_time, step_size
            if (
                0.0 < h < _INF
                and -_INF < t < _INF
                and abs(t - self._call.time) <= TIME_RTOL * max(abs(t), abs(self._call.time))
                and step(h) == 0
            ):
                self._call.time, self._call.dirty, self._call.out_stale = t + h, False, True
                return True
        return self._python_step(current_time, step_size)

    def _python_step(self, t: float, h: float) -> bool:
        try:
            return self._do_step(float(t), float(h))
        except Exception as e:  # never let an exception reach pythonfmu (fmi2Fatal)
            return self._discard(words.STEP_FAILED(why=describe(e)))

    def _do_step(self, t: float, h: float) -> bool:
        if self._terminated:
            terminate = words.CALL_NAMES["TERMINATE"][0]
            self._error(words.STEP_AFTER_TERMINATE(t=t, api=words.API, call=terminate))
            return False
        if self._model is None:
            if why := self._init_problem:
                self._error(words.STEP_AFTER_FAILED_INIT(t=t, api=words.API, why=why))
            else:
                self._error(words.STEP_BEFORE_INIT(t=t, api=words.API))
            return False
        if not (math.isfinite(h) and h > 0.0):
            return self._discard(words.STEP_SIZE(h=h))
        now = self._call.time
        if not math.isfinite(t) or abs(t - now) > TIME_RTOL * max(abs(t), abs(now)):
            return self._discard(words.STEP_TIME(t=t, time=now))
        if self._call.bad:
            return self._discard(words.STEP_HELD(t=t, why="; ".join(self._call.bad.values())))
        self._fast_pull()
        snap = self._model.snapshot()
        try:
            note = self._model.step(h, self._inputs())
            out = self._collect(self._model.outputs())
        except Exception as e:
            self._model.restore(snap)
            if self._fast is not None:  # the stepper may have stepped the struct too
                self._fast_push()
            return self._discard(words.STEP_DISCARDED(t=t, h=h, why=describe(e)))
        self._out, self._call.time, self._call.dirty = out, t + h, False
        self._out_mu = self._call.values.get("mu")
        if self._fast is not None:
            self._fast_push()
        if note:
            self.log(note, Fmi2Status.warning)
        return True
