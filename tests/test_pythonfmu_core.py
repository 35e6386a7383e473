"""The pythonfmu FMU delegating to its model's C core (fmu/slave_core.py) against its
Python path (the reference implementation: CONTACT_FMU_CORE=0).

A pythonfmu FMU of a model the native FMU covers carries that model's core (instance.c
for its cf_model.h, fmu_build ``_compile_core``); every FMI call of the adapter then goes
to it. Given the same calls, the two paths must answer the same statuses, log the same
messages word for word (both format fmu/messages.py's templates) and serve the same
doubles where the same C steps the model (the body modes: stepper.c, field.c, behind
the Python path's compiled step too). The contact mode evaluates the law in Python on
the Python path, in C in the core: the same to rounding (1e-12 of each value, the
native FMU's tolerance against the pythonfmu FMU, tests/test_native_core.py).

In-process (``ContactSlave`` of the source tree given a resources folder that holds a
core compiled for its configuration) for many models; through fmpy (the built FMU,
the shim) for the Fig. 13 and full body FMUs, their FMU states and the fallbacks.
"""

from __future__ import annotations

import ctypes
import math
import os
import shutil
import subprocess
import sys
import uuid
import zipfile
from pathlib import Path

import pytest
from test_native_core import CALLS, Adapter, F, H, _close, _other_calls, answers, reals

import fmu_build
from contact_fmu import examples as ex
from contact_fmu.fmu import slave_core, state_bytes
from contact_fmu.fmu.config import ModelConfig
from contact_fmu.fmu.slave import CELL_VR, ContactSlave
from contact_fmu.native import core
from contact_fmu.scenario import load
from contact_fmu.scenario.instance import ERROR, OK, Instance
from fmu_build import native_fmu, tables

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "out" / "fmu"
pytestmark = pytest.mark.skipif(
    shutil.which("cc") is None or not sys.platform.startswith("linux"),
    reason="no C compiler (the core is compiled for Linux)",
)


@pytest.fixture(autouse=True)
def _paths_on(monkeypatch):
    """Both paths admitted unless a test turns one off (the user's environment aside)."""
    monkeypatch.delenv(slave_core.CORE_ENV, raising=False)
    monkeypatch.delenv("CONTACT_FMU_NATIVE", raising=False)


def resources(cfg: ModelConfig, folder: Path) -> Path:
    """A resources folder holding the core of ``cfg`` where an FMU holds it
    (<package>/native: the library, its GUID, the creep-force table), as fmu_build
    writes it, and the law's generated data (the Python path's table). A GUID of its
    own: a process loads one core library per GUID (an FMU's content)."""
    where = folder / "contact_fmu" / "native"
    where.mkdir(parents=True)
    fmu_build._compile_core(cfg, where, "{" + str(uuid.uuid4()) + "}")
    assert (where / core.LIBRARY).is_file()
    for rel in cfg.generated_files:
        (folder / "contact_fmu" / rel).parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(tables.ensure(cfg), folder / "contact_fmu" / rel)
    return folder


class Delegating(Adapter):
    """The adapter in-process on the resources ``folder``, with its core or on its
    Python path (CONTACT_FMU_CORE=0 while it is made)."""

    def __init__(self, cfg: ModelConfig, folder: Path, with_core: bool = True) -> None:
        cls = type("Model", (ContactSlave,), {"CONFIG": cfg.to_dict()})
        os.environ[slave_core.CORE_ENV] = "1" if with_core else "0"
        try:
            self.s = cls(instance_name="adapter", resources=str(folder))
        finally:
            del os.environ[slave_core.CORE_ENV]
        assert (self.s._core_calls is not None) == with_core
        self.cell = ctypes.c_int(0)
        self.s.set_string([CELL_VR], [f"status cell {hex(ctypes.addressof(self.cell))}"])
        self.vr = {v.name: k for k, v in self.s.vars.items()}


def _scene(name: str) -> ModelConfig:
    if name.startswith("full_"):
        return ModelConfig.full(name[5:])
    return load(ROOT / "scenarios" / f"{name}.toml").config


