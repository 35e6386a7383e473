"""The fuzz worker: one FMU loaded once, runs of FMI calls executed on request.

Started by ``pool.Worker`` as ``python worker.py FMU`` (only the standard library and
fmpy: nothing of the project, so that what it measures is the FMU as a host sees it).
Protocol: one JSON object per line on stdin, a run ``{"ops": [...]}``; for each call of
the run one JSON line on the protocol pipe, ``{"i": op index, "call": name, "status":
int, "log": [[status, message], ...], ...}``, then ``{"done": true}``. The FMI functions
are called through fmpy's ctypes bindings directly (fmpy's wrappers raise above
fmi2Warning and hide OK from Warning). The process's fd 1 goes to stderr, so that
nothing the FMU prints can corrupt the protocol; faulthandler writes the Python stack
of a crash there.

Ops (``"inst"`` 0 or 1, the instance; each instance is instantiated at the start of a
run and freed at its end):

- ``setup`` (t0), ``enter``, ``exit``, ``terminate``, ``reset``
- ``set`` (name, value): fmi2SetReal/Integer/String by the variable's type
- ``get``: fmi2GetReal of every Real variable (and GetInteger of the Integers)
- ``step`` (h, t: null for the instance's time, else an offset added to it): getReal
  before, fmi2DoStep, getReal after
- ``getstate``/``setstate``/``freestate`` (slot), ``setfreed`` (slot: set a state by its
  address after it was freed)
- ``serialize`` (slot, buf), ``deserialize`` (buf, slot, damage: null, ["flip", pos,
  xor], ["truncate", length] with pos/length as fractions of the size)
- ``craft`` (buf, edit): the bytes' pickled state rewritten (outputs NaN, a value, ...)
- ``roundtrip`` (h, k): getstate, k steps (get after each), setstate, k steps again
"""

from __future__ import annotations

import faulthandler
import json
import math
import os
import pickle
import resource
import shutil
import sys
import tempfile
from ctypes import (
    byref,
    c_char_p,
    c_double,
    c_int,
    c_size_t,
    c_uint,
    c_void_p,
    create_string_buffer,
)

import fmpy
from fmpy.fmi2 import (
    FMU2Slave,
    fmi2CallbackAllocateMemoryTYPE,
    fmi2CallbackFreeMemoryTYPE,
    fmi2CallbackFunctions,
    fmi2CallbackLoggerTYPE,
    fmi2FMUstate,
)

PROTO = None  # the protocol's file (the original stdout)
FATAL = 4


class FatalStatusError(Exception):
    """A call answered fmi2Fatal: the run ends and the worker with it."""


def emit(obj: dict) -> None:
    PROTO.write(json.dumps(obj) + "\n")
    PROTO.flush()


