"""The FMI 3.0 native FMU (fmu_build --native --fmi3: the FMI 3.0 front end
contact_fmu/native/fmi3.c on the instance layer instance.c, with model.c and stepper.c)
against the FMI 2.0 native FMU (fmi2.c on the same layer).

Both FMUs run the same compiled C behind their front ends (the same flags; fmi3.c passes
every double through unchanged), so every output and derivative is the FMI 2.0 FMU's and
every message is its message with FMI 3.0's call and status names (FMI2_TO_FMI3): outputs
are compared exactly, step for step, where both run the same calls with the same values.
Tests that need a C compiler, cmake or a sanitizer skip only where the tool is missing.
"""

from __future__ import annotations

import math
import re
import shutil
import subprocess
import tempfile
import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path

import fmpy
import native_c
import numpy as np
import pytest
from fmpy.fmi1 import FMICallException

from contact_fmu import examples as ex
from contact_fmu.fmu import messages as words
from contact_fmu.fmu.config import ModelConfig
from contact_fmu.laws.thin_layer import LayerContact
from contact_fmu.scenario import instance, load, runner
from contact_fmu.scenario.instance import DISCARD, ERROR, FATAL, OK, Instance
from fmu_build import __main__ as cli
from fmu_build import model_description3, native_fmu, native_fmu3

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "out" / "fmu"
STEADY = ("fig13", "brake", "fig12", "railway", "sweep", "cornering", "rail_creep", "rail_traction")
FULL = ("body", "contact", "rigid_body")
KINDS = ("fig13", "rail_traction", *(f"full_{m}" for m in FULL))
F = ex.force_unit()
H = 1.75e-4

pytestmark = pytest.mark.skipif(shutil.which("cc") is None, reason="no C compiler")

# The FMI 2.0 names in the instance layer's messages and the FMI 3.0 names the FMI 3.0 FMU
# says in their place (FMI 3.0 renamed the typed accessors and the FMU state calls, and
# sets the experiment up at fmi3EnterInitializationMode); statuses by their prefix.
FMI2_TO_FMI3 = {
    "fmi2Instantiate": "fmi3InstantiateCoSimulation",
    "fmi2SetupExperiment": "fmi3EnterInitializationMode",
    "fmi2EnterInitializationMode": "fmi3EnterInitializationMode",
    "fmi2ExitInitializationMode": "fmi3ExitInitializationMode",
    "fmi2Terminate": "fmi3Terminate",
    "fmi2GetReal": "fmi3GetFloat64",
    "fmi2SetReal": "fmi3SetFloat64",
    "fmi2GetInteger": "fmi3GetInt32",
    "fmi2SetInteger": "fmi3SetInt32",
    "fmi2GetBoolean": "fmi3GetBoolean",
    "fmi2SetBoolean": "fmi3SetBoolean",
    "fmi2GetString": "fmi3GetString",
    "fmi2SetString": "fmi3SetString",
    "fmi2GetDirectionalDerivative": "fmi3GetDirectionalDerivative",
    "fmi2GetFMUstate": "fmi3GetFMUState",
    "fmi2SetFMUstate": "fmi3SetFMUState",
    "fmi2FreeFMUstate": "fmi3FreeFMUState",
    "fmi2SerializedFMUstateSize": "fmi3SerializedFMUStateSize",
    "fmi2SerializeFMUstate": "fmi3SerializeFMUState",
    "fmi2DeSerializeFMUstate": "fmi3DeserializeFMUState",
    "fmi2OK": "fmi3OK",
    "fmi2Warning": "fmi3Warning",
    "fmi2Discard": "fmi3Discard",
    "fmi2Error": "fmi3Error",
    "fmi2Fatal": "fmi3Fatal",
}


def in_fmi3_words(messages: list[tuple[int, str]]) -> list[tuple[int, str]]:
    """The FMI 2.0 FMU's messages with each FMI 2.0 name replaced by its FMI 3.0 name
    (FMI2_TO_FMI3; a name not in it is a KeyError: the mapping is the whole difference)."""
    return [
        (s, re.sub(r"\bfmi2\w+", lambda m: FMI2_TO_FMI3[m.group(0)], text)) for s, text in messages
    ]


def _config(kind: str) -> ModelConfig:
    if kind.startswith("full_"):
        return ModelConfig.full(kind[5:])
    return load(ROOT / "scenarios" / f"{kind}.toml").config


@pytest.fixture(scope="module")
def fmus():
    """kind -> (FMI 3.0 FMU, FMI 2.0 native FMU), each built once (and cached by content)."""
    built: dict[str, tuple[Path, Path]] = {}

    def get(kind: str) -> tuple[Path, Path]:
        if kind not in built:
            cfg = _config(kind)
            built[kind] = (native_fmu3.build(cfg, OUT).path, native_fmu.build(cfg, OUT).path)
        return built[kind]

    return get


class Instance3(instance.Instance3):
    """scenario.Instance3 with the tests' keywords (``start``, ``init``) and a strict
    ``step``: a doStep through fmpy that must return no event, no termination and no
    early return, with lastSuccessfulTime the instance layer's t + h (the same double)."""

    def __init__(self, path: Path, name: str = "i3", start: dict | None = None, init=True):
        super().__init__(path, name, start, initialise=init)

    def step(self, h: float, time: float | None = None) -> int:
        t = self.time if time is None else time
        try:
            event, terminate, early, last = self.fmu.doStep(t, h)
        except FMICallException as e:
            return int(e.status)
        assert not (event or terminate or early)
        assert last == t + h  # the instance layer's time: t + h, the same double
        self.time = last
        return OK


