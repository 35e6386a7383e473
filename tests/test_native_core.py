"""The native FMUs' C core (instance.c, for one model) in-process against the pythonfmu
adapter's Python path, the reference implementation.

``contact_fmu.native.core`` drives one instance of the core compiled for a scene's
configuration (its cf_model.h from fmu_build/native_fmu.py, no FMI front end) with
ctypes, as the adapter would delegate to it. Given the same FMI calls, the core and
the adapter (``ContactSlave`` in-process, with the shim's status cell) must answer the
same statuses, log the same messages word for word (both format the templates of
fmu/messages.py) and serve the same doubles: the Fig. 13 body (Lobatto IIIC, the thin-
layer law) steps through the same C stepper in both. Its FMU state, in instance.c's one
format, restores bit for bit.
"""

from __future__ import annotations

import ctypes
import math
import shutil
from pathlib import Path

import pytest

from contact_fmu import examples as ex
from contact_fmu.fmu.slave import CELL_VR, ContactSlave
from contact_fmu.native import core
from contact_fmu.scenario import load
from fmu_build import native_fmu

ROOT = Path(__file__).resolve().parents[1]
H = 1.75e-4  # s, the Fig. 13 scene's communication step
GUID = "{core-test}"
pytestmark = pytest.mark.skipif(shutil.which("cc") is None, reason="no C compiler")


@pytest.fixture(scope="module")
def fig13(tmp_path_factory):
    """(configuration, the core library compiled for it)."""
    cfg = load(ROOT / "scenarios" / "fig13.toml").config
    src = tmp_path_factory.mktemp("core")
    for name in native_fmu.CORE:
        shutil.copyfile(native_fmu.NATIVE_DIR / name, src / name)
    (src / native_fmu.HEADER).write_text(native_fmu.header(cfg, GUID))
    lib = native_fmu.compile_binary(src, src / "core.so", core.FLAGS, native_fmu.CORE)
    return cfg, core.load(lib)


class Adapter:
    """The pythonfmu adapter in-process, answering as the FMU's binary would (the worst
    of the call's result and the status the adapter wrote into the shim's cell)."""

    def __init__(self, cfg) -> None:
        cls = type("Model", (ContactSlave,), {"CONFIG": cfg.to_dict()})
        self.s = cls(instance_name="adapter")
        self.cell = ctypes.c_int(0)
        self.s.set_string([CELL_VR], [f"status cell {hex(ctypes.addressof(self.cell))}"])
        self.vr = {v.name: k for k, v in self.s.vars.items()}

    def call(self, fn, *args) -> tuple[int, object]:
        self.cell.value = core.OK
        result = fn(*args)
        status = core.DISCARD if result is False else core.OK
        return max(status, self.cell.value), result

    def messages(self) -> list[tuple[int, str]]:
        return [(m.status.value, m.msg) for m in self.s.log_queue]

    def run(self, kind: str, *args) -> tuple[int, object]:
        if kind == "set":
            return self.call(self.s.set_real, [self.vr[args[0]]], [args[1]])
        if kind == "get":
            status, out = self.call(self.s.get_real, [self.vr[n] for n in args[0]])
            return status, out
        if kind == "step":
            return self.call(self.s.do_step, *args)
        if kind == "init":
            self.call(self.s.setup_experiment, 0.0)
            self.call(self.s.enter_initialization_mode)
            return self.call(self.s.exit_initialization_mode)
        if kind == "terminate":
            return self.call(self.s.terminate)
        raise ValueError(kind)


class Native:
    """The core, answering with its own statuses."""

    def __init__(self, cfg, lib) -> None:
        self.log: list[tuple[int, str]] = []
        self.c = core.Core(lib, GUID, lambda s, m: self.log.append((s, m)))
        self.vr = {v.name: k for k, v in enumerate(cfg.variables)}

    def messages(self) -> list[tuple[int, str]]:
        return self.log

    def run(self, kind: str, *args) -> tuple[int, object]:
        if kind == "set":
            return self.c.set_real([self.vr[args[0]]], [args[1]]), None
        if kind == "get":
            return self.c.get_real([self.vr[n] for n in args[0]])
        if kind == "step":
            return self.c.do_step(*args), None
        if kind == "init":
            self.c.setup_experiment(0.0)
            self.c.enter_initialization_mode()
            return self.c.exit_initialization_mode(), None
        if kind == "terminate":
            return self.c.terminate(), None
        raise ValueError(kind)