class Host:
    def __init__(self, fmu: str) -> None:
        self.dir = tempfile.mkdtemp(prefix="fuzz-fmu-")
        fmpy.extract(fmu, self.dir)
        self.md = fmpy.read_model_description(self.dir)
        self.vars = {v.name: v for v in self.md.modelVariables}
        self.reals = [v for v in self.md.modelVariables if v.type == "Real"]
        self.ints = [v for v in self.md.modelVariables if v.type == "Integer"]
        self.log: list[list] = []
        cb = fmi2CallbackFunctions()
        cb.logger = fmi2CallbackLoggerTYPE(self._log)
        cb.allocateMemory = fmi2CallbackAllocateMemoryTYPE(fmpy.calloc)
        cb.freeMemory = fmi2CallbackFreeMemoryTYPE(fmpy.free)
        from fmpy.logging import addLoggerProxy

        addLoggerProxy(byref(cb))
        self.callbacks = cb
        self.slaves = [
            FMU2Slave(
                guid=self.md.guid,
                unzipDirectory=self.dir,
                modelIdentifier=self.md.coSimulation.modelIdentifier,
                instanceName=f"fuzz{i}",
            )
            for i in range(2)
        ]
        f = self.slaves[0]._functions
        self.f = f
        self.package = None  # the FMU's package name (from its state bytes)

    def _log(self, env, instance, status, category, message) -> None:
        self.log.append([int(status), message.decode(errors="replace") if message else ""])

    # ---- one run ---------------------------------------------------------------------
    def run(self, ops: list[dict]) -> None:
        comps: dict[int, int] = {}
        self.times = {0: 0.0, 1: 0.0}
        self.states: dict[int, tuple[int, object, float]] = {}  # slot -> (inst, state, t)
        self.freed: dict[int, int] = {}  # slot -> address of a freed state
        self.bufs: dict[int, tuple[bytes, float]] = {}
        self.comps = comps
        for inst in sorted({int(op.get("inst", 0)) for op in ops} | {0}):
            s = self.slaves[inst]
            s.instantiate(callbacks=self.callbacks, loggingOn=True)
            comps[inst] = s.component
            self.record(-1, "instantiate", 0 if s.component else 3, inst=inst)
        for i, op in enumerate(ops):
            getattr(self, "op_" + op["op"])(i, op, comps[int(op.get("inst", 0))])
        for slot, (inst, state, _t) in self.states.items():  # what the run left held
            if state.value and slot not in self.freed:
                st = self.f["fmi2FreeFMUstate"](comps[inst], byref(state))
                self.record(len(ops), "freeFMUstate", st, inst=inst)
        for inst, c in comps.items():
            self.f["fmi2FreeInstance"](c)
            self.record(len(ops), "freeInstance", 0, inst=inst)

    def record(self, i: int, call: str, status: int, **extra) -> None:
        emit({"i": i, "call": call, "status": int(status), "log": self.log, **extra})
        self.log = []
        if status >= FATAL:  # the instance may not be called again, not even freed
            raise FatalStatusError

    # ---- calls -----------------------------------------------------------------------
    def op_setup(self, i, op, c):
        t0 = float(op.get("t0", 0.0))
        st = self.f["fmi2SetupExperiment"](c, 0, 0.0, t0, 0, 0.0)
        self.times[int(op.get("inst", 0))] = t0
        self.record(i, "setupExperiment", st)

    def op_enter(self, i, op, c):
        self.record(i, "enterInitializationMode", self.f["fmi2EnterInitializationMode"](c))

    def op_exit(self, i, op, c):
        self.record(i, "exitInitializationMode", self.f["fmi2ExitInitializationMode"](c))

    def op_terminate(self, i, op, c):
        self.record(i, "terminate", self.f["fmi2Terminate"](c))

    def op_reset(self, i, op, c):
        st = self.f["fmi2Reset"](c)
        if st <= 1:  # back to the instantiated state (pythonfmu makes the model anew)
            self.times[int(op.get("inst", 0))] = 0.0
        self.record(i, "reset", st)

    def op_set(self, i, op, c):
        v = self.vars[op["name"]]
        vr = (c_uint * 1)(v.valueReference)
        if v.type == "Real":
            st = self.f["fmi2SetReal"](c, vr, 1, (c_double * 1)(float(op["value"])))
        elif v.type == "Integer":
            x = op["value"]
            x = int(x) if isinstance(x, int) or (math.isfinite(x) and abs(x) < 2**31) else 0
            st = self.f["fmi2SetInteger"](c, vr, 1, (c_int * 1)(x))
        else:
            st = self.f["fmi2SetString"](c, vr, 1, (c_char_p * 1)(str(op["value"]).encode()))
        self.record(i, "set" + v.type, st, name=op["name"])

    def _get(self, c) -> tuple[int, dict]:
        n = len(self.reals)
        vr = (c_uint * n)(*[v.valueReference for v in self.reals])
        out = (c_double * n)()
        st = self.f["fmi2GetReal"](c, vr, n, out)
        values = {v.name: out[k] for k, v in enumerate(self.reals)}
        if self.ints and st <= 1:
            m = len(self.ints)
            ivr = (c_uint * m)(*[v.valueReference for v in self.ints])
            iout = (c_int * m)()
            st = max(st, self.f["fmi2GetInteger"](c, ivr, m, iout))
            values.update({v.name: iout[k] for k, v in enumerate(self.ints)})
        return st, values

    def op_get(self, i, op, c):
        st, values = self._get(c)
        self.record(i, "getReal", st, values=_enc(values))

    def _step(self, i, op, c, call="doStep"):
        inst = int(op.get("inst", 0))
        st0, before = self._get(c)
        self.record(i, "getReal", st0, values=_enc(before), phase="before")
        h = float(op["h"])
        t = self.times[inst] + (0.0 if op.get("t") is None else float(op["t"]))
        st = self.f["fmi2DoStep"](c, t, h, 1)
        if st <= 1:
            self.times[inst] = t + h
        self.record(i, call, st, t=t, h=h)
        st1, after = self._get(c)
        self.record(i, "getReal", st1, values=_enc(after), phase="after")
        return st, st1, after

    def op_step(self, i, op, c):
        self._step(i, op, c)

    def op_getstate(self, i, op, c):
        state = fmi2FMUstate()
        st = self.f["fmi2GetFMUstate"](c, byref(state))
        inst = int(op.get("inst", 0))
        self.states[op["slot"]] = (inst, state, self.times[inst])
        self.freed.pop(op["slot"], None)
        self.record(i, "getFMUstate", st)

    def op_setstate(self, i, op, c):
        entry = self.states.get(op["slot"])
        if entry is None:
            return self.record(i, "setFMUstate", 0, skipped="no such state")
        st = self.f["fmi2SetFMUstate"](c, entry[1])
        if st <= 1:
            self.times[int(op.get("inst", 0))] = entry[2]
        self.record(i, "setFMUstate", st)

    def op_freestate(self, i, op, c):
        entry = self.states.get(op["slot"])
        if entry is None:
            return self.record(i, "freeFMUstate", 0, skipped="no such state")
        addr = entry[1].value
        st = self.f["fmi2FreeFMUstate"](self.comps[entry[0]], byref(entry[1]))
        if addr:
            self.freed[op["slot"]] = addr
        # the address the handle holds afterwards: 0 if the FMU cleared it (a second
        # free is then a free of NULL), else a dangling pointer
        self.record(i, "freeFMUstate", st, before=addr or 0, after=entry[1].value or 0)

    def op_setfreed(self, i, op, c):
        addr = self.freed.get(op["slot"])
        if addr is None:
            return self.record(i, "setFMUstate", 0, skipped="no freed state")
        st = self.f["fmi2SetFMUstate"](c, c_void_p(addr))
        self.record(i, "setFMUstate", st, freed=True)

    def op_serialize(self, i, op, c):
        entry = self.states.get(op["slot"])
        if entry is None:
            return self.record(i, "serializeFMUstate", 0, skipped="no such state")
        size = c_size_t()
        st = self.f["fmi2SerializedFMUstateSize"](c, entry[1], byref(size))
        if st <= 1:
            buf = create_string_buffer(size.value)
            st = max(st, self.f["fmi2SerializeFMUstate"](c, entry[1], buf, size))
            self.bufs[op["buf"]] = (buf.raw, entry[2])
        self.record(i, "serializeFMUstate", st, size=size.value)

    def op_deserialize(self, i, op, c):
        entry = self.bufs.get(op["buf"])
        if entry is None:
            return self.record(i, "deSerializeFMUstate", 0, skipped="no such bytes")
        data, t = entry
        damage = op.get("damage")
        if damage and data:
            if damage[0] == "flip":
                pos = min(int(damage[1] * len(data)), len(data) - 1)
                data = data[:pos] + bytes([data[pos] ^ (int(damage[2]) or 1)]) + data[pos + 1 :]
            elif damage[0] == "truncate":
                data = data[: int(damage[1] * len(data))]
        state = fmi2FMUstate()
        buf = create_string_buffer(data, size=len(data))
        st = self.f["fmi2DeSerializeFMUstate"](c, buf, len(data), byref(state))
        self.states[op["slot"]] = (int(op.get("inst", 0)), state, t)
        self.freed.pop(op["slot"], None)
        self.record(i, "deSerializeFMUstate", st, size=len(data))

    def op_craft(self, i, op, c):
        """Rewrite the state inside serialized bytes: what a master (or a bit rot) could
        hand back that the FMU never wrote."""
        entry = self.bufs.get(op["buf"])
        if entry is None:
            return self.record(i, "craft", 0, skipped="no such bytes")
        data, t = entry
        try:
            head1, head2, body = data.split(b"\n", 2)
            s = pickle.loads(body)
            kind, arg = op["edit"]
            if kind == "outputs_nan":
                s["out"] = {k: math.nan for k in s["out"]}
            elif kind == "outputs_inf":
                s["out"] = {k: math.inf for k in s["out"]}
            elif kind == "time":
                s["time"] = float(arg)
            elif kind == "value":
                s["values"][arg[0]] = arg[1]
            elif kind == "drop":
                s.pop(arg, None)
            elif kind == "model_none":
                s["model"] = None
            elif kind == "not_a_dict":
                s = [1, 2, 3]
            data = head1 + b"\n" + head2 + b"\n" + pickle.dumps(s, protocol=5)
            self.bufs[op["buf"]] = (data, t)
            self.record(i, "craft", 0)
        except Exception as e:  # the layout is the FMU's business: report, do not fail
            self.record(i, "craft", 0, skipped=f"{type(e).__name__}: {e}")

    def op_roundtrip(self, i, op, c):
        inst = int(op.get("inst", 0))
        state = fmi2FMUstate()
        st = self.f["fmi2GetFMUstate"](c, byref(state))
        t0 = self.times[inst]
        self.record(i, "getFMUstate", st, phase="roundtrip")
        if st > 1:
            return
        series = []
        for rep in range(2):
            if rep:
                st = self.f["fmi2SetFMUstate"](c, state)
                self.times[inst] = t0
                self.record(i, "setFMUstate", st, phase="roundtrip")
                if st > 1:
                    break
            seq = []
            for _ in range(int(op["k"])):
                s, s1, after = self._step(i, {"h": op["h"], "inst": inst}, c, call="doStep")
                seq.append([s, s1, _hex(after)])
            series.append(seq)
        st = self.f["fmi2FreeFMUstate"](c, byref(state))
        self.record(i, "freeFMUstate", st, phase="roundtrip", series=series)