# ---- the model description, the binary ------------------------------------------------------
FMI3_FUNCTIONS = re.compile(r"FMI3_Export\s+\w+TYPE\s+(fmi3\w+);")


@pytest.mark.parametrize("kind", KINDS)
def test_model_description_is_the_fmi2_fmus_in_fmi3_and_validates(fmus, kind):
    """fmpy's validation (schema, names, ModelStructure, units, start values, one
    independent variable) finds no problem, in the model and the build description; the
    variables are the FMI 2.0 native FMU's (value references, causality, variability,
    units, ranges, starts; Real as Float64, Integer as Int32) and its ModelStructure, plus
    time (independent, after the model's value references); the capabilities are the
    FMI 2.0 FMU's, with adjoint derivatives where it provides directional ones; the binary
    exports the 75 FMI 3.0 functions of fmi3Functions.h and nothing else."""
    from fmpy.validation import validate_fmu

    path3, path2 = fmus(kind)
    assert validate_fmu(str(path3)) == []
    md3 = fmpy.read_model_description(str(path3))
    md2 = fmpy.read_model_description(str(path2))
    assert md3.fmiVersion == "3.0" and md3.coSimulation.modelIdentifier == f"{kind}_native3"
    v3 = {v.name: v for v in md3.modelVariables}
    types = {"Real": "Float64", "Integer": "Int32", "String": "String"}
    for v in md2.modelVariables:
        w = v3.pop(v.name)
        assert types[v.type] == w.type, v.name
        for a in ("valueReference", "causality", "variability", "initial", "unit", "min", "max"):
            assert getattr(v, a) == getattr(w, a), (v.name, a)
        assert v.start == w.start, v.name  # strings as written: the same repr
    # FMI 3.0's own: time, and the centre line's arrays on the thin-layer law outside the
    # rigid_body mode, after it
    line = [name for name, _, _ in model_description3.LINE]
    if kind in ("rail_traction", "full_rigid_body"):
        line = []
    assert list(v3) == ["time", *line] and v3["time"].causality == "independent"
    assert v3["time"].valueReference == len(md2.modelVariables)
    for k, name in enumerate(line, start=1):
        assert v3[name].valueReference == len(md2.modelVariables) + k
        assert [d.start for d in v3[name].dimensions] == [model_description3.LINE_N]
        assert v3[name].causality == "output" and v3[name].variability == "continuous"

    def deps(unknowns):
        return {u.variable.name: sorted(d.name for d in u.dependencies or []) for u in unknowns}

    scalar = [u for u in md3.outputs if u.variable.name not in line]
    assert deps(scalar) == deps(md2.outputs)
    # the line follows the inputs Tx follows
    assert all(deps(md3.outputs)[n] == deps(md2.outputs)["Tx"] for n in line)
    assert deps(u for u in md3.initialUnknowns if u.variable.name not in line) == deps(
        md2.initialUnknowns
    )
    with zipfile.ZipFile(path3) as z:
        cs3 = ET.fromstring(z.read("modelDescription.xml")).find("CoSimulation").attrib
    with zipfile.ZipFile(path2) as z:
        cs2 = ET.fromstring(z.read("modelDescription.xml")).find("CoSimulation").attrib
    derivatives = "true" if kind == "full_contact" else "false"
    assert cs2["providesDirectionalDerivative"] == derivatives
    assert cs3["providesDirectionalDerivatives"] == cs3["providesAdjointDerivatives"] == derivatives
    for a in ("canGetAndSetFMUState", "canSerializeFMUState"):
        assert cs3[a] == cs2[a.replace("State", "state")] == "true"
    same = ("needsExecutionTool", "canHandleVariableCommunicationStepSize")
    assert [cs3[a] for a in same] == [cs2[a] for a in same] == ["false", "true"]
    assert cs3["hasEventMode"] == "false"
    [config] = md3.buildConfigurations
    listed = [f for s in config.sourceFileSets for f in s.sourceFiles]
    assert listed == ["fmi3.c", "instance.c", "model.c", "stepper.c", "field.c"]
    with zipfile.ZipFile(path3) as z:
        names = set(z.namelist())
    assert {f"sources/{n}" for n in (*native_fmu3.SOURCES, "cf_model.h")} <= names
    header = (native_fmu.fmi_headers() / "fmi3Functions.h").read_text()
    standard = set(FMI3_FUNCTIONS.findall(header))
    lib = f"binaries/{native_fmu3.PLATFORM}/{kind}_native3.so"
    with tempfile.TemporaryDirectory() as tmp, zipfile.ZipFile(path3) as z:
        so = z.extract(lib, tmp)
        exported = subprocess.run(
            ["nm", "-D", "--defined-only", so], capture_output=True, text=True, check=True
        ).stdout
    names = {line.split()[-1] for line in exported.splitlines() if " T " in line}
    assert len(standard) == 75 and names == standard