def _calls(cfg: ModelConfig, name: str) -> list:
    """fig13: test_native_core's CALLS; the full modes: _other_calls; a scene: the full
    body's calls it has inputs for."""
    if name == "fig13":
        return CALLS
    if name.startswith("full_"):
        return _other_calls(cfg)
    return [c for c in _other_calls(ModelConfig.full("body")) if c[0] != "set" or
            c[1] in (*cfg.inputs, "Rx")]  # fmt: skip


SCENES = ["fig13", "full_body", "full_rigid_body", "full_contact", "brake", "railway",
          "cornering", "rail_traction", "fig12_transient"]  # fmt: skip


@pytest.mark.parametrize("name", SCENES)
def test_the_core_path_answers_every_call_as_the_python_path(tmp_path, name):
    """From the start (a step before initialisation, initialised at the scene's values),
    good calls and bad ones (values out of range, NaN and inf, steps of 0, NaN, not at
    the FMU's time, beyond the load limit or the work budget, a fixed parameter set,
    a step after terminate): the same status for every call, the same messages word for
    word in the same order, and after every call the same doubles where the same C
    steps the model (the body on stepper.c, the half-space table blended in C on both).
    In contact mode the Python path evaluates the law in Python (math.hypot, numpy's
    sums of the spin grid): within 1e-12 of each value. On the transient field the
    Python path's stage is field.c's but its summary numpy's (z**3 by numpy's own
    power against C's z z z: tests/test_native_field.py): within TRAJ_RTOL = 1e-9 of each
    output's largest magnitude over the run (measured: below 1e-15)."""
    cfg = _scene(name)
    # a core of every one of them (the FMU of fig12_transient carries none: its grid is
    # the user's to set; the core at the scene's grid still answers as the adapter)
    assert native_fmu.unsupported(cfg) is None
    assert fmu_build.carries_core(cfg) == (not cfg.transient)
    folder = resources(cfg, tmp_path)
    with_core, python = Delegating(cfg, folder), Delegating(cfg, folder, with_core=False)
    calls, outputs = _calls(cfg, name), reals(cfg)
    a, b = (answers(t, calls, outputs) for t in (with_core, python))
    assert a[1] == b[1]  # the messages, word for word
    if cfg.mode != "contact" and not cfg.transient:
        assert a == b
    read = [(x, y) for x, y in zip(a[0], b[0], strict=True) if not isinstance(x, int)]
    scale = [max(abs(y[1][k]) for _, y in read) for k in range(len(outputs))]
    for x, y in zip(a[0], b[0], strict=True):
        if isinstance(x, int):
            assert x == y
        elif cfg.transient:
            assert x[0] == y[0] and all(abs(u - v) <= 1e-9 * m for u, v, m in
                                        zip(x[1], y[1], scale, strict=True)), (x, y)  # fmt: skip
        else:
            assert x[0] == y[0] and _close(x[1], y[1]), (x, y)
    statuses = [s if isinstance(s, int) else s[0] for s in a[0]]
    assert OK in statuses and ERROR in statuses  # the bad calls were refused alike


def test_the_core_is_freed_when_the_shim_says_the_instance_goes(tmp_path):
    """fmi2FreeInstance and fmi2Reset: the shim sends RELEASE through the cell's value
    reference before pythonfmu drops the Python object; the core instance is freed then
    (not at the object's collection), and a call after it is refused (an exception:
    pythonfmu's fmi2Fatal), never served from freed memory."""
    cfg = _scene("fig13")
    d = Delegating(cfg, resources(cfg, tmp_path))
    calls = d.s._core_calls
    assert d.run("init")[0] == OK and d.run("step", 0.0, H)[0] == OK
    d.s.set_string([CELL_VR], [slave_core.RELEASE])
    assert calls.core is None
    with pytest.raises(RuntimeError, match="C core was freed"):
        d.s.do_step(H, H)


def test_the_per_step_calls_run_in_the_c_binding_and_answer_as_ctypes(tmp_path):
    """With the shim's cell known, do_step, set_real and get_real are fmi.c's CoreBinding
    (one C call each at the core's addresses): the same statuses, messages and doubles
    as the same calls through ctypes (the binding's fallbacks)."""
    cfg = _scene("fig13")
    folder = resources(cfg, tmp_path)
    fast, slow = Delegating(cfg, folder), Delegating(cfg, folder)
    assert type(fast.s.do_step).__name__ == "builtin_function_or_method"
    calls = slow.s._core_calls
    for name in ("do_step", "set_real", "get_real"):  # the ctypes path
        setattr(slow.s, name, getattr(calls, "_py_" + name))
    a, b = (answers(t, CALLS, reals(cfg)) for t in (fast, slow))
    assert a == b


