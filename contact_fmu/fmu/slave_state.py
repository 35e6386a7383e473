"""The FMU state of the pythonfmu adapter: get, check whole, apply, serialise.

A mixin of ContactSlave (slave.py), which holds the instance this works on: its
CallState (``_call``), outputs, model and the hooks of the compiled path
(``_fast_pull``, ``_fast_enable``, ``_fast_push``). A state is the instance's calls'
state, its outputs and its model's snapshot; setting one is all or nothing
(``_set_fmu_state``): it is checked whole before any part is applied, and a state
refused leaves the instance as it was. The bytes are state_bytes's format, owned by
this FMU's package.
"""

from __future__ import annotations

import copy
import importlib
import math
from typing import Any

from . import messages as words
from . import state_bytes
from . import variables as fv
from .package_loader import PACKAGE as _PACKAGE  # the owner named in the state bytes

# the entry of CallState.bad that a refused FMU state holds (no variable has this name)
STATE = "FMU state"
# the fields of an FMU state (_get_fmu_state)
_STATE_FIELDS = frozenset({"time", "values", "bad", "out", "out_mu", "dirty", "model"})


class FmuStateMixin:
    """ContactSlave's FMU state calls (pythonfmu's _get_fmu_state, _set_fmu_state and
    the byte conversions)."""

    def _get_fmu_state(self) -> dict[str, Any]:
        self._fast_pull()
        model = None
        if self._model is not None:
            model = (dict(self._model_params), self._model.snapshot())
        return copy.deepcopy(
            {
                "time": self._call.time,
                "values": self._call.values,
                "bad": self._call.bad,
                "out": self._out,
                "out_mu": self._out_mu,
                "dirty": self._call.dirty,
                "model": model,
            }
        )

    def _set_fmu_state(self, state: dict[str, Any] | state_bytes.Unreadable) -> None:
        """All or nothing: the state is checked whole (its fields, every value against
        its declaration, the model rebuilt and restored, the outputs finite and within
        Coulomb's bound) before any part of it is applied; a state refused answers
        fmi2Error and leaves the instance as it was."""
        self._fast_pull()
        try:
            problem = self._apply_state(state)
        except Exception as e:  # whatever a damaged state makes fail: refused, not Fatal
            problem = describe(e)
        if problem is None:
            self._call.bad.pop(STATE, None)
            return
        msg = words.STATE_REFUSED(why=problem)
        if self._cell is None:  # no fmi2Error to answer with: refuse the steps instead
            self._call.bad[STATE] = msg
            msg += words.STATE_HELD_NOTE()
        self._error(words.STATE_UNCHANGED(refused=msg))

    def _apply_state(self, state: Any) -> str | None:
        """Apply ``state`` if it is a whole, admissible state of this FMU; else the
        reason, with nothing applied."""
        if isinstance(state, state_bytes.Unreadable):
            return state.reason
        if isinstance(state, bytes):  # the C core's (slave_core.py): not this path's
            return words.STATE_OF_CORE()
        if not isinstance(state, dict) or set(state) != _STATE_FIELDS:
            return words.STATE_FIELDS()
        t, values, out, dirty = state["time"], state["values"], state["out"], state["dirty"]
        if type(t) is not float or not math.isfinite(t):
            return words.STATE_TIME(time=t)
        if type(dirty) is not bool:
            return words.STATE_FLAG(flag=dirty)
        if not isinstance(values, dict) or set(values) != set(self._call.values):
            return words.STATE_VARIABLES()
        bad = {}
        for n, v in values.items():
            string = self._vars[n].type == "String"
            if isinstance(v, str) != string or isinstance(v, bool):
                kind = "string" if string else "number"
                return words.STATE_VALUE_TYPE(name=n, value=v, kind=kind)
            if (problem := self.cfg.check(n, v)) is not None:
                bad[n] = words.INVALID(name=n, value=v, requirement=problem)
        recorded = state["bad"]
        if not isinstance(recorded, dict):
            return words.STATE_RECORD_TYPE(record=recorded)
        for n, v in values.items():  # the first value recorded otherwise than it is
            if (n in bad) != (n in recorded):
                one = bad[n] if n in bad else words.STATE_NAMED(name=n, value=v)
                was = "invalid" if n in recorded else "valid"
                return words.STATE_RECORD(value=one, recorded=was)
        if extra := sorted(set(recorded) - {STATE} - set(values), key=repr):
            one = words.STATE_NOT_A_VARIABLE(name=extra[0])
            return words.STATE_RECORD(value=one, recorded="invalid")
        if not isinstance(out, dict) or set(out) != set(self._out):
            return words.STATE_OUTPUTS()
        for n, v in out.items():
            if type(v) is not float or not math.isfinite(v):
                return words.STATE_OUTPUT(name=n, value=v)
        out_mu = state["out_mu"]
        if out_mu is not None and (type(out_mu) is not float or not 0.0 < out_mu < math.inf):
            return words.STATE_OUT_MU(mu=out_mu)
        model, params = None, None
        if state["model"] is not None:
            model, params = self._state_model(state["model"], values, bad, t)
            if isinstance(model, str):
                return model
            # outputs taken after mu was tuned, before the next step: the earlier mu's bound
            mu = values.get("mu")
            if isinstance(mu, float) and out_mu is not None:
                mu = max(mu, out_mu)
            bound = _coulomb_excess(out, mu, getattr(model, "P", None))
            if bound is not None:
                self._restore_own(model)
                return bound
        # checked: apply
        self._call.time, self._call.values, self._call.bad = t, copy.deepcopy(values), bad
        self._call.inputs = self._input_values()
        self._model, self._model_params = model, params
        self._out, self._call.dirty, self._out_mu = dict(out), dirty, out_mu
        self._fast_enable()
        return None

    def _state_model(
        self, saved: Any, values: dict[str, Any], bad: dict[str, str], t: float
    ) -> tuple[Any, Any]:
        """(model at the saved snapshot, its parameters), without touching this
        instance's model unless it is the one to restore (then undone on failure); or
        (reason, None)."""
        if not isinstance(saved, tuple | list) or len(saved) != 2:
            return words.STATE_MODEL_PART(), None
        params, snap = saved
        own = {n: v for n, v in values.items() if self._causality[n] == fv.PARAMETER}
        if not isinstance(params, dict) or params != own or any(n in bad for n in own):
            return words.STATE_PARAMS(value=_first_differing(params, own, bad)), None
        if self._model is not None and params == self._model_params:
            model = self._model
            self._undo = model.snapshot()
        else:  # built at start values where the state holds an invalid input
            inputs = {
                n: (self.cfg.start(self._vars[n]) if n in bad else v)
                for n, v in values.items()
                if self._causality[n] == fv.INPUT
            }
            module = importlib.import_module(f"..{self.cfg.model_module}", __package__)
            model = module.build(self.cfg, dict(params), inputs, t, self._data_dir())
            self._undo = None
        try:
            model.restore(copy.deepcopy(snap))
            self._collect(model.outputs())
        except Exception as e:
            self._restore_own(model)
            return words.STATE_MODEL(why=describe(e)), None
        return model, dict(params)

    def _restore_own(self, model: Any) -> None:
        """Undo a refused state's restore into this instance's own model."""
        if model is self._model and self._undo is not None:
            model.restore(self._undo)
            if self._fast is not None:
                self._fast_push()

    @staticmethod
    def _fmu_state_to_bytes(state: dict[str, Any] | bytes) -> bytes:
        """The Python path's state in state_bytes's format; the C core's state is its
        bytes already (slave_core.py)."""
        if isinstance(state, bytes):
            return state
        return state_bytes.dumps(state, _PACKAGE)

    @staticmethod
    def _fmu_state_from_bytes(data: bytes) -> dict[str, Any] | state_bytes.Unreadable | bytes:
        """The Python path's state, or Unreadable; bytes of the C core as they are
        (checked by the instance that sets them: the core, or refused by the Python
        path naming the core)."""
        if bytes(data[: len(state_bytes.CORE_MAGIC)]) == state_bytes.CORE_MAGIC:
            return bytes(data)
        return state_bytes.loads(data, _PACKAGE)


def _first_differing(params: Any, own: dict[str, Any], bad: dict[str, str]) -> str:
    """The first parameter held invalid, or whose model value differs from the state's
    (as the native FMU names it: its refusal, or NAME = VALUE)."""
    for n, v in own.items():
        if n in bad:
            return bad[n]
        if not isinstance(params, dict) or n not in params or params[n] != v:
            return words.STATE_NAMED(name=n, value=v)
    return words.STATE_NAMED(name="parameters", value=params)


def _coulomb_excess(out: dict[str, float], mu: Any, P: Any) -> str | None:
    """Why outputs break Coulomb's bound abs(T) <= mu P (rounding allowed), or None."""
    if "Tx" not in out or not isinstance(P, float) or not isinstance(mu, float):
        return None
    T = math.hypot(out["Tx"], out.get("Ty", 0.0))
    if T <= mu * P * (1.0 + 1e-12):
        return None
    return words.STATE_COULOMB(T=T, muP=mu * P)


def describe(e: Exception) -> str:
    """The message of an exception, with its type unless it is a plain input error."""
    name = type(e).__name__
    return str(e) if name == "InputError" else f"{name}: {e}"