def test_binary_needs_no_python_and_an_old_c_library(fmus, tmp_path):
    """The FMI 3.0 binary needs no Python symbol, and its newest glibc symbol version is
    the FMI 2.0 native FMU's floor (test_native.GLIBC_FLOOR, 2.17): fmi3.c adds only
    calloc, free, the printf family and isalnum."""
    from test_native import GLIBC_FLOOR, glibc_needed

    path3, _ = fmus("fig13")
    lib = f"binaries/{native_fmu3.PLATFORM}/fig13_native3.so"
    with zipfile.ZipFile(path3) as z:
        so = Path(z.extract(lib, tmp_path))
    undefined = subprocess.run(
        ["nm", "-D", "--undefined-only", str(so)], capture_output=True, text=True, check=True
    ).stdout
    assert "Py" not in undefined and "python" not in undefined.lower() and "fmi2" not in undefined
    if shutil.which("objdump"):
        assert glibc_needed(so) <= GLIBC_FLOOR


def test_fmi3_c_compiles_without_warnings(tmp_path):
    """fmi3.c with the instance layer, model and stepper (the full contact FMU's header),
    each its own translation unit, under -Wall -Wextra -Werror and the flags they ship
    with, and under -pedantic -Wmissing-prototypes with no warning in fmi3.c itself: a
    warning there is a defect left for a user's compiler to find."""
    src = tmp_path / "sources"
    src.mkdir()
    for name in native_fmu3.SOURCES:
        shutil.copyfile(native_fmu.NATIVE_DIR / name, src / name)
    (src / native_fmu.HEADER).write_text(native_fmu.header(ModelConfig.full("contact"), "{}"))
    for extra in (("-Werror",), ("-pedantic", "-Wmissing-prototypes")):
        flags = (*native_fmu.CFLAGS, "-Wall", "-Wextra", *extra, f"-I{src}")
        cmd = ["cc", *flags, f"-I{native_fmu.fmi_headers()}", "-o", str(tmp_path / "m.so")]
        units = [str(src / n) for n in native_fmu.c_files(native_fmu3.SOURCES)]
        proc = subprocess.run([*cmd, *units, "-lm"], capture_output=True, text=True)
        assert proc.returncode == 0, proc.stderr[-3000:]
        assert not re.search(r"fmi3\.c:\d+:\d+: warning", proc.stderr), proc.stderr[-3000:]


def test_command_line_writes_the_fmi3_fmu_beside_the_fmi2_one(capsys, tmp_path):
    """--native --fmi3 writes <name>_native3.fmu (the FMI 2.0 native FMU is
    <name>_native.fmu: both can live in one folder); --fmi3 alone is refused."""
    args = ["--native", "--fmi3", "--out", str(OUT), "--full", "rigid_body"]
    assert cli.main(args) == 0
    last = capsys.readouterr().out.strip().splitlines()[-1]
    assert last.endswith("_native3.fmu") and Path(last).is_file()
    with pytest.raises(SystemExit) as e:
        cli.main(["--fmi3", "--full", "rigid_body"])
    assert e.value.code == 2
    assert "--native --fmi3" in capsys.readouterr().err


# ---- the numbers: the FMI 2.0 FMU's doubles ----------------------------------------------------
@pytest.mark.parametrize("name", STEADY)
def test_steady_scene_through_fmpy_gives_the_fmi2_native_fmus_doubles(fmus, name):
    """Every steady scene the native FMU covers, through fmpy's simulate_fmu (FMI 3.0 and
    FMI 2.0 paths): each recorded output is the FMI 2.0 native FMU's double (the same C
    steps), and the scene's references pass."""
    scene = load(ROOT / "scenarios" / f"{name}.toml")
    path3, path2 = fmus(name)
    got, ref = runner.simulate(path3, scene), runner.simulate(path2, scene)
    for a, b in zip(got, ref, strict=True):
        assert a.error is None and b.error is None, (a.error, b.error)
        assert a.columns.keys() == b.columns.keys()
        for k in b.columns:
            assert np.array_equal(a.columns[k], b.columns[k]), (name, a.case, k)
    checks = runner.compare(scene, got)
    assert checks and all(c.ok for c in checks), [c for c in checks if not c.ok]


def _drive(inst, mode: str, n: int) -> list[tuple[int, tuple]]:
    """n steps of H under changing inputs of ``mode``'s full FMU: the status and the
    outputs of each."""
    rows = []
    for k in range(n):
        s = math.sin(k / 7)
        if mode == "body":  # Fig. 13's loads, modulated; a lateral force and a yaw moment
            inputs = {"Fx_ex": F * (1 + 0.2 * s), "My_ex": -0.1 * F * ex.Rx, "Fy_ex": 0.1 * F}
            inputs["Mz_ex"] = 1e-3 * F * ex.Rx * s
        elif mode == "contact":  # rolling with creep, lateral slip and spin
            inputs = {"Vx": 5.0, "Omega_y": (5.0 - 0.01 * (1 + s)) / 0.05, "Vy": 0.005 * s}
            inputs |= {"Omega_z": 0.5 * s, "P": 1000.0 * (1 + 0.1 * s)}
        else:  # Eqs. (8)-(9) under held loads
            inputs = {"Tx": 80.0 * s, "Fx_ex": 100.0, "My_ex": -2.0 + 0.1 * k}
        for key, value in inputs.items():
            inst.set(key, value)
        rows.append((inst.step(H), tuple(inst.outputs().values())))
    return rows