F = ex.force_unit()


def reals(cfg) -> list[str]:
    """The configuration's Real outputs (regime is an Integer)."""
    return [v.name for v in cfg.variables if v.name in cfg.outputs and v.type == "Real"]


# calls after initialisation and a step of the loaded body: bad values held and
# corrected, steps refused (size, time, load limit, range, the work budget), a fixed
# parameter set, a step after terminate
CALLS = [
    ("set", "Fx_ex", F),
    ("set", "My_ex", -0.1 * F * ex.Rx),
    ("step", 0.0, H),
    ("set", "P", -1.0),
    ("set", "My_ex", math.inf),
    ("step", H, H),
    ("set", "P", ex.P),
    ("set", "My_ex", -0.1 * F * ex.Rx),
    ("step", H, 0.0),
    ("step", H, math.nan),
    ("step", 1.0, H),
    ("set", "Fx_ex", -1.2e308),
    ("step", H, H),
    ("set", "Fx_ex", F),
    ("set", "My_ex", 1e20),
    ("step", H, H),
    ("set", "My_ex", 1e10),
    ("step", H, 1.0),
    ("set", "My_ex", -0.1 * F * ex.Rx),
    ("step", H, 10.0),
    ("set", "mu", math.nan),
    ("set", "M", 2.0),
    ("terminate",),
    ("step", H + 10.0, H),
]


def test_the_core_answers_every_call_as_the_adapter_does(fig13):
    """The calls above, from the start (a step before initialisation, then initialised
    at the scene's values): the same status for each call, the same messages word for
    word in the same order, and the outputs read after each call the same doubles
    (rolling at Fig. 13's speed, loaded by Fx_ex = F and My_ex = -0.1 F Rx; a step of
    10 s is taken in the budget's internal steps with a warning, the same on both)."""
    cfg, lib = fig13
    outputs = reals(cfg)
    answers = []
    targets = (Adapter(cfg), Native(cfg, lib))
    assert targets[0].vr == targets[1].vr  # one model description: the same references
    for target in targets:
        got = [target.run("step", 0.0, H)[0], target.run("init")[0]]
        for call in CALLS:
            got.append(target.run(*call)[0])
            got.append(target.run("get", outputs))
        answers.append((got, target.messages()))
    assert answers[0][0] == answers[1][0]
    assert answers[0][1] == answers[1][1]
    statuses = [s for s in answers[0][0] if isinstance(s, int)]
    assert {core.OK, core.WARNING, core.DISCARD, core.ERROR} <= set(statuses)
    # each answer other than OK is explained by one message of its status
    assert [s for s, _ in answers[0][1]] == [s for s in statuses if s != core.OK]


def test_the_cores_state_restores_bit_for_bit(fig13):
    """instance.c's FMU state as bytes: get, step on, set, step again gives the same
    doubles as the first time; bytes altered in their checksum are refused naming the
    reason, and the instance is unchanged and steps on."""
    cfg, lib = fig13
    n = Native(cfg, lib)
    n.run("init")
    for name, value in (("Fx_ex", F), ("My_ex", -0.1 * F * ex.Rx)):
        n.run("set", name, value)
    outputs = reals(cfg)
    assert n.run("step", 0.0, H)[0] == core.OK
    status, state = n.c.get_state()
    assert status == core.OK and state
    first = [n.run("step", H * (1 + k), H)[0] for k in range(3)], n.run("get", outputs)
    assert n.c.set_state(state) == core.OK
    again = [n.run("step", H * (1 + k), H)[0] for k in range(3)], n.run("get", outputs)
    assert first == again
    damaged = state[:-1] + bytes([state[-1] ^ 1])
    assert n.c.set_state(damaged) == core.ERROR
    assert n.log[-1] == (
        core.ERROR,
        f"fmi2DeSerializeFMUstate: the {len(state)} bytes are refused: damaged (its checksum "
        "differs)",
    )
    assert n.run("get", outputs) == again[1]
    assert n.run("step", 4 * H, H)[0] == core.OK
