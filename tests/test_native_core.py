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
from contact_fmu.fmu import variables as fv
from contact_fmu.fmu.config import ModelConfig
from contact_fmu.fmu.slave import CELL_VR, ContactSlave
from contact_fmu.native import core
from contact_fmu.scenario import load
from fmu_build import native_fmu

ROOT = Path(__file__).resolve().parents[1]
H = 1.75e-4  # s, the Fig. 13 scene's communication step
GUID = "{core-test}"
pytestmark = pytest.mark.skipif(shutil.which("cc") is None, reason="no C compiler")


def compiled(cfg: ModelConfig, folder: Path) -> ctypes.CDLL:
    """The core library of ``cfg``, compiled in ``folder``."""
    for name in native_fmu.CORE:
        shutil.copyfile(native_fmu.NATIVE_DIR / name, folder / name)
    (folder / native_fmu.HEADER).write_text(native_fmu.header(cfg, GUID))
    return core.load(native_fmu.compile_binary(folder, folder / "core.so", core.FLAGS,
                                               native_fmu.CORE))  # fmt: skip


@pytest.fixture(scope="module")
def fig13(tmp_path_factory):
    """(configuration, the core library compiled for it)."""
    cfg = load(ROOT / "scenarios" / "fig13.toml").config
    return cfg, compiled(cfg, tmp_path_factory.mktemp("core"))


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


def answers(target, calls: list, outputs: list[str]) -> tuple[list, list]:
    """The status of each call and the outputs read after it; the messages logged."""
    got = [target.run("step", 0.0, H)[0], target.run("init")[0]]
    for call in calls:
        got.append(target.run(*call)[0])
        got.append(target.run("get", outputs))
    return got, target.messages()


def test_the_core_answers_every_call_as_the_adapter_does(fig13):
    """The calls above, from the start (a step before initialisation, then initialised
    at the scene's values): the same status for each call, the same messages word for
    word in the same order, and the outputs read after each call the same doubles
    (rolling at Fig. 13's speed, loaded by Fx_ex = F and My_ex = -0.1 F Rx; a step of
    10 s is taken in the budget's internal steps with a warning, the same on both)."""
    cfg, lib = fig13
    outputs = reals(cfg)
    targets = (Adapter(cfg), Native(cfg, lib))
    assert targets[0].vr == targets[1].vr  # one model description: the same references
    python, native = (answers(t, CALLS, outputs) for t in targets)
    assert python == native
    statuses = [s for s in python[0] if isinstance(s, int)]
    assert {core.OK, core.WARNING, core.DISCARD, core.ERROR} <= set(statuses)
    # each answer other than OK is explained by one message of its status
    assert [s for s, _ in python[1]] == [s for s in statuses if s != core.OK]


def _other_calls(cfg: ModelConfig) -> list:
    """Calls of the full body (Eqs. 10-11: the vector stepper, the law's spin by the
    strip march), the rigid body (Eqs. 8-9) and the contact mode (the law at the inputs,
    direct feedthrough): good values, then bad ones held and corrected, bad steps, a
    fixed parameter set after initialisation; in contact mode, a parameter read while an
    input is held bad (OK: only the outputs cannot be had)."""
    Rx = float(cfg.start(fv.BY_NAME["Rx"]))
    common = [("step", H, 0.0), ("step", 1.0, H), ("set", "Rx", 2.0 * Rx)]
    if cfg.mode == "rigid_body":
        return [("set", "Tx", 10.0), ("step", 0.0, H), ("set", "Tx", math.inf),
                ("step", H, H), ("set", "Tx", 10.0), ("step", H, H), ("set", "My_ex", 1e30),
                ("step", 2 * H, 1.0), ("set", "My_ex", 0.0), *common]  # fmt: skip
    if cfg.mode == "contact":
        return [("set", "Vx", 10.0), ("set", "Omega_y", 0.999 * 10.0 / Rx),
                ("set", "Omega_z", 0.5), ("step", 0.0, H), ("set", "P", -1.0),
                ("get", ["mu"]), ("step", H, H), ("set", "P", 1e3), ("set", "Vy", math.nan),
                ("set", "Vy", 0.01), ("step", H, H), *common]  # fmt: skip
    return [("set", "Fx_ex", 0.1), ("set", "Fy_ex", 0.05), ("set", "Mz_ex", 1e-4),
            ("step", 0.0, H), ("set", "Fy_ex", math.nan), ("step", H, H),
            ("set", "Fy_ex", 0.05), ("step", H, H), ("set", "Fx_ex", -1.2e308),
            ("step", 2 * H, H), ("set", "Fx_ex", 0.1), ("step", 2 * H, H), *common]  # fmt: skip


def _close(a: list[float], b: list[float]) -> bool:
    """Within 1e-12 of the larger magnitude, value by value (exact zeros equal)."""
    return len(a) == len(b) and all(
        abs(x - y) <= 1e-12 * max(abs(x), abs(y)) for x, y in zip(a, b, strict=True)
    )


@pytest.mark.parametrize("mode", ["body", "rigid_body", "contact"])
def test_the_core_of_every_mode_answers_as_the_adapter_does(tmp_path, mode):
    """The full body, rigid-body and contact FMUs' models (ModelConfig.full): the core
    and the adapter's Python path answer the calls of _other_calls with the same
    statuses and the same messages word for word (one refusal of a getReal call logged
    once), and the same doubles after each call. The contact mode with a spin input
    marches the strips on the law's spin grid, built in C here and by numpy in Python:
    the same to rounding, within 1e-12 of each value (tests/test_native_contact_spin.py's
    tolerance between the two FMUs); the bodies step through the same C stepper: the
    same doubles."""
    cfg = ModelConfig.full(mode)
    targets = (Adapter(cfg), Native(cfg, compiled(cfg, tmp_path)))
    assert targets[0].vr == targets[1].vr
    python, native = (answers(t, _other_calls(cfg), reals(cfg)) for t in targets)
    assert python[1] == native[1]
    if mode != "contact":
        assert python == native
    for a, b in zip(python[0], native[0], strict=True):
        if isinstance(a, int):
            assert a == b
        else:
            assert a[0] == b[0] and _close(a[1], b[1]), (a, b)
    statuses = [s if isinstance(s, int) else s[0] for s in python[0]]  # getReal's too
    assert core.OK in statuses and core.ERROR in statuses
    assert [s for s, _ in python[1]] == [s for s in statuses if s != core.OK]
    if mode == "contact":  # mu read while P = -1 is held: OK
        assert python[0][2 + 2 * 5] == core.OK  # the call after the 5 before it


@pytest.mark.parametrize("scene", ["brake", "railway", "cornering"])
def test_the_core_of_a_scene_answers_as_the_adapter_does(tmp_path, scene):
    """The scenes' body models (SDIRK2 on the brake, Vy from Eq. 10 on the railway, Vy
    and Omega_z from Eqs. 10-11 in the curve): the full body's calls that the scene has
    inputs for, with the same statuses, messages word for word and doubles on both."""
    cfg = load(ROOT / "scenarios" / f"{scene}.toml").config
    calls = [c for c in _other_calls(ModelConfig.full("body")) if c[0] != "set" or
             c[1] in (*cfg.inputs, "Rx")]  # fmt: skip
    targets = (Adapter(cfg), Native(cfg, compiled(cfg, tmp_path)))
    python, native = (answers(t, calls, reals(cfg)) for t in targets)
    assert python == native
    assert any(s == core.DISCARD for s in python[0])  # the bad steps are refused alike


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