@pytest.mark.parametrize("mode", FULL)
def test_full_fmu_steps_to_the_fmi2_native_fmus_doubles(fmus, mode):
    """The full FMU of each mode under the same changing inputs (the body mode on SDIRK2,
    a String parameter set through fmi3SetString): every step OK, its outputs the FMI 2.0
    native FMU's doubles (Int32 regime = Integer regime)."""
    path3, path2 = fmus(f"full_{mode}")
    start = {"scheme": "sdirk2", "h_max": H / 4} if mode == "body" else {}
    with Instance3(path3, start=start) as a, Instance(path2, "i2", start) as b:
        rows3, rows2 = _drive(a, mode, 40), _drive(b, mode, 40)
        if mode == "body":
            assert a.get("scheme") == b.get("scheme") == "sdirk2"
    assert [s for s, _ in rows3] == [OK] * 40
    assert rows3 == rows2


# ---- bad input: the FMI 2.0 FMU's statuses and words ------------------------------------------
def _bad_calls(inst) -> list[tuple[str, int]]:
    """A master's mistakes on the Fig. 13 FMU: (call, status) of each."""
    out = []

    def call(name, fn, *args):
        try:
            r = fn(*args)
            out.append((name, OK if r is None else r))
        except FMICallException as e:
            out.append((name, int(e.status)))

    inst.set("Fx_ex", F)
    inst.set("My_ex", -0.1 * F * ex.Rx)
    call("step", inst.step, H)
    call("set Fx_ex nan", inst.set, "Fx_ex", math.nan)
    call("step held", inst.step, H)
    call("get Fx_ex held", inst.get, "Fx_ex")
    call("set Fx_ex", inst.set, "Fx_ex", F)
    call("step corrected", inst.step, H)
    call("set P -5", inst.set, "P", -5.0)
    call("step P", inst.step, H)
    call("set P", inst.set, "P", ex.P)
    call("set Rx fixed", inst.set, "Rx", 0.1)
    call("set Vx output", inst.set, "Vx", 1.0)
    call("step h = 0", inst.step, 0.0)
    call("step h = nan", inst.step, math.nan)
    call("step at 10 H", inst.step, H, 10 * H)
    call("step 1e300 moment", lambda: (inst.set("My_ex", 6e306), inst.step(H))[1])
    call("set My_ex", inst.set, "My_ex", -0.1 * F * ex.Rx)
    call("step again", inst.step, H)
    return out


def test_bad_input_gives_the_fmi2_fmus_statuses_and_messages(fmus):
    """The same mistakes on both FMUs: a refused value answers fmi3Error at its setter
    naming the variable and the value, a step while it is held fmi3Discard with the same
    words, a step not in (0, inf) or not at the FMU's time fmi3Discard, a fixed parameter
    or an output set fmi3Error; corrected, the instance steps on. Statuses, messages and
    outputs are the FMI 2.0 FMU's, call for call, its messages in FMI 3.0's names."""
    path3, path2 = fmus("fig13")
    with Instance3(path3) as a, Instance(path2, "i2") as b:
        calls3, calls2 = _bad_calls(a), _bad_calls(b)
        assert a.outputs() == b.outputs()
        assert a.messages == in_fmi3_words(b.messages)
        assert any("fmi2" in m for _, m in b.messages)  # the mapping has work to do
    assert calls3 == calls2
    status = dict(calls3)
    assert status["set Fx_ex nan"] == ERROR and status["step held"] == DISCARD
    assert status["get Fx_ex held"] == ERROR and status["step corrected"] == OK
    assert status["step P"] == DISCARD and status["set Rx fixed"] == ERROR
    assert status["step at 10 H"] == DISCARD and status["step again"] == OK
    text = "Fx_ex = nan is invalid: must be finite"
    assert any(text in m for s, m in a.messages if s == ERROR)
    assert any(text in m for s, m in a.messages if s == DISCARD)
    assert any("P = -5.0 is invalid: must be >= 0 (lift-off" in m for _, m in a.messages)
    assert any(
        m.endswith("; doStep answers fmi3Discard until it is corrected") for _, m in a.messages
    )
    assert all(s < FATAL for s, _ in a.messages)


def test_a_bad_parameter_is_refused_at_initialisation_in_the_fmi2_fmus_words(fmus):
    """mu = 0 (the law needs mu > 0): fmi3Error at the setter and at
    exitInitializationMode, with the FMI 2.0 FMU's messages in FMI 3.0's names; a step
    then: fmi3Error naming fmi3ExitInitializationMode."""
    path3, path2 = fmus("fig13")
    answers = []
    for cls, path in ((Instance3, path3), (Instance, path2)):
        late = {"init": False} if cls is Instance3 else {"initialise": False}
        with cls(path, "bad", **late) as inst:
            got = []
            for call in (lambda: inst.set("mu", 0.0), inst.fmu.exitInitializationMode):
                with pytest.raises(FMICallException) as e:
                    call()
                got.append(e.value.status)
            got.append(inst.step(H))
            answers.append((got, inst.messages))
    assert answers[0][0] == answers[1][0] == [ERROR, ERROR, ERROR]
    assert answers[0][1] == in_fmi3_words(answers[1][1])
    assert "(fmi3ExitInitializationMode failed: " in answers[0][1][-1][1]
    assert any("mu = 0.0 is invalid: must be >= 1e-09" in m for _, m in answers[0][1])