# ---- the built FMU through fmpy ---------------------------------------------------------------
@pytest.fixture(scope="module")
def fmus() -> dict[str, Path]:
    return {n: fmu_build.build(_scene(n), OUT).path for n in ("fig13", "full_body")}


def _drive(path: Path, core_on: bool, calls: list, monkeypatch) -> tuple[list, list, bytes]:
    """The statuses of ``calls`` on a fresh instance (core on or off at instantiation),
    the outputs after each, the messages, and a state of it serialized."""
    from fmpy.fmi1 import FMICallException

    monkeypatch.setenv(slave_core.CORE_ENV, "1" if core_on else "0")
    got = []
    with Instance(path, "drive") as inst:
        for kind, *args in calls:
            try:
                if kind == "set":
                    inst.set(*args)
                    got.append(OK)
                else:
                    got.append(inst.step(args[1], time=args[0]))
            except FMICallException as e:
                got.append(int(e.status))
            try:
                got.append(inst.outputs())
            except FMICallException as e:
                got.append(int(e.status))
        data = inst.serialize_state(inst.get_state())
        return got, inst.messages, data


def _inner(data: bytes) -> bytes:
    """The adapter's bytes inside the shim's envelope (its magic, format, GUID length,
    GUID, payload length, CRC-32: pythonfmu_shim.c)."""
    m = len(b"contact_fmu state\n")
    glen = int.from_bytes(data[m + 4 : m + 8], "little")
    return data[m + 8 + glen + 12 :]


@pytest.mark.parametrize("name", ["fig13", "full_body"])
def test_the_fmu_with_its_core_answers_as_with_core_off(fmus, name, monkeypatch):
    """The built FMU through fmpy and its shim, the core on and off
    (CONTACT_FMU_CORE=0): the same statuses, outputs (bit for bit: the same stepper.c)
    and messages word for word over the loaded body, bad inputs held and corrected and
    bad steps; the state each serializes is its own path's format."""
    cfg = _scene(name)
    Rx = float(cfg.start(cfg.variables[[v.name for v in cfg.variables].index("Rx")]))
    loads = [("set", "Fx_ex", F), ("set", "My_ex", -0.1 * F * ex.Rx)] if name == "fig13" else [
        ("set", "Fx_ex", 0.1), ("set", "Fy_ex", 0.05), ("set", "Mz_ex", 1e-4)]  # fmt: skip
    calls = [*loads, ("step", 0.0, H), ("set", "My_ex", math.nan), ("step", H, H),
             ("set", "My_ex", 0.0), ("step", H, H), ("step", 2 * H, 0.0), ("step", 1.0, H),
             ("set", "Rx", 2.0 * Rx), ("set", "P", -1.0), ("step", 2 * H, H),
             ("set", "P", ex.P if name == "fig13" else 1.0), ("step", 2 * H, H)]  # fmt: skip
    on, off = (_drive(fmus[name], flag, calls, monkeypatch) for flag in (True, False))
    assert on[:2] == off[:2]
    assert {ERROR, 2} <= {s for s in on[0] if isinstance(s, int)}  # refusals, discards
    assert _inner(on[2]).startswith(state_bytes.CORE_MAGIC)  # instance.c's format
    assert _inner(off[2]).startswith(state_bytes.MAGIC)  # the Python path's