def _enc(values: dict) -> dict:
    """Floats as JSON numbers (repr is exact); NaN/inf as strings JSON can carry."""
    return {
        k: (v if isinstance(v, int) or math.isfinite(v) else repr(v)) for k, v in values.items()
    }


def _hex(values: dict) -> dict:
    return {k: (v.hex() if isinstance(v, float) else v) for k, v in values.items()}


def main() -> None:
    global PROTO
    PROTO = os.fdopen(os.dup(1), "w")
    os.dup2(2, 1)  # whatever the FMU prints goes to stderr
    faulthandler.enable(sys.stderr)
    # a bound on the address space: a hostile grid size must fail with MemoryError in
    # the worker, not take the memory of the machine
    limit = int(float(os.environ.get("CONTACT_FMU_FUZZ_MEMORY_GB", "4")) * 2**30)
    resource.setrlimit(resource.RLIMIT_AS, (limit, limit))
    host = Host(sys.argv[1])
    emit({"ready": True, "reals": [v.name for v in host.reals]})
    try:
        for line in sys.stdin:
            if not line.strip():
                continue
            req = json.loads(line)
            try:
                host.run(req["ops"])
            except FatalStatusError:
                emit({"done": True, "fatal": True})
                break
            emit({"done": True})
    finally:
        shutil.rmtree(host.dir, ignore_errors=True)


if __name__ == "__main__":
    main()