# ---- FMU state --------------------------------------------------------------------------------
def test_fmu_state_round_trips_and_damaged_bytes_are_refused(fmus):
    """fmi3GetFMUState, steps, fmi3SetFMUState, the same steps: the same doubles;
    serialized into a fresh instance: the same doubles after the same steps. Bytes that are
    damaged (a flipped byte, truncated, extended), garbage or the FMI 2.0 native FMU's
    state (another instantiation token) are refused with fmi3Error naming the reason (the
    FMI 2.0 FMU's words, the call fmi3DeserializeFMUState), nothing changes, and the
    instance steps on."""
    path3, path2 = fmus("fig13")
    with Instance(path2, "i2") as b:
        b.set("Fx_ex", F)
        assert b.step(H) == OK
        foreign = b.serialize_state(b.get_state())
    with Instance3(path3) as a, Instance3(path3, "fresh") as fresh:
        for inst in (a, fresh):
            inst.set("Fx_ex", F)
            inst.set("My_ex", -0.1 * F * ex.Rx)
        for _ in range(3):
            assert a.step(H) == OK
        state, at = a.fmu.getFMUState(), a.time
        for _ in range(3):
            assert a.step(H) == OK
        first = a.outputs()
        a.fmu.setFMUState(state)
        a.time = at
        for _ in range(3):
            assert a.step(H) == OK
        assert a.outputs() == first
        data = a.fmu.serializeFMUState(state)
        fresh.fmu.setFMUState(fresh.fmu.deserializeFMUState(data))
        fresh.time = at
        for _ in range(3):
            assert fresh.step(H) == OK
        assert fresh.outputs() == first
        flipped = bytearray(data)
        flipped[len(data) // 2] ^= 0x08
        length = words.LENGTH_DIFFERS(expected=words.LENGTH_OF_STATES())
        cases = {
            "flipped": (bytes(flipped), words.CHECKSUM_DIFFERS()),
            "truncated": (data[:-20], length),
            "extended": (data + b"x", length),
            "garbage": (b"garbage", words.NOT_SERIALIZED()),
            "fmi2": (foreign, words.OTHER_FMU()),
        }
        for case, (raw, reason) in cases.items():
            before = a.outputs()
            with pytest.raises(FMICallException) as e:
                a.fmu.deserializeFMUState(raw)
            assert e.value.status == ERROR, case
            assert a.messages[-1] == (
                ERROR,
                f"fmi3DeserializeFMUState: the {len(raw)} bytes are refused: {reason}",
            ), case
            assert a.outputs() == before
            assert a.step(H) == OK
        a.fmu.freeFMUState(state)
        assert all(s < FATAL for s, _ in a.messages)


# ---- directional and adjoint derivatives ------------------------------------------------------
def test_contact_derivatives_are_the_fmi2_fmus(fmus):
    """The full contact FMU (a force element) at rolling with creep, lateral slip and spin:
    fmi3GetDirectionalDerivative gives the FMI 2.0 FMU's doubles for every column of the
    Jacobian of the outputs along the inputs (the same C), and fmi3GetAdjointDerivative
    gives seed^T J summed in the order of the unknowns, exactly (no contraction:
    -ffp-contract=off). The Jacobian is not trivial: dTx/dVx > 0 (Tx, the force the
    body exerts on the substrate, grows with the creep vx = Vx - Rx Omega_y > 0) and the
    spin moves Mz."""
    path3, path2 = fmus("full_contact")
    inputs = {"Vx": 5.0, "Omega_y": 4.99 / 0.05, "Vy": 0.003, "Omega_z": 0.4, "P": 900.0}
    with Instance3(path3, start=inputs) as a, Instance(path2, "i2", inputs) as b:
        knowns = [a.vars[n].valueReference for n in ("Vx", "Vy", "Omega_y", "Omega_z", "P")]
        unknowns = [
            v.valueReference
            for v in a.md.modelVariables
            if v.causality == "output" and v.type == "Float64" and not v.dimensions
        ]
        J3, J2 = [], []
        for k in knowns:
            J3.append(a.fmu.getDirectionalDerivative(unknowns, [k], [1.0]))
            J2.append(b.fmu.getDirectionalDerivative(unknowns, [k], [1.0]))
        assert J3 == J2
        J = np.array(J3).T  # rows: unknowns, columns: knowns
        assert np.all(np.isfinite(J)) and np.count_nonzero(J) > len(knowns)
        names = [v.name for v in a.md.modelVariables if v.valueReference in unknowns]
        assert J[names.index("Tx"), 0] > 0.0 and J[names.index("Mz"), 3] != 0.0
        seed = [math.cos(i + 1.0) for i in range(len(unknowns))]
        # one sensitivity per known (fmpy's default length is the unknowns')
        adjoint = a.fmu.getAdjointDerivative(unknowns, knowns, seed, len(knowns))
        expected = []
        for j in range(len(knowns)):
            s = 0.0
            for i in range(len(unknowns)):
                s += seed[i] * J3[j][i]
            expected.append(s)
        assert adjoint == expected


def test_derivatives_outside_the_contact_mode_are_refused_naming_why(fmus):
    path3, _ = fmus("fig13")
    with Instance3(path3) as a:
        vx, fx = a.vars["Vx"].valueReference, a.vars["Fx_ex"].valueReference
        for fn in (a.fmu.getDirectionalDerivative, a.fmu.getAdjointDerivative):
            with pytest.raises(FMICallException) as e:
                fn([vx], [fx], [1.0])
            assert e.value.status == ERROR
            assert "provided by the contact mode only" in a.messages[-1][1]


# ---- the traction along the centre line (FMI 3.0 arrays) ---------------------------------------
LAW = ("P", "Rx", "Ry", "k1", "k2", "kb", "ks", "mu")


def _line(inst) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    return tuple(inst.array(name) for name, _, _ in model_description3.LINE)


def test_centre_line_is_eq_36_in_the_adhesion_area_and_the_laws_field(fmus):
    """Fig. 13's body under a traction force (partial slip, no spin): along the centre line
    y = 0 the traction is Eq. (36) where the material adheres, tau_x = vx (l - x)/(|Vx| k)
    from the leading edge l = a1 (Vx > 0, k = kb + ks), and mu p(x) = mu p0 (1 - (x/a1)^2)
    where it slips (Eqs. 4-5); the cells are thin_layer.LayerContact.traction's (nx = 41, ny = 1)
    and so is the whole field. The C march and the Python one run the same recurrence of
    41 projections on the same doubles, so they agree to rounding: 1e-12 mu p0 covers a
    few ulp per step."""
    path3, _ = fmus("fig13")
    with Instance3(path3) as a:
        a.set("Fx_ex", 0.8 * 0.3 * 1000.0)  # 0.8 mu P: an adhesion area and a slip area
        for _ in range(40):
            assert a.step(H) == OK
        x, tx, ty = _line(a)
        law = LayerContact(**{n: a.get(n) for n in LAW})
        Vx, vx, k = a.get("Vx"), a.get("vx"), a.get("kb") + a.get("ks")
        ref = law.traction(vx, 0.0, Vx, nx=model_description3.LINE_N, ny=1)
    cap = law.mu * law.p0 * np.maximum(1.0 - (x / law.a1) ** 2, 0.0)
    np.testing.assert_allclose(x, ref.x, rtol=1e-14, atol=0.0)
    scale = law.mu * law.p0
    assert np.max(np.abs(tx - ref.tau_x[0])) <= 1e-12 * scale and not np.any(ty)
    assert np.all(np.abs(tx) <= cap * (1 + 1e-12))
    stick = tx < cap * (1 - 1e-9)
    assert 1 < np.count_nonzero(stick) < 40  # partial slip: both areas on the line
    eq36 = vx * (law.a1 - x) / (abs(Vx) * k)
    np.testing.assert_allclose(tx[stick], eq36[stick], rtol=1e-12)
    np.testing.assert_allclose(tx[~stick], cap[~stick], rtol=1e-12)


def test_centre_line_with_spin_at_standstill_and_lifted_off(fmus):
    """The full contact FMU (inputs are the kinematics): with lateral creep and spin the
    line is the law's field (the strip march, Eqs. 35 and 3 with phi = Omega_z); at
    standstill (Vx = 0) every point slides, tau = mu p v/|v| with v = vx + i (vy + phi x)
    (Eq. 5), so |tau| = mu p(x); lifted off (P = 0) there is no traction. Each read
    follows the inputs set since the last (no step in contact mode)."""
    path3, _ = fmus("full_contact")
    kin = {"Vx": 5.0, "Omega_y": 4.99 / 0.05, "Vy": 0.003, "Omega_z": 0.4, "P": 900.0}
    with Instance3(path3, start=kin) as a:
        law = LayerContact(**{n: a.get(n) for n in LAW})
        vx = kin["Vx"] - a.get("Rx") * kin["Omega_y"]
        x, tx, ty = _line(a)
        ref = law.traction(vx, kin["Vy"], kin["Vx"], nx=model_description3.LINE_N, ny=1,
                           phi=kin["Omega_z"])  # fmt: skip
        scale = law.mu * law.p0
        assert np.max(np.abs(tx - ref.tau_x[0])) <= 1e-12 * scale
        assert np.max(np.abs(ty - ref.tau_y[0])) <= 1e-12 * scale
        assert np.any(ty != 0.0)
        a.set("Vx", 0.0)
        a.set("Omega_y", 0.0)  # standstill, the wheel turned by nothing: vx = 0
        x, tx, ty = _line(a)
        cap = law.mu * law.p0 * np.maximum(1.0 - (x / law.a1) ** 2, 0.0)
        v = 0.0 + 1j * (kin["Vy"] + kin["Omega_z"] * x)
        np.testing.assert_allclose(tx + 1j * ty, cap * v / np.abs(v), rtol=1e-14, atol=0.0)
        a.set("P", 0.0)
        assert not any(np.any(arr) for arr in _line(a))


def test_centre_line_refusals(fmus):
    """An array read with too few values, an array set, or read before the model is set
    up: fmi3Error, a message that says why, the instance usable after."""
    path3, _ = fmus("fig13")
    with Instance3(path3, init=False) as a:
        vr = a.vars["tau_x_centre"].valueReference
        with pytest.raises(FMICallException):
            a.fmu.getFloat64([vr], nValues=model_description3.LINE_N)
        assert "read it after" in a.messages[-1][1]
        a.fmu.exitInitializationMode()
        a.initialised = True
        with pytest.raises(FMICallException):
            a.fmu.getFloat64([vr], nValues=1)
        assert "41 per array of the centre line" in a.messages[-1][1]
        with pytest.raises(FMICallException):
            a.fmu.setFloat64([vr], [0.0] * model_description3.LINE_N)
        assert "is an output of this FMU" in a.messages[-1][1]
        assert a.step(H) == OK and np.all(np.isfinite(_line(a)[1]))


# ---- resources ---------------------------------------------------------------------------------
def test_table_resource_is_found_under_a_path_with_spaces_and_percent_signs(fmus, tmp_path):
    """FMI 3.0 hands a native resource path; fmi3.c makes the file URI the layer reads,
    percent-encoding what a URI cannot hold: the creep-force table loads from a folder
    named "a b%20c" and the scene's first step runs."""
    path3, _ = fmus("rail_traction")
    odd = tmp_path / "a b%20c"
    odd.mkdir()
    shutil.copy(path3, odd / "rail.fmu")
    with Instance3(odd / "rail.fmu") as a:
        assert a.step(1e-4) == OK, a.messages
        assert all(math.isfinite(v) for v in a.outputs().values())


# ---- a C importer, sanitizers ------------------------------------------------------------------
IMPORTER = native_c.IMPORTER3
_spec, _compile = native_c.spec, native_c.compile_c


@pytest.fixture(scope="module")
def fig13_case(fmus, tmp_path_factory):
    """Fig. 13, eta = 3: the extracted FMI 3.0 FMU, its spec, and the FMI 2.0 native FMU's
    outputs with the input table's row k held over step k (through fmpy)."""
    scene = load(ROOT / "scenarios" / "fig13.toml")
    case = scene.case("eta = 3")
    path3, path2 = fmus("fig13")
    tmp = tmp_path_factory.mktemp("fig13_3")
    unzip = tmp / "fmu"
    fmpy.extract(str(path3), str(unzip))
    md = fmpy.read_model_description(str(unzip))
    spec = tmp / "spec.txt"
    spec.write_text(_spec(md, scene, case))
    from test_native_fmu import _instance_run

    # the importer prints the time after each step beside the outputs
    after = np.asarray(scene.grid[:-1], dtype=float) + scene.step
    return unzip, md, spec, np.column_stack([_instance_run(path2, scene, case), after])


def _run(exe: Path, lib: Path | str, md, *args: str, ok: bool = True) -> str:
    proc = subprocess.run(
        [str(exe), str(lib), md.guid, *args], capture_output=True, text=True, timeout=300
    )
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert "runtime error" not in proc.stderr and "Sanitizer" not in proc.stderr
    return proc.stdout


def _rows(text: str) -> np.ndarray:
    return np.array([[float.fromhex(x) for x in line.split()] for line in text.splitlines()])


def test_a_c_importer_without_python_runs_fig13_to_the_fmi2_fmus_numbers(fig13_case, tmp_path):
    """A plain C FMI 3.0 importer (dlopen, the FMI 3.0 calls; no libpython: it needs no
    Python symbol) runs the Fig. 13 case eta = 3 on the binary: every step's outputs are
    the FMI 2.0 native FMU's doubles, lastSuccessfulTime is t + h."""
    unzip, md, spec, expected = fig13_case
    exe = _compile(tmp_path / "importer3", str(IMPORTER), "-ldl")
    undefined = subprocess.run(
        ["nm", "-D", "--undefined-only", str(exe)], capture_output=True, text=True, check=True
    ).stdout
    assert "Py" not in undefined and "fmi2" not in undefined
    lib = unzip / "binaries" / native_fmu3.PLATFORM / f"{md.coSimulation.modelIdentifier}.so"
    got = _rows(_run(exe, lib, md, "run", str(spec)))
    assert got.shape == expected.shape and np.array_equal(got, expected)


@pytest.mark.skipif(shutil.which("cmake") is None, reason="no cmake")
def test_source_fmu_built_by_fmpy_from_its_build_description_gives_the_same_numbers(
    fig13_case, tmp_path
):
    """fmpy's build of a source FMU (cmake, its own CMakeLists and FMI headers, no
    visibility flag) from sources/buildDescription.xml alone, the shipped binary removed:
    it exports the FMI 3.0 functions only (the instance layer's are hidden by the sources
    themselves: CF_HIDDEN) and the
    C importer gets the same doubles from it."""
    from fmpy.build import build_platform_binary

    unzip, md, spec, expected = fig13_case
    copy = tmp_path / "fmu"
    shutil.copytree(unzip, copy)
    shutil.rmtree(copy / "binaries")
    (tmp_path / "build").mkdir()
    build_platform_binary(str(copy), str(tmp_path / "build"))
    lib = copy / "binaries" / native_fmu3.PLATFORM / f"{md.coSimulation.modelIdentifier}.so"
    exported = subprocess.run(
        ["nm", "-D", "--defined-only", str(lib)], capture_output=True, text=True, check=True
    ).stdout
    assert all(line.split()[-1].startswith("fmi3") for line in exported.splitlines())
    exe = _compile(tmp_path / "importer3", str(IMPORTER), "-ldl")
    assert np.array_equal(_rows(_run(exe, lib, md, "run", str(spec))), expected)


# the calls mode's answers: FMI 3.0 statuses (0 OK, 2 Discard, 3 Error; 0/1 for an instance)
CALLS = {
    "token": 0, "eventMode": 0, "modelExchange": 0, "doStep": 0, "setNaN": 3,
    "doStepHeld": 2, "getHeld": 3, "setGood": 0, "doStepAgain": 0, "nValues": 3,
    "getState": 0, "repeated": 1, "setState": 0, "stateSize": 0, "serialize": 0,
    "deserialize": 0, "freeBack": 0, "flipped": 3, "truncated": 3, "freeState": 0,
    "freeFreed": 0, "directional": 3, "adjoint": 3, "getFloat32": 3, "enterEventMode": 3,
    "enterStepMode": 3, "enterConfigurationMode": 3, "updateDiscreteStates": 3,
    "setTime": 3, "getClock": 3, "reset": 0, "enterInit": 0, "exitInit": 0,
    "doStepAfterReset": 0, "terminate": 0,
}  # fmt: skip


@pytest.mark.skipif(not native_c.HAS_VALGRIND, reason="no valgrind")
def test_memcheck_finds_no_error_in_the_shipped_binary(fig13_case, tmp_path):
    """The FMI 3.0 binary as shipped, dlopened by the plain C importer, under valgrind's
    memcheck: Fig. 13 to the FMI 2.0 FMU's doubles, the bad and unsupported calls with
    their statuses, 2000 random calls, with no invalid read or write, no use of an
    undefined value and no definite leak."""
    unzip, md, spec, expected = fig13_case
    exe = str(_compile(tmp_path / "importer3", str(IMPORTER), "-ldl"))
    lib = unzip / "binaries" / native_fmu3.PLATFORM / f"{md.coSimulation.modelIdentifier}.so"
    head = (exe, str(lib), md.guid)
    assert np.array_equal(_rows(native_c.memcheck(*head, "run", str(spec))), expected)
    short = tmp_path / "params.txt"
    scene = load(ROOT / "scenarios" / "fig13.toml")
    short.write_text(_spec(md, scene, scene.case("eta = 3"), rows=False))
    answers = dict(
        line.split() for line in native_c.memcheck(*head, "calls", str(short)).splitlines()
    )
    assert {k: int(answers[k]) for k in CALLS} == CALLS
    time_vr = str(model_description3.time_vr(scene.config))
    out = native_c.memcheck(*head, "fuzz", str(short), "0", "2000", time_vr).split()
    counts = {
        k: int(v)
        for k, v in zip(out[::2], out[1::2], strict=True)
        if k in ("ok", "discard", "error")
    }
    assert counts["ok"] > 500 and counts["discard"] + counts["error"] > 100, counts


def test_sanitized_importer_runs_fig13_bad_and_unsupported_calls_and_random_extremes_cleanly(
    fig13_case, tmp_path
):
    """The FMU's C sources (fmi3.c, instance.c, model.c, stepper.c) and the C importer in
    one program built with
    AddressSanitizer and UBSan (no recovery): Fig. 13 to the same doubles; the bad calls
    (another token, event mode, model exchange: no instance; a NaN input: fmi3Error, the
    step fmi3Discard, corrected fmi3OK; values not one per value reference; a state got,
    set, serialized, deserialized, a flipped and a truncated copy refused; the derivatives
    outside contact mode, the other types, event mode, configuration mode, clocks, model
    exchange: fmi3Error, logged; reset and a new start) with the expected statuses; then
    2 x 2000 random calls with extreme values, steps and states: no sanitizer report, no
    fmi3Fatal, no non-finite output served with fmi3OK, no flag of doStep set."""
    unzip, md, spec, expected = fig13_case
    try:
        exe = native_c.sanitized(tmp_path / "imp3_asan", IMPORTER, unzip)
    except subprocess.CalledProcessError as e:  # pragma: no cover - gcc without libasan
        pytest.skip(f"no sanitizer runtime: {e.stderr[-300:]}")
    assert np.array_equal(_rows(_run(exe, "-", md, "run", str(spec))), expected)
    short = tmp_path / "params.txt"
    scene = load(ROOT / "scenarios" / "fig13.toml")
    short.write_text(_spec(md, scene, scene.case("eta = 3"), rows=False))
    lines = _run(exe, "-", md, "calls", str(short)).splitlines()
    answers = dict(line.split() for line in lines)
    assert {k: int(answers[k]) for k in CALLS} == CALLS
    assert float.fromhex(answers["lastSuccessfulTime"]) == H  # the discarded step's start
    # each refusal logged once: the three instantiations, every Discard and Error
    refusals = 3 + sum(v >= DISCARD for k, v in CALLS.items() if k != "repeated")
    assert int(answers["messages"]) == refusals == 18
    time_vr = str(model_description3.time_vr(scene.config))
    counts = {"ok": 0, "discard": 0, "error": 0}
    for seed in range(2):
        out = _run(exe, "-", md, "fuzz", str(short), str(seed), "2000", time_vr).split()
        for k, v in dict(zip(out[::2], out[1::2], strict=True)).items():
            if k in counts:
                counts[k] += int(v)
    assert counts["ok"] > 1000 and counts["discard"] > 100 and counts["error"] > 100, counts