def test_states_of_one_path_are_refused_by_the_other_naming_it(fmus, monkeypatch):
    """A state serialized with the core, deserialized by an instance on the Python path
    (or the other way): fmi2Error naming the path that wrote it, nothing changed, the
    instance steps on; bytes damaged or of a freed state are refused by the shim alike
    on both paths."""
    from fmpy.fmi1 import FMICallException

    path = fmus["fig13"]
    data = {}
    for flag in (True, False):
        monkeypatch.setenv(slave_core.CORE_ENV, "1" if flag else "0")
        with Instance(path, "writer") as w:
            assert w.step(H) == OK
            data[flag] = w.serialize_state(w.get_state())
    words = {
        True: "a state of this FMU's Python path (saved with CONTACT_FMU_CORE=0 or "
        "CONTACT_FMU_NATIVE=0); this instance runs its C core",
        False: "a state of this FMU's C core; this instance runs its Python path "
        "(CONTACT_FMU_CORE=0 or CONTACT_FMU_NATIVE=0 when it was made)",
    }
    for flag in (True, False):
        monkeypatch.setenv(slave_core.CORE_ENV, "1" if flag else "0")
        with Instance(path, "reader") as r:
            assert r.step(H) == OK
            before = r.outputs()
            try:
                r.set_state(r.deserialize_state(data[not flag], r.time))
                status = OK
            except FMICallException as e:
                status = int(e.status)
            assert status == ERROR and words[flag] in r.messages[-1][1], r.messages[-1:]
            assert r.outputs() == before and r.step(H) == OK
            r.set_state(r.deserialize_state(data[flag], H))  # its own, at its time: restored
            assert r.step(H) == OK
            damaged = bytearray(data[flag])
            damaged[-1] ^= 1
            with pytest.raises(FMICallException):
                r.deserialize_state(bytes(damaged), r.time)
            assert r.messages[-1][1].endswith("damaged (its checksum differs)")
            state = r.get_state()
            r.free_state(state)
            with pytest.raises(FMICallException):
                r.set_state(state)
            assert "is not an FMU state of this instance" in r.messages[-1][1], r.messages[-1:]
            assert r.step(H) == OK


def test_core_off_by_either_variable_and_no_core_run_the_python_path(fmus):
    """CONTACT_FMU_CORE=0 or CONTACT_FMU_NATIVE=0 when the instance is made, or an FMU
    that carries no core (fig12_transient: the pythonfmu FMU lets the user set the
    field's grid, which the native core holds at the build's size), run the Python path:
    its state format; with neither variable the core's (a fresh process each: the
    loaders keep what they loaded)."""
    no_core = fmu_build.build(_scene("fig12_transient"), OUT)
    with zipfile.ZipFile(no_core.path) as z:
        assert not any(n.endswith(core.LIBRARY) for n in z.namelist())
    code = (
        "import sys; from contact_fmu.scenario.instance import Instance\n"
        "with Instance(sys.argv[1], 'x') as i:\n"
        "    data = i.serialize_state(i.get_state())\n"
        "from contact_fmu.fmu.state_bytes import CORE_MAGIC\n"
        "print('core' if CORE_MAGIC in data else 'python')\n"
    )
    cases = [(fmus["fig13"], {}, "core"), (fmus["fig13"], {slave_core.CORE_ENV: "0"}, "python"),
             (fmus["fig13"], {"CONTACT_FMU_NATIVE": "0"}, "python"),
             (no_core.path, {}, "python")]  # fmt: skip
    for path, env, expected in cases:
        clean = {k: v for k, v in os.environ.items() if k not in (slave_core.CORE_ENV,
                 "CONTACT_FMU_NATIVE")}  # fmt: skip
        out = subprocess.run([sys.executable, "-c", code, str(path)], capture_output=True,
                             text=True, env=clean | env, cwd=ROOT)  # fmt: skip
        assert out.stdout.split()[-1:] == [expected], (env, out.stderr[-2000:])


def test_a_core_that_cannot_start_leaves_the_python_path_with_a_warning(tmp_path):
    """A core whose creep-force table is gone from the instance's resources cannot
    instantiate: the adapter logs why as a warning (the core's words, the file named)
    and runs its Python path, which answers as the core would."""
    cfg = _scene("rail_traction")
    folder = resources(cfg, tmp_path)
    (folder / "contact_fmu" / "native" / core.TABLE).unlink()
    d = Delegating.__new__(Delegating)
    cls = type("Model", (ContactSlave,), {"CONFIG": cfg.to_dict()})
    d.s = cls(instance_name="adapter", resources=str(folder))
    assert d.s._core_calls is None
    (status, text), *_ = [(m.status.value, m.msg) for m in d.s.log_queue]
    assert status == 1 and text.startswith("the FMU's C core cannot start (")
    assert "table.bin" in text and text.endswith("): the adapter's Python path runs")
