"""The native FMU (fmu_build --native: the FMI 2.0 front end fmi2.c on the instance layer
instance.c, the model model.c and the compiled stepper, no Python on the target) against
the pythonfmu FMU and the scenes' references.

Both FMUs run the same C step (stepper.c's cf_advance and cf_body_outputs), the native
one with the law's and the body's constants derived in C (cf_layer_law, cf_body_inertia)
from the same expressions as laws/thin_layer.py and dynamics/body.py: their outputs must be the same
doubles, step for step. Tests that need a C compiler, cmake or a sanitizer skip only
where the tool is missing (CI has them all).
"""

from __future__ import annotations

import ctypes
import itertools
import math
import os
import re
import shutil
import subprocess
import sys
import threading
import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path

import native_c
import numpy as np
import pytest

import fmu_build
from contact_fmu import examples as ex
from contact_fmu import native
from contact_fmu.dynamics.body import Body
from contact_fmu.fmu.config import ModelConfig
from contact_fmu.fmu.state_bytes import CORE_MAGIC
from contact_fmu.laws.thin_layer import LayerContact
from contact_fmu.scenario import load, runner
from contact_fmu.scenario.instance import DISCARD, ERROR, FATAL, OK, Instance
from fmu_build import native_fmu

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "out" / "fmu"
SCENES = ("fig13", "brake", "fig12", "railway", "sweep", "cornering", "rail_creep", "rail_traction")
F = ex.force_unit()
MU_P = ex.mu * ex.P

needs_cc = pytest.mark.skipif(shutil.which("cc") is None, reason="no C compiler")
pytestmark = needs_cc


@pytest.fixture(scope="session")
def scenes():
    return {n: load(ROOT / "scenarios" / f"{n}.toml") for n in SCENES}


@pytest.fixture(scope="session")
def native_fmus(scenes) -> dict[str, Path]:
    return {n: native_fmu.build(s.config, OUT).path for n, s in scenes.items()}


@pytest.fixture(scope="session")
def python_fmus(scenes) -> dict[str, Path]:
    return {n: fmu_build.build(s.config, OUT).path for n, s in scenes.items()}


# ---- the scenes ----------------------------------------------------------------------------
@pytest.mark.parametrize("name", SCENES)
def test_scene_through_the_native_fmu_passes_its_references_bit_for_bit(
    scenes, native_fmus, python_fmus, name
):
    """Every steady scene the native FMU covers: its references pass, and each output of
    each step is the pythonfmu FMU's double where both run stepper.c's step (body mode;
    cornering: Eqs. 10-11 with the law's spin grid built in C, cf_grid_build, to numpy's
    doubles); the contact mode's pythonfmu FMU evaluates the law in Python, whose
    math.hypot is not the C library's, and the adhesion with spin sums its grid in
    another order than numpy: there the two agree to 1e-12 of each output's scale (bit
    for bit without lateral slip, where hypot(vx, 0) = |vx| in both)."""
    scene = scenes[name]
    got = runner.simulate(native_fmus[name], scene)
    ref = runner.simulate(python_fmus[name], scene)
    for a, b in zip(got, ref, strict=True):
        assert a.error is None and b.error is None, (a.error, b.error)
        exact = scene.config.mode == "body" or not np.any(b.columns.get("Vy", 0.0))
        for k in b.columns:
            x, y = a.columns[k], b.columns[k]
            if exact and not (k == "adhesion" and scene.config.spin != "zero"):
                assert np.array_equal(x, y), (name, a.case, k)
            else:
                assert np.max(np.abs(x - y)) <= 1e-12 * np.max(np.abs(y)), (name, a.case, k)
    checks = runner.compare(scene, got)
    assert checks and all(c.ok for c in checks), [c for c in checks if not c.ok]


def test_law_and_body_constants_in_c_are_pythons_doubles():
    """The contact ellipse and the law's constants (Eqs. 33-34, creep_full_slip and
    beta per creepage: LayerContact.native_fields, a2, p0) and the body's A1, A2, M A2
    (Eq. 23), derived in C for every new load, equal thin_layer.py's and body.py's bit for
    bit over random parameters spanning twelve decades."""
    lib = native.library()
    lib.cf_layer_law.argtypes = (
        [ctypes.POINTER(native.Params)]
        + [ctypes.c_double] * 8
        + [ctypes.POINTER(ctypes.c_double)] * 2
    )
    lib.cf_body_inertia.argtypes = [ctypes.POINTER(native.Params)] + [ctypes.c_double] * 3
    rng = np.random.default_rng(3)
    for _ in range(300):
        P, Rx, Ry, M = 10 ** rng.uniform([-1, -3, -3, -2], [6, 1, 1, 3])
        k1, k2, kb, ks = 10 ** rng.uniform(-16, -8, 4)
        mu, Iy = rng.uniform(0.01, 1.0), float(rng.choice([0.0, 10 ** rng.uniform(-6, 1)]))
        law = LayerContact(P, Rx, Ry, k1, k2, kb, ks, mu)
        p = native.Params(beta_full_slip=LayerContact.native_constants["beta_full_slip"])
        a2, p0 = ctypes.c_double(), ctypes.c_double()
        lib.cf_layer_law(p, P, Rx, Ry, k1, k2, kb, ks, mu, a2, p0)
        for k, v in law.native_fields().items():
            assert getattr(p, k) == v, k
        assert (a2.value, p0.value) == (law.a2, law.p0)
        body = Body(M, Rx, Iy)
        lib.cf_body_inertia(p, M, Rx, Iy)
        assert (p.A1, p.A2, p.m_slip) == (body.A1, body.A2, body.m_slip)


# ---- model description, build ----------------------------------------------------------------
def _md(path: Path) -> ET.Element:
    with zipfile.ZipFile(path) as z:
        return ET.fromstring(z.read("modelDescription.xml"))


@pytest.mark.parametrize("name", ["fig13", "railway", "sweep"])
def test_model_description_is_the_pythonfmu_ones_and_validates(native_fmus, python_fmus, name):
    """Generated from the same declarations: the same variables (names, value
    references, causality, variability, units, ranges, starts), unit definitions and
    ModelStructure; the native one needs no execution tool, handles and serializes its
    state, lists its C sources; fmpy's validation finds no problem."""
    from fmpy.validation import validate_fmu

    a, b = _md(native_fmus[name]), _md(python_fmus[name])
    for tag in ("ModelVariables", "ModelStructure", "UnitDefinitions", "DefaultExperiment"):
        ea, eb = a.find(tag), b.find(tag)
        assert (ea is None) == (eb is None), tag
        if ea is not None:
            assert ET.tostring(ea) == ET.tostring(eb), tag
    cs = a.find("CoSimulation")
    assert cs.get("needsExecutionTool") == "false"
    assert cs.get("canGetAndSetFMUstate") == "true" and cs.get("canSerializeFMUstate") == "true"
    listed = [f.get("name") for f in cs.find("SourceFiles")]
    assert listed == list(native_fmu.c_files()) and "stepper.c" in listed
    with zipfile.ZipFile(native_fmus[name]) as z:
        names = set(z.namelist())
    carried = (*native_fmu.SOURCES, "cf_model.h")
    assert {f"sources/{n}" for n in carried} <= names
    assert not any(n.endswith(".h") and "fmi2" in n for n in names)  # fmpy's headers
    assert validate_fmu(str(native_fmus[name])) == []


def test_guid_follows_the_model(scenes):
    """The GUID is a content key: the same model gives the same GUID, a changed start
    value another one."""
    cfg = scenes["fig13"].config
    other = ModelConfig.from_dict(cfg.to_dict() | {"starts": {**cfg.starts, "mu": 0.25}})
    assert native_fmu.identity(cfg) == native_fmu.identity(ModelConfig.from_dict(cfg.to_dict()))
    assert native_fmu.identity(cfg) != native_fmu.identity(other)


def test_guid_follows_the_creep_force_table(scenes, monkeypatch):
    """A half-space FMU carries its table's data as a resource, which the variables'
    header does not describe: another table (a changed solver, numpy or scipy: the
    table's key) is another FMU, never a cached one with the old data."""
    from fmu_build import tables

    cfg = scenes["rail_creep"].config
    before = native_fmu.identity(cfg)
    key, law = tables.key(cfg), native_fmu._table_law(cfg)
    monkeypatch.setattr(native_fmu, "_table_law", lambda c: law)  # the same header
    other = ("1" if key[0] == "0" else "0") + key[1:]  # another table's data (its key)
    monkeypatch.setattr(tables, "key", lambda c: other)
    assert native_fmu.identity(cfg) != before


def test_rigid_body_fmu_steps_eqs_8_9_to_the_pythonfmu_doubles(tmp_path):
    """The full rigid_body FMU (Eqs. 8-9 under held inputs, exact for held Tx), native and
    pythonfmu, under the same changing inputs: the same doubles; Iy = 0 cannot start."""
    from fmpy.fmi1 import FMICallException

    cfg = ModelConfig.full("rigid_body")
    paths = (native_fmu.build(cfg, OUT).path, fmu_build.build(cfg, OUT).path)
    results = []
    for path in paths:
        with Instance(path, "rb", {"Iy": 2e-4}) as b:
            rows = []
            for k in range(50):
                b.set("Tx", 80.0 * math.sin(k / 7))
                b.set("Fx_ex", 100.0)
                b.set("My_ex", -2.0 + 0.1 * k)
                assert b.step(1e-4) == OK
                rows.append((b.get("Vx"), b.get("Omega_y")))
            results.append(rows)
    assert results[0] == results[1]
    with pytest.raises(FMICallException):
        Instance(paths[0], "rb", {"Iy": 0.0})
    from fmpy.validation import validate_fmu

    assert validate_fmu(str(paths[0])) == []


@pytest.fixture(scope="module")
def full_rigid() -> dict[str, Path]:
    """The full rigid_body FMU (Eqs. 8-9 alone) of both targets."""
    cfg = ModelConfig.full("rigid_body")
    return {"native": native_fmu.build(cfg, OUT).path, "pythonfmu": fmu_build.build(cfg, OUT).path}


@pytest.mark.parametrize("target", ["pythonfmu", "native"])
def test_rigid_body_step_beyond_the_physical_range_is_discarded_naming_it(full_rigid, target):
    """Eq. (8) under a held Tx drives Vx by h (Fx_ex - Tx)/M: a Tx of -2e7 N (or a huge
    finite 1e300, or loads whose difference overflows) would take Vx beyond SPEED_MAX =
    1e4 m/s, a moment of 1e300 N m Omega_y beyond RATE_MAX = 1e7 rad/s. Each step
    answers fmi2Discard with the body mode's words (ranges.within_range) naming the
    variable and the value Eq. (8) or (9) gives it, the same message on both targets;
    the outputs stay the last accepted step's; NaN/inf are refused at the setter; once
    corrected, the instance steps on by Eq. (8) exactly."""
    from fmpy.fmi1 import FMICallException

    from contact_fmu.fmu.variables import RATE_MAX, SPEED_MAX

    h, Fx, M, Rx, Iy = 1e-3, 10.0, 1.0, 0.05, 2e-4
    with Instance(full_rigid[target], "rb", {"M": M, "Rx": Rx, "Iy": Iy}) as b:
        b.set("Fx_ex", Fx)
        b.set("Tx", 0.0)
        assert b.step(h) == OK and b.step(h) == OK
        before = b.outputs()
        V, W = before["Vx"], before["Omega_y"]
        # (inputs, the variable named, the value Eq. (8) or (9) gives it, its bound)
        cases = [
            ({"Tx": -2e7}, "Vx", V + h * (Fx + 2e7) / M, SPEED_MAX),
            ({"Tx": 1e300}, "Vx", V + h * (Fx - 1e300) / M, SPEED_MAX),
            ({"Fx_ex": 1e308, "Tx": -1e308}, "Vx", math.inf, SPEED_MAX),  # overflows
            ({"Fx_ex": Fx, "Tx": 0.0, "My_ex": 1e300}, "Omega_y", W + h * 1e300 / Iy, RATE_MAX),
        ]
        for inputs, name, value, bound in cases:
            for k, x in inputs.items():
                b.set(k, x)
            assert b.step(h) == DISCARD
            assert abs(value) > bound
            assert b.messages[-1] == (
                DISCARD,
                f"doStep at t = {b.time!r} with h = {h!r} discarded, state unchanged: "
                f"{name} = {value!r} is invalid: must be within abs <= {bound:g} (the loads "
                "drive the body beyond it)",
            )
            assert b.outputs() == before
        with pytest.raises(FMICallException) as e:  # not finite: refused at the setter
            b.set("Tx", math.inf)
        assert e.value.status == ERROR
        assert b.step(h) == DISCARD and "Tx = inf is invalid" in b.messages[-1][1]
        assert b.outputs() == before
        b.set("Tx", 0.0)
        b.set("My_ex", 0.0)
        assert b.step(h) == OK
        assert b.outputs() == {"Vx": V + h * Fx / M, "Omega_y": W}


@pytest.mark.parametrize(
    ("scene", "feature"),
    [
        ("many_loads", "(more than 16 load nodes"),
        ("transient_big", 'phase = "transient" on a 128 x 64 field'),
    ],
)
def test_models_the_c_kernel_does_not_cover_are_refused_naming_the_feature(scene, feature):
    if scene.startswith("full_"):
        cfg = ModelConfig.full(scene[5:])
    elif scene == "many_loads":  # refused before its table is built
        d = load(ROOT / "scenarios" / "rail_creep.toml").config.to_dict()
        spec = d["law_spec"] | {"loads": [50.0e3 + 5e3 * k for k in range(17)]}
        cfg = ModelConfig.from_dict(d | {"law_spec": spec})
    elif scene.startswith("transient_"):  # fig12_transient itself is native (its own tests)
        d = load(ROOT / "scenarios" / "fig12_transient.toml").config.to_dict()
        change = {"starts": d["starts"] | {"nx": 128, "ny": 64}}
        cfg = ModelConfig.from_dict(d | change)
    else:
        cfg = load(ROOT / "scenarios" / f"{scene}.toml").config
    with pytest.raises(native_fmu.NativeUnsupportedError, match=re.escape(feature)):
        native_fmu.build(cfg, OUT)


@pytest.fixture(scope="module")
def full_body() -> dict[str, Path]:
    """The full body FMU (Eqs. 10-11, both methods and both schemes) of both targets."""
    cfg = ModelConfig.full("body")
    return {"native": native_fmu.build(cfg, OUT).path, "pythonfmu": fmu_build.build(cfg, OUT).path}


def test_full_body_fmu_runs_both_schemes_and_methods_to_the_pythonfmu_doubles(full_body):
    """The full body FMU, Eqs. (8)-(11) with the law's spin (stepper.c's vector step on
    both targets), validates, has the pythonfmu FMU's variables (the String parameters
    method and scheme among them) and structure, and for each method and scheme
    20 communication steps under swept lateral loads give the pythonfmu FMU's doubles;
    the adhesion with spin sums the grid in another order than numpy's (1e-12). The
    scheme is honoured: in the slip transient after the load is applied (internal steps
    of 6 tau_r, where Lobatto IIIC's R(z) is 0.04 and SDIRK2's -0.20) their Tx differ by
    more than 1e-4 mu P (measured: 5e-4 mu P at the first step)."""
    from fmpy.validation import validate_fmu

    assert validate_fmu(str(full_body["native"])) == []
    a, b = _md(full_body["native"]), _md(full_body["pythonfmu"])
    for tag in ("ModelVariables", "ModelStructure"):
        assert ET.tostring(a.find(tag)) == ET.tostring(b.find(tag)), tag
    runs = {}
    for method, scheme in itertools.product(("full", "quasistationary"), ("lobatto3c", "sdirk2")):
        for target, path in full_body.items():
            rows = []
            with Instance(path, target, {"method": method, "scheme": scheme}) as b:
                names = list(b.outputs())
                for k in range(20):
                    s = math.sin(k / 5)
                    b.set("Fx_ex", 0.3 * MU_P)
                    b.set("Fy_ex", 0.3 * MU_P * s)
                    b.set("Mz_ex", 5e-5 * MU_P * s)
                    assert b.step(2.5e-4) == OK, b.messages[-1:]
                    rows.append([b.get(n) for n in names])
                assert (b.get("method"), b.get("scheme")) == (method, scheme)
            runs[method, scheme, target] = dict(zip(names, np.array(rows).T, strict=True))
        got, ref = runs[method, scheme, "native"], runs[method, scheme, "pythonfmu"]
        for n in names:
            if n == "adhesion":
                assert np.max(np.abs(got[n] - ref[n])) <= 1e-12
            else:
                assert np.array_equal(got[n], ref[n]), (method, scheme, n)
        assert np.any(got["Omega_z"] != 0.0) and np.any(got["Vy"] != 0.0)
    lob, sd = runs["full", "lobatto3c", "native"], runs["full", "sdirk2", "native"]
    assert np.max(np.abs(lob["Tx"] - sd["Tx"])) > 1e-4 * MU_P


@pytest.mark.parametrize("target", ["pythonfmu", "native"])
def test_a_bad_scheme_is_refused_naming_it_until_corrected(full_body, target):
    """scheme = 'rk4': refused with RollingBody's words at setString by both targets,
    no initialisation with it; corrected, the model starts and steps."""
    from fmpy.fmi1 import FMICallException

    with Instance(full_body[target], "bad", initialise=False) as b:
        with pytest.raises(FMICallException) as e:
            b.set("scheme", "rk4")
        assert e.value.status == ERROR
        with pytest.raises(FMICallException):
            b.initialise()
        want = """scheme = 'rk4' is invalid: must be "lobatto3c" or "sdirk2\""""
        assert any(want in m for _, m in b.messages), b.messages
        b.set("scheme", "sdirk2")
        b.initialise()
        assert b.step(1e-4) == OK and b.get("scheme") == "sdirk2"


def test_command_line_prints_the_fmu_path_last(native_fmus):
    cmd = [sys.executable, "-m", "fmu_build", "--native", "scenarios/fig13.toml", "--out", str(OUT)]
    proc = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    printed = Path(proc.stdout.splitlines()[-1])  # the stable path, the latest build's bytes
    assert printed == OUT / "fig13_native.fmu"
    assert printed.read_bytes() == native_fmus["fig13"].read_bytes()
    cmd[4] = "scenarios/fig12_transient.toml"  # every shipped scene builds native
    proc = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    assert Path(proc.stdout.splitlines()[-1]) == OUT / "fig12_transient_native.fmu"


# ---- call by call, both targets ------------------------------------------------------------------
# The pythonfmu FMU (its adapter slave.py, with the FMI calls of native/fmi.c) and the
# native FMU (instance.c) make the same checks in the same C (cf_core.h, stepper.c's
# cf_body_check): the bad-input and FMU-state tests run against both.
H = 1.75e-4  # s, the Fig. 13 scene's communication step


@pytest.fixture(params=["pythonfmu", "native"])
def fig13(request, native_fmus, python_fmus) -> Path:
    return (native_fmus if request.param == "native" else python_fmus)["fig13"]


def body(path: Path, **params) -> Instance:
    """The Fig. 13 FMU (eta = 3) under Fx_ex = F, My_ex = -0.1 F Rx."""
    inst = Instance(path, "body", params)
    inst.set("Fx_ex", F)
    inst.set("My_ex", -0.1 * F * ex.Rx)
    return inst


def steps(inst: Instance, n: int, h: float = 1.75e-4) -> None:
    for _ in range(n):
        assert inst.step(h) == OK, inst.messages[-1:]


@pytest.mark.parametrize(
    ("name", "value", "requirement"),
    [
        ("Fx_ex", math.nan, "finite"),
        ("My_ex", math.inf, "finite"),
        ("My_ex", -math.inf, "finite"),
        ("P", math.nan, "finite"),
        ("My_ex", 6e306, None),  # finite: the step itself fails (the drive overflows)
        ("Fx_ex", 1.2e308, None),
        ("P", -5e-324, ">= 0 (lift-off, no contact, is P = 0)"),  # P = 0 is lift-off
        ("P", -5.0, ">= 0 (lift-off, no contact, is P = 0)"),
    ],
)
def test_bad_input_gives_discard_a_named_message_and_recovery(fig13, name, value, requirement):
    """A bad or impossible input: fmi2Error at its setReal where its declared range
    refuses it, and doStep answers fmi2Discard with a message naming the variable and
    the value (or the failed step), the outputs stay, and once the input is corrected
    the instance steps to the same doubles as one that never saw it."""
    from fmpy.fmi1 import FMICallException

    with body(fig13) as clean:  # one at a time: pythonfmu logs to the last instance
        steps(clean, 3)
        expected = clean.outputs()
    with body(fig13) as b:
        steps(b, 1)
        good, before = b.get(name), b.outputs()
        try:
            b.set(name, value)
            assert requirement is None  # out of the declared range: refused at once
        except FMICallException as e:
            assert requirement is not None and e.status == ERROR
        assert b.step(1.75e-4) == DISCARD
        if requirement is not None:
            text = f"{name} = {value!r} is invalid: must be {requirement}"
            assert any(text in m for s, m in b.messages if s == DISCARD), b.messages
        else:
            assert any("discarded, state unchanged" in m for s, m in b.messages if s == DISCARD)
        assert b.outputs() == before
        b.set(name, good)
        steps(b, 2)
        assert b.outputs() == expected
        assert all(s < FATAL for s, _ in b.messages)


@pytest.mark.parametrize("h", [0.0, -1.75e-4, math.nan, math.inf])
def test_a_step_not_in_0_inf_gives_discard(fig13, h):
    with body(fig13) as b:
        assert b.step(h) == DISCARD
        assert f"communicationStepSize = {h!r} is invalid" in b.messages[-1][1]
        assert b.step(1.75e-4) == OK


def test_a_step_not_at_the_fmu_time_gives_discard(fig13):
    with body(fig13) as b:
        steps(b, 1)
        assert b.step(H, time=10 * H) == DISCARD
        text = f"currentCommunicationPoint = {10 * H!r} is invalid: must be the FMU's time {H!r}"
        assert b.messages[-1] == (DISCARD, text)
        steps(b, 1)


@pytest.mark.parametrize(
    ("name", "value", "good", "fragment"),
    [
        ("mu", 0.0, ex.mu, "mu = 0.0 is invalid: must be >= 1e-09"),
        ("mu", -0.3, ex.mu, "mu = -0.3 is invalid: must be >= 1e-09"),
        ("Rx", math.nan, ex.Rx, "Rx = nan is invalid: must be finite"),
        ("h_max", 0.0, H / 4, "h_max = 0.0 is invalid: must be > 0"),
        ("M", math.inf, ex.M, "M = inf is invalid: must be finite"),
    ],
)
def test_bad_parameter_gives_error_until_corrected(fig13, name, value, good, fragment):
    """A parameter out of its range: fmi2Error at its setter and at
    exitInitializationMode (the model cannot start), naming it; doStep before a
    successful initialisation answers fmi2Error naming the reason; corrected, the model
    starts and steps to the doubles of one that never saw the bad value."""
    from fmpy.fmi1 import FMICallException

    with body(fig13) as fresh:
        steps(fresh, 1)
        expected = fresh.outputs()
    with Instance(fig13, "bad", {"h_max": H / 4}, initialise=False) as b:
        for call in (lambda: b.set(name, value), b.initialise):
            with pytest.raises(FMICallException) as e:
                call()
            assert e.value.status == ERROR
        assert any(fragment in m for _, m in b.messages), b.messages
        assert b.step(H) == ERROR
        refused = "doStep at t = 0.0 refused: called before the model is initialised "
        assert b.messages[-1] == (
            ERROR,
            f"{refused}(fmi2ExitInitializationMode failed: {fragment})",
        )
        assert all(math.isfinite(v) for v in b.outputs().values())
        b.set(name, good)  # the model is not set up: the parameter may still change
        b.initialise()
        b.set("Fx_ex", F)
        b.set("My_ex", -0.1 * F * ex.Rx)
        steps(b, 1)
        assert b.outputs() == expected


def test_a_step_before_initialisation_or_after_terminate_is_an_error(fig13):
    with Instance(fig13, "early", initialise=False) as b:
        assert b.step(H) == ERROR
        assert "(fmi2ExitInitializationMode not called)" in b.messages[-1][1]
    with body(fig13) as b:
        steps(b, 1)
        b.fmu.terminate()
        assert b.step(H) == ERROR
        assert b.messages[-1] == (ERROR, f"doStep at t = {H!r} refused: called after fmi2Terminate")


def _phase_calls(b: Instance, calls: list[str]) -> tuple[list[int], list[tuple[int, str]]]:
    """The statuses of fmpy's FMU2Slave methods ``calls`` on b and the messages logged."""
    from fmpy.fmi1 import FMICallException

    start, statuses = len(b.messages), []
    for call in calls:
        try:
            getattr(b.fmu, call)()
            statuses.append(OK)
        except FMICallException as e:
            statuses.append(int(e.status))
    return statuses, b.messages[start:]


def test_exit_before_enter_and_terminate_before_initialisation_are_refused_alike(
    native_fmus, python_fmus
):
    """FMI 2.0's order of calls: exitInitializationMode only in initialisation mode,
    terminate only once the model is initialised (after a failed one the instance is
    reset or freed). Both targets answer fmi2Error with the same message to
    exitInitializationMode before enterInitializationMode (after fmi2Reset) and to
    terminate before initialisation (never tried, or failed), and then start normally:
    enter, exit, a step, terminate OK."""
    from fmpy.fmi1 import FMICallException

    answers = []
    for path in (python_fmus["fig13"], native_fmus["fig13"]):
        with Instance(path, "order", initialise=False) as b:
            got = _phase_calls(b, ["reset", "exitInitializationMode", "terminate"])
            b.fmu.enterInitializationMode()
            with pytest.raises(FMICallException):
                b.set("h_max", 0.0)  # declared > 0: the start fails
            got += _phase_calls(b, ["exitInitializationMode", "terminate"])
            b.set("h_max", 1e-5)
            got += _phase_calls(b, ["exitInitializationMode"])
            b.initialised = True
            got += ([b.step(H)], [])
            got += _phase_calls(b, ["terminate"])
            answers.append(got)
    assert answers[0] == answers[1]
    statuses = [s for k, s in enumerate(answers[1]) if k % 2 == 0]
    assert statuses == [[OK, ERROR, ERROR], [ERROR, ERROR], [OK], [OK], [OK]], answers[1]
    assert answers[1][1] == [
        (ERROR, "exitInitializationMode refused: called before fmi2EnterInitializationMode"),
        (ERROR, "terminate refused: called before the model is initialised "
                "(fmi2ExitInitializationMode not called)"),
    ]  # fmt: skip
    assert answers[1][3][-1] == (
        ERROR,
        "terminate refused: called before the model is initialised "
        "(fmi2ExitInitializationMode failed)",
    )


# the start values and the calls after a first step, whose statuses and messages both
# targets must give word for word (the pythonfmu FMU words them in Python, the native
# one in C)
BAD_CALLS = {
    "two bad inputs": ({}, [("set", "P", -1.0), ("set", "My_ex", math.inf), ("step", H)]),
    "a step of 0": ({}, [("step", 0.0)]),
    "a step of nan": ({}, [("step", math.nan)]),
    "a step not at the FMU's time": ({}, [("step", H, 1.0)]),
    "Fx_ex beyond LOAD_LIMIT mu P": ({}, [("set", "Fx_ex", -1.2e308), ("step", H)]),
    "My_ex beyond LOAD_LIMIT mu P Rx": ({}, [("set", "My_ex", 1e20), ("step", H)]),
    "a step that spins the body beyond its range": ({}, [("set", "My_ex", 1e10), ("step", 1.0)]),
    "a step beyond max_substeps internal steps": ({}, [("step", 10.0)]),
    "loads beyond mu P on an eta = inf body": (
        {"Iy": 0.0},
        [("set", "My_ex", -2.0 * ex.mu * ex.P * ex.Rx), ("step", H)],
    ),
}


def _answer(b: Instance, calls: list) -> tuple[list[int], list[tuple[int, str]]]:
    """The statuses of ``calls`` on b and the messages logged meanwhile."""
    from fmpy.fmi1 import FMICallException

    start, statuses = len(b.messages), []
    for kind, *args in calls:
        if kind == "step":
            statuses.append(b.step(*args))
            continue
        try:
            b.initialise() if kind == "initialise" else b.set(*args)
            statuses.append(OK)
        except FMICallException as e:
            statuses.append(int(e.status))
    return statuses, b.messages[start:]


@pytest.mark.parametrize(("params", "calls"), BAD_CALLS.values(), ids=list(BAD_CALLS))
def test_both_targets_answer_a_bad_call_in_the_same_words(native_fmus, python_fmus, params, calls):
    """One C core behind two front ends: the same statuses and the same messages, naming
    the variable and its value, from the pythonfmu FMU and the native FMU."""
    answers = []
    for path in (python_fmus["fig13"], native_fmus["fig13"]):
        with body(path, **params) as b:
            steps(b, 1)
            answers.append(_answer(b, calls))
    assert answers[0] == answers[1]
    assert answers[0][1], answers  # each case is answered with a message


# a start whose Omega_y0 = (Vx0 - vx0)/Rx = 1e8 rad/s is beyond RATE_MAX: each value
# in its declared range, Rx small
SPIN_START = {"Rx": 1e-7, "Vx0": 10.0, "vx0": 0.0}


@pytest.mark.parametrize(
    ("params", "set_status"),
    [({"mu": -0.3}, ERROR), ({"M": math.inf, "h_max": 0.0}, ERROR), (SPIN_START, OK)],
)
def test_both_targets_refuse_a_bad_start_in_the_same_words(
    native_fmus, python_fmus, params, set_status
):
    """Bad parameters (or good ones giving an initial state beyond its range): the same
    statuses at setReal, fmi2Error at exitInitializationMode and at the doStep that
    follows, with the same messages, from both targets."""
    calls = [("set", *kv) for kv in params.items()] + [("initialise",), ("step", H)]
    answers = []
    for path in (python_fmus["fig13"], native_fmus["fig13"]):
        with Instance(path, "start", initialise=False) as b:
            answers.append(_answer(b, calls))
    assert answers[0] == answers[1]
    assert answers[0][0] == [set_status] * len(params) + [ERROR, ERROR], answers


@pytest.fixture(scope="module")
def start_fmus(native_fmus, python_fmus) -> dict[tuple[str, str], Path]:
    """(target, kind): the Fig. 13 body FMU (scalar stepper), the full body FMU (Eqs.
    10-11: the vector stepper) and the full rigid_body FMU, of both targets."""
    fmus = {
        (t, "fig13"): f["fig13"] for t, f in (("native", native_fmus), ("pythonfmu", python_fmus))
    }
    for kind, mode in (("full body", "body"), ("rigid_body", "rigid_body")):
        cfg = ModelConfig.full(mode)
        fmus["native", kind] = native_fmu.build(cfg, OUT).path
        fmus["pythonfmu", kind] = fmu_build.build(cfg, OUT).path
    return fmus


START_KINDS = ("fig13", "full body", "rigid_body")
START_REFUSED = re.compile(
    r"cannot initialise the model: Omega_y0 = (\S+) is invalid: must be within abs <= 1e\+07 "
    r"\(Omega_y0 = \(Vx0 - vx0\)/Rx: the model cannot start there\)"
)


@pytest.mark.parametrize("kind", START_KINDS)
@pytest.mark.parametrize("target", ["pythonfmu", "native"])
def test_a_start_spinning_beyond_rate_max_is_refused_naming_omega_y0(start_fmus, target, kind):
    """Eq. (3) solved for the start, Omega_y0 = (Vx0 - vx0)/Rx: Vx0 = 10 m/s on Rx = 1e-7
    m gives 1e8 rad/s, beyond RATE_MAX = 1e7 rad/s, from which every step would be
    discarded. exitInitializationMode answers fmi2Error naming Omega_y0 and its value
    (1e8 to a few roundings: the state holds vx = Vx0 - Omega_y0 Rx, whence Omega_y is
    read back); doStep is refused. Rx = 1e-6 puts Omega_y0 on the bound (1e7): the same
    instance then starts and steps; so does a new instance at the default Rx."""
    from fmpy.fmi1 import FMICallException

    path = start_fmus[target, kind]
    with Instance(path, "spin", SPIN_START, initialise=False) as b:
        with pytest.raises(FMICallException) as e:
            b.initialise()
        assert e.value.status == ERROR
        found = [m for s, m in b.messages if s == ERROR and START_REFUSED.fullmatch(m)]
        assert len(found) == 1, b.messages
        assert float(START_REFUSED.fullmatch(found[0])[1]) == pytest.approx(1e8, rel=1e-12)
        assert b.messages[-1] == (
            ERROR,
            "exitInitializationMode: the model cannot start: see the messages above",
        )
        assert b.step(1e-5) == ERROR
        b.set("Rx", 1e-6)  # Omega_y0 = 10 / 1e-6 = 1e7: on the bound, within it
        b.initialise()
        assert abs(b.get("Omega_y")) <= 1e7
        assert b.get("Omega_y") == pytest.approx(1e7, rel=1e-12)
        assert b.step(1e-5) == OK
    with Instance(path, "sane", {"Vx0": 10.0, "vx0": 0.0}) as b:
        assert b.get("Omega_y") == pytest.approx(10.0 / b.get("Rx"), rel=1e-12)
        assert b.step(1e-5) == OK


@pytest.mark.parametrize("kind", START_KINDS)
def test_both_targets_refuse_a_start_beyond_rate_max_in_the_same_words(start_fmus, kind):
    """The refused start of the test above, scalar and vector body and rigid body: the
    same statuses and messages word for word from the pythonfmu and the native FMU."""
    calls = [("set", *kv) for kv in SPIN_START.items()] + [("initialise",), ("step", H)]
    answers = []
    for target in ("pythonfmu", "native"):
        with Instance(start_fmus[target, kind], "start", initialise=False) as b:
            answers.append(_answer(b, calls))
    assert answers[0] == answers[1]
    assert answers[0][0] == [OK] * len(SPIN_START) + [ERROR, ERROR], answers


def test_a_string_parameter_outside_its_choices_is_refused_at_once_alike(start_fmus):
    """The String parameters method ("full" or "quasistationary") and scheme ("lobatto3c"
    or "sdirk2", RollingBody's choices): a string that is neither answers fmi2Error at
    setString on both targets with the same message naming the variable and the value
    (the pythonfmu FMU checked it only at set-up before); exitInitializationMode then
    fails naming both and doStep is refused; corrected, the model starts and steps."""
    calls = [("set", "method", "garbage"), ("set", "scheme", "rk4"), ("initialise",)]
    answers = []
    for target in ("pythonfmu", "native"):
        with Instance(start_fmus[target, "full body"], "choice", initialise=False) as b:
            answers.append(_answer(b, [*calls, ("step", H)]))
            b.set("method", "quasistationary")
            b.set("scheme", "sdirk2")
            b.initialise()
            assert b.step(H) == OK
    assert answers[0] == answers[1]
    assert answers[0][0] == [ERROR, ERROR, ERROR, ERROR]
    assert answers[0][1][0] == (
        ERROR,
        'method = \'garbage\' is invalid: must be "full" or "quasistationary"; doStep '
        "answers fmi2Discard until it is corrected",
    )


@pytest.mark.parametrize("kind", ("fig13", "full body"))
@pytest.mark.parametrize("Vx0", [0.0, None], ids=["Vx0 = 0", "Vx0 default"])
def test_a_body_whose_inertia_underflows_cannot_start_in_the_same_words(start_fmus, kind, Vx0):
    """dynamics.Body: A1 and A2 (Eq. 23) divide by M Rx^2 + Iy, which must neither
    underflow nor overflow. Iy = 0 (eta = inf) with Rx = 1e-200 m (each admissible
    alone) gives M Rx^2 = 0 in doubles: both targets refuse the start at
    exitInitializationMode naming M Rx^2 + Iy, M, Rx and Iy, word for word, whether the
    start itself is at rest (Vx0 = 0, where the native FMU started before with A2 =
    0/0) or rolls (Omega_y0 = Vx0/Rx far beyond RATE_MAX, which it named instead)."""
    params = {"Rx": 1e-200, "Iy": 0.0} | ({} if Vx0 is None else {"Vx0": Vx0})
    calls = [("set", *kv) for kv in params.items()] + [("initialise",), ("step", H)]
    answers = []
    for target in ("pythonfmu", "native"):
        with Instance(start_fmus[target, kind], "inertia", initialise=False) as b:
            answers.append(_answer(b, calls))
    assert answers[0] == answers[1]
    assert answers[0][0] == [OK] * len(params) + [ERROR, ERROR], answers
    assert answers[0][1][0] == (
        ERROR,
        "cannot initialise the model: M Rx^2 + Iy = 0.0 is invalid: must be positive and "
        "finite with M Rx^2 > 0 (M = 1.0, Rx = 1e-200, Iy = 0.0)",
    )


def test_fmu_state_get_step_set_step_is_bit_identical(fig13):
    with body(fig13) as b:
        steps(b, 4)
        state = b.get_state()
        steps(b, 3)
        first = b.outputs()
        b.set_state(state)
        steps(b, 3)
        assert b.outputs() == first
        b.free_state(state)


def test_serialized_native_state_restores_bit_for_bit_in_another_instance(native_fmus):
    """fmi2SerializeFMUstate of the native FMU into a fresh instance: the same steps give
    the same doubles (the P change on the way rebuilds the law from the state)."""
    with body(native_fmus["fig13"]) as a, body(native_fmus["fig13"]) as b:
        steps(a, 4)
        a.set("P", 0.9 * ex.P)
        steps(a, 1)
        state = a.get_state()
        data = a.serialize_state(state)
        steps(a, 3)
        b.set_state(b.deserialize_state(data, state[1]))
        b.set("P", 0.9 * ex.P)
        steps(b, 3)
        assert b.outputs() == a.outputs()


# what each target's envelope names when it refuses bytes (pythonfmu_shim.c, instance.c)
REFUSALS = {
    "pythonfmu": {
        "garbage": "not a serialized contact_fmu FMU state",
        "foreign": "another FMU",
        "flipped": "damaged (its checksum differs)",
        "truncated": "truncated",
        "extended": "truncated or extended",
    },
    "native": {
        "garbage": "not a serialized contact_fmu FMU state",
        "foreign": "another FMU",
        "flipped": "checksum",
        "truncated": "length",
        "extended": "length",
        "version": "format version",
    },
}


@pytest.mark.parametrize("target", list(REFUSALS))
def test_state_bytes_not_of_this_fmu_are_refused_and_the_instance_recovers(
    native_fmus, python_fmus, target
):
    """Foreign or damaged bytes (garbage, another FMU's state, a flipped byte,
    truncated, extended, another format version): fmi2DeSerializeFMUstate answers
    fmi2Error naming the reason (the envelope: magic, format, GUID, length, checksum),
    nothing changes, and the instance steps on."""
    from fmpy.fmi1 import FMICallException

    fmus = native_fmus if target == "native" else python_fmus
    with Instance(fmus["railway"], "other") as other:
        assert other.step(1e-4) == OK
        foreign = other.serialize_state(other.get_state())
    with body(fmus["fig13"]) as b:
        steps(b, 2)
        state = b.get_state()
        good = b.serialize_state(state)
        flipped = bytearray(good)
        flipped[len(good) // 2] ^= 0x08  # in the pythonfmu FMU's: the key 'mu' read as 'iu'
        version = bytearray(good)
        version[8] ^= 1
        data = {"garbage": b"garbage", "foreign": foreign, "flipped": bytes(flipped)}
        data |= {"truncated": good[:-20], "extended": good + b"x", "version": bytes(version)}
        for case, reason in REFUSALS[target].items():
            before = b.outputs()
            with pytest.raises(FMICallException) as e:
                b.deserialize_state(data[case], b.time)
            assert e.value.status == ERROR and reason in b.messages[-1][1], b.messages[-1:]
            assert b.outputs() == before
            steps(b, 1)
        b.set_state(b.deserialize_state(good, state[1]))
        steps(b, 1)
        assert all(s < FATAL for s, _ in b.messages)


PYTHONFMU_ENVELOPE = b"contact_fmu state\n"  # pythonfmu_shim.c's CF_MAGIC
PYTHONFMU_STATE = b"contact_fmu FMU state 1\n"  # fmu/state_bytes.py's MAGIC


def _fnv1a(data: bytes) -> int:
    h = 1469598103934665603
    for byte in data:
        h = ((h ^ byte) * 1099511628211) % 2**64
    return h


def _tampered(data: bytes, old: dict[str, float], new: dict[str, float]) -> bytes:
    """State bytes of either target with the values of ``old`` replaced by ``new`` and
    the envelope made whole again (length and checksum recomputed): a content that no
    setter admits in an intact envelope. pythonfmu on its Python path: the pickled
    state's values and outputs (its classes are the loaded FMU's, in sys.modules);
    native, and the pythonfmu FMU on its C core (inside the shim's envelope): every
    double of the instance's core that holds the old value (the value, its copy by role,
    the model's state and outputs)."""
    import pickle
    import struct
    import zlib

    if data.startswith(PYTHONFMU_ENVELOPE):
        m = len(PYTHONFMU_ENVELOPE)
        glen = int.from_bytes(data[m + 4 : m + 8], "little")
        head = m + 8 + glen + 8 + 4
        payload = data[head:]
        if payload.startswith(CORE_MAGIC):  # the C core's state (fmu/slave_core.py)
            payload = _tampered(payload, old, new)
            size = len(payload).to_bytes(8, "little") + zlib.crc32(payload).to_bytes(4, "little")
            return data[: m + 8 + glen] + size + payload
        assert payload.startswith(PYTHONFMU_STATE)
        owner, _, body = payload[len(PYTHONFMU_STATE) :].partition(b"\n")
        state = pickle.loads(body)
        for name, value in new.items():
            state["out" if name in state["out"] else "values"][name] = value
        payload = PYTHONFMU_STATE + owner + b"\n" + pickle.dumps(state, protocol=5)
        size = len(payload).to_bytes(8, "little") + zlib.crc32(payload).to_bytes(4, "little")
        return data[: m + 8 + glen] + size + payload
    assert data.startswith(CORE_MAGIC)  # instance.c's MAGIC, as state_bytes declares it
    glen = int.from_bytes(data[12:16], sys.byteorder)
    start = 16 + glen + 8
    payload = data[start:-8]
    for name, value in new.items():
        was = struct.pack("=d", old[name])
        assert was in payload, name
        payload = payload.replace(was, struct.pack("=d", value))
    body = data[:start] + payload
    return body + struct.pack("=Q", _fnv1a(body))


@pytest.mark.parametrize(
    ("change", "reason"),
    [
        ({"mu": math.nan}, "its record of invalid values does not match its values"),
        ({"P": -1.0}, "its record of invalid values does not match its values"),
        ({"Vx": math.inf}, "its output Vx = inf is not a finite float"),
        ({"Vx": math.nan}, "its output Vx = nan is not a finite float"),
    ],
    ids=["mu nan", "P -1", "Vx inf", "Vx nan"],
)
@pytest.mark.parametrize("core", ["core on", "CONTACT_FMU_CORE=0"])
def test_a_state_whose_content_no_setter_admits_is_refused_and_nothing_changes(
    fig13, change, reason, core, monkeypatch
):
    """An FMU state is checked whole, not only its envelope: bytes whose length and
    checksum are intact but whose content holds mu = NaN or P = -1 (values the setters
    refuse, not recorded as held bad) or an output Vx = inf or NaN are refused with
    fmi2Error naming the reason in the words of the pythonfmu FMU's check (the native
    FMU at deserialisation, the pythonfmu FMU on its C core at setFMUstate, where the
    core reads the bytes, and on its Python path, CONTACT_FMU_CORE=0, in Python); the
    outputs are unchanged and the instance steps on."""
    from fmpy.fmi1 import FMICallException

    if core != "core on":
        if "-native-" in fig13.name:
            pytest.skip("the native FMU has no Python path")
        monkeypatch.setenv("CONTACT_FMU_CORE", "0")
    with body(fig13) as b:
        steps(b, 2)
        old = {n: b.get(n) for n in change}
        state = b.get_state()
        bad = _tampered(b.serialize_state(state), old, change)
        steps(b, 1)
        before = b.outputs()
        now = b.time
        with pytest.raises(FMICallException) as e:
            b.set_state(b.deserialize_state(bad, state[1]))
        b.time = now  # the master's time: the state was not set
        assert e.value.status == ERROR
        assert reason in b.messages[-1][1], b.messages[-1:]
        assert b.outputs() == before
        steps(b, 1)
        assert all(s < FATAL for s, _ in b.messages)


def test_a_live_native_state_altered_in_memory_is_refused_at_set_in_the_pythonfmu_words(
    native_fmus,
):
    """The same check at fmi2SetFMUstate, for a state altered where it lives (mu = NaN
    written into the state the instance handed out): fmi2Error with the pythonfmu FMU's
    message (slave._set_fmu_state), the instance unchanged."""
    import struct

    from fmpy.fmi1 import FMICallException

    with body(native_fmus["fig13"]) as b:
        steps(b, 2)
        state = b.get_state()
        payload = b.serialize_state(state)
        start = 16 + int.from_bytes(payload[12:16], sys.byteorder) + 8
        mu = struct.pack("=d", b.get("mu"))
        core = payload[start:-8]
        offsets = [k for k in range(0, len(core) - 7, 8) if core[k : k + 8] == mu]
        assert len(offsets) >= 2  # the value and its copy by role
        for k in offsets:
            ctypes.memmove(state[0].value + k, struct.pack("=d", math.nan), 8)
        steps(b, 1)
        before = b.outputs()
        now = b.time
        with pytest.raises(FMICallException) as e:
            b.set_state(state)
        b.time = now  # the master's time: the state was not set
        assert e.value.status == ERROR
        assert b.messages[-1][1].startswith(
            "the FMU state given to setFMUstate is refused: its record of invalid values "
            "does not match its values (mu = nan is invalid: must be finite, recorded as valid)"
        ) and b.messages[-1][1].endswith("; the instance's state is unchanged")
        assert b.outputs() == before
        steps(b, 1)


NOT_A_STATE = "is not an FMU state of this instance (never given, or freed)"


def test_a_pointer_that_is_not_a_live_state_of_the_instance_is_refused(fig13, tmp_path):
    """FMI 2.0 forbids passing back a freed state (set, or freed twice), a state of
    another instance of the same binary (one alive, one freed with its instance) or any
    other pointer (here one into a valid buffer). Both FMUs keep the states they handed
    out and answer each state call with such a pointer with fmi2Error and the same
    message, instead of reading it (freed memory: the sanitized importer below shows
    the native FMU's guard at work); the instance's outputs are unchanged, it steps on,
    and the other instance's state still restores there."""
    from ctypes import addressof, byref, c_size_t, c_void_p, create_string_buffer

    import fmpy

    fmpy.extract(str(fig13), str(tmp_path))  # one binary for the three instances
    with Instance(fig13, "b", unzip_dir=tmp_path) as b:
        steps(b, 1)
        foreign = b.fmu.getFMUstate()
        pointers = {"foreign": foreign.value}
        good = b.serialize_state(b.get_state())  # valid bytes for any instance of the FMU
        with Instance(fig13, "c", unzip_dir=tmp_path) as c:
            pointers["of a freed instance"] = c.fmu.getFMUstate().value
        # the last instance made: fmpy's logger proxy reports to its callback alone. It
        # holds no live state while the pointers are tried: the allocator may hand it an
        # address freed before (the freed instance's state), which would then be live.
        with Instance(fig13, "a", unzip_dir=tmp_path) as a:
            steps(a, 2)
            freed = a.fmu.getFMUstate()
            pointers["freed"] = freed.value
            a.fmu.freeFMUstate(freed)
            buffer = create_string_buffer(good, len(good))  # a state's bytes, no state
            pointers["into a buffer"] = addressof(buffer) + 64
            before = a.outputs()
            dll, comp, size, out = a.fmu.dll, a.fmu.component, c_size_t(0), create_string_buffer(9)
            for case, value in pointers.items():
                p = c_void_p(value)
                calls = {
                    "fmi2SetFMUstate": lambda: dll.fmi2SetFMUstate(comp, p),  # noqa: B023
                    "fmi2FreeFMUstate": lambda: dll.fmi2FreeFMUstate(comp, byref(p)),  # noqa: B023
                    "fmi2SerializedFMUstateSize": (
                        lambda: dll.fmi2SerializedFMUstateSize(comp, p, byref(size))  # noqa: B023
                    ),
                    "fmi2SerializeFMUstate": lambda: dll.fmi2SerializeFMUstate(comp, p, out, 9),  # noqa: B023
                    "fmi2GetFMUstate": lambda: dll.fmi2GetFMUstate(comp, byref(p)),  # noqa: B023
                    "fmi2DeSerializeFMUstate": (
                        lambda: dll.fmi2DeSerializeFMUstate(comp, buffer, len(good), byref(p))  # noqa: B023
                    ),
                }
                for call, answer in calls.items():
                    assert answer() == ERROR, (case, call)
                    assert a.messages[-1] == (ERROR, f"{call}: {hex(value)} {NOT_A_STATE}"), case
                    assert p.value == value, (case, call)  # the caller's pointer as it was
            nothing = c_void_p(None)
            assert dll.fmi2FreeFMUstate(comp, byref(nothing)) == OK  # FMI 2.0: a no-op
            assert a.outputs() == before
            steps(a, 1)
        b.set_state((foreign, b.time))
        steps(b, 1)
        b.free_state((foreign, b.time))


def test_instances_are_independent_also_on_threads(native_fmus, tmp_path):
    """Two instances of one loaded binary stepped at once on two threads with different
    loads, each getting and freeing FMU states on the way (its own table of live
    states; those left are freed with the instance), give each the doubles of a lone
    run: no shared mutable state."""
    import fmpy

    fmpy.extract(str(native_fmus["fig13"]), str(tmp_path))

    def run(my: float, out: list) -> None:
        with Instance(native_fmus["fig13"], "body", unzip_dir=tmp_path) as b:
            b.set("Fx_ex", F)
            b.set("My_ex", my)
            held = []
            for k in range(200):
                if k % 5 == 0:
                    held.append(b.get_state())
                assert b.step(1.75e-4) == OK
            for state in held[::2]:
                b.free_state(state)
            out.append(b.outputs())

    alone = ([], [])
    run(-0.1 * F * ex.Rx, alone[0])
    run(0.2 * F * ex.Rx, alone[1])
    both = ([], [])
    threads = [
        threading.Thread(target=run, args=(-0.1 * F * ex.Rx, both[0])),
        threading.Thread(target=run, args=(0.2 * F * ex.Rx, both[1])),
    ]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert both == alone and alone[0] != alone[1]


def test_fixed_parameter_or_output_set_after_initialisation_is_refused(fig13):
    """Illegal calls (FMI 2.0: a fixed parameter after initialisation, an output) answer
    fmi2Error with a message naming it; the value stays, the instance steps on."""
    from fmpy.fmi1 import FMICallException

    with body(fig13) as b:  # M: mu is tunable (test_fmu_interface)
        M = b.get("M")
        for name, text in (("M", "M is a fixed parameter"), ("Tx", "Tx is an output")):
            with pytest.raises(FMICallException) as e:
                b.set(name, 0.5)
            assert e.value.status == ERROR and text in b.messages[-1][1]
        assert b.get("M") == M
        steps(b, 1)


def test_a_parameter_combination_the_model_refuses_is_named_at_initialisation(fig13):
    """k1 = k2 = 0 passes each range but leaves no normal compliance (Eq. 32): fmi2Error
    at exitInitializationMode naming it; corrected, the model starts."""
    from fmpy.fmi1 import FMICallException

    with Instance(fig13, "bad", {"k1": 0.0, "k2": 0.0}, initialise=False) as b:
        with pytest.raises(FMICallException) as e:
            b.initialise()
        assert e.value.status == ERROR
        assert any("k1 + k2 = 0.0 is invalid" in m for _, m in b.messages), b.messages
        assert b.step(H) == ERROR
        b.set("k1", ex.k1)
        b.set("k2", ex.k2)
        b.initialise()
        steps(b, 1)


# ---- the library itself ---------------------------------------------------------------------
def test_native_binary_needs_no_python_and_an_old_c_library(native_fmus, tmp_path):
    """The FMU's binary exports the FMI functions and needs nothing from Python; its
    newest glibc symbol version is at most 2.17 (test_native.GLIBC_FLOOR)."""
    from test_native import GLIBC_FLOOR, glibc_needed

    with zipfile.ZipFile(native_fmus["fig13"]) as z:
        (so,) = [n for n in z.namelist() if n.startswith("binaries/linux64/") and n.endswith(".so")]
        z.extract(so, tmp_path)
    lib = tmp_path / so
    undefined = subprocess.run(
        ["nm", "-D", "--undefined-only", str(lib)], capture_output=True, text=True, check=True
    ).stdout
    assert "Py" not in undefined and "python" not in undefined.lower()
    exported = subprocess.run(
        ["nm", "-D", "--defined-only", str(lib)], capture_output=True, text=True, check=True
    ).stdout
    names = set(re.findall(r" T (fmi2\w+)", exported))
    assert len(names) == 34 and not re.search(r" T cf_", exported)  # FMI 2.0 CS: 34
    if shutil.which("objdump"):
        assert glibc_needed(lib) <= GLIBC_FLOOR


# the native FMU kinds a builder may compile from sources/: the scalar and the vector body
# step, the contact mode with spin, the rigid body, the half-space table, the body on the
# transient traction field
SOURCE_KINDS = ("fig13", "full body", "full contact", "full rigid_body", "rail_traction",
                "fig12_transient")  # fmt: skip


# the FMI versions: the front end and the count of functions the standard's headers
# declare for co-simulation (FMI 2.0: 34; FMI 3.0: the 75 of fmi3Functions.h)
FRONT_ENDS = {"fmi2": ("fmi2.c", 34), "fmi3": ("fmi3.c", 75)}


@pytest.mark.parametrize("fmi", FRONT_ENDS)
@pytest.mark.parametrize("kind", SOURCE_KINDS)
def test_sources_alone_compile_strictly_and_export_only_the_fmi_functions(
    scenes, native_fmus, kind, fmi, tmp_path
):
    """Each C file of sources/ is its own translation unit: ``cc -shared -fPIC`` of
    sources/*.c with fmpy's FMI headers, under -Wall -Wextra -pedantic -Werror and
    without -fvisibility=hidden (as fmpy's cmake or an importer's own build compiles
    them), builds a library whose dynamic symbol table defines the functions of FMI
    2.0 co-simulation (34) or, for the FMI 3.0 FMU, of FMI 3.0 (75), and nothing else: the
    sources hide their own internals (stepper.h's CF_HIDDEN, static), so no cf_* symbol
    can clash with a host's. Each FMU carries its own front end only (fmi2.c or fmi3.c)
    with the same instance layer, model, stepper and transient field (field.c)."""
    import fmpy

    from fmu_build import native_fmu3

    scene_file = ROOT / "scenarios" / f"{kind}.toml"
    cfg = (
        scenes[kind].config
        if kind in scenes
        else load(scene_file).config
        if scene_file.is_file()
        else ModelConfig.full(kind.removeprefix("full "))
    )
    if fmi == "fmi2":
        path = native_fmus[kind] if kind in native_fmus else native_fmu.build(cfg, OUT).path
    else:
        path = native_fmu3.build(cfg, OUT).path
    front, count = FRONT_ENDS[fmi]
    unzip = tmp_path / "fmu"
    fmpy.extract(str(path), str(unzip))
    units = sorted((unzip / "sources").glob("*.c"))
    assert [u.name for u in units] == sorted([front, "field.c", "instance.c", "model.c",
                                              "stepper.c"])  # fmt: skip
    lib = tmp_path / "built.so"
    cmd = ["cc", "-shared", "-fPIC", "-Wall", "-Wextra", "-pedantic", "-Werror",
           f"-I{native_fmu.fmi_headers()}", *map(str, units), "-lm", "-o", str(lib)]  # fmt: skip
    proc = subprocess.run(cmd, capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr[-3000:]
    defined = subprocess.run(
        ["nm", "-D", "--defined-only", str(lib)], capture_output=True, text=True, check=True
    ).stdout.split("\n")
    names = [line.split()[-1] for line in defined if line.strip()]
    assert len(names) == count and all(n.startswith(fmi) for n in names), names


# ---- a C importer, a source build, sanitizers -------------------------------------------------
IMPORTER = native_c.IMPORTER2
_spec, _compile = native_c.spec, native_c.compile_c


def _instance_run(path: Path, scene, case) -> np.ndarray:
    """The case through fmpy's FMU2Slave, the input table's row k held over step k (the
    importer's inputs exactly; fmpy's simulate_fmu interpolates them at its own time)."""
    table = runner.input_table(scene, case)
    reals = [o for o in scene.outputs if o != "regime"]
    rows = []
    with Instance(path, "expected", runner.start_values(scene, case)) as inst:
        for k in range(scene.grid.size - 1):
            for n in scene.inputs:
                inst.set(n, float(table[n][k]))
            assert inst.step(scene.step, float(scene.grid[k])) == OK
            rows.append([inst.get(o) for o in reals])
    return np.array(rows)


@pytest.fixture(scope="session")
def fig13_expected(scenes, native_fmus, python_fmus) -> np.ndarray:
    """Fig. 13, eta = 3, through fmpy: the native FMU's outputs, which are the pythonfmu
    FMU's doubles."""
    scene = scenes["fig13"]
    case = scene.case("eta = 3")
    got = _instance_run(native_fmus["fig13"], scene, case)
    assert np.array_equal(got, _instance_run(python_fmus["fig13"], scene, case))
    return got


def _fig13_case(scenes, native_fmus, expected, tmp_path):
    import fmpy

    scene = scenes["fig13"]
    case = scene.case("eta = 3")
    unzip = tmp_path / "fmu"
    fmpy.extract(str(native_fmus["fig13"]), str(unzip))
    md = fmpy.read_model_description(str(unzip))
    spec = tmp_path / "spec.txt"
    spec.write_text(_spec(md, scene, case))
    return unzip, md, spec, expected


def _importer_run(exe: Path, lib: Path, md, spec: Path) -> np.ndarray:
    args = [str(exe), str(lib), md.guid, md.coSimulation.modelIdentifier, "run", str(spec)]
    proc = subprocess.run(args, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr[-2000:]
    lines = [line for line in proc.stdout.split("\n") if line]
    return np.array([[float.fromhex(x) for x in line.split()] for line in lines])


def test_a_c_importer_without_python_runs_fig13_to_fmpys_numbers(
    scenes, native_fmus, fig13_expected, tmp_path
):
    """A plain C program (dlopen, the FMI calls; no libpython linked: it needs no Python
    symbol) runs the Fig. 13 case eta = 3 on the FMU's binary: the same doubles as fmpy's
    run of the same FMU, and so the pythonfmu FMU's."""
    unzip, md, spec, expected = _fig13_case(scenes, native_fmus, fig13_expected, tmp_path)
    exe = _compile(tmp_path / "importer", str(IMPORTER), "-ldl")
    undefined = subprocess.run(
        ["nm", "-D", "--undefined-only", str(exe)], capture_output=True, text=True, check=True
    ).stdout
    assert "Py" not in undefined
    lib = unzip / "binaries" / "linux64" / f"{md.coSimulation.modelIdentifier}.so"
    got = _importer_run(exe, lib, md, spec)
    assert got.shape == expected.shape and np.array_equal(got, expected)


def test_importer_bench_repeats_the_case_and_stops_loudly(
    scenes, native_fmus, fig13_expected, tmp_path
):
    """The importer's bench run (benchmarks/bench_native.py): the Fig. 13 case eta = 3
    repeated from its start state, so any number of steps stays within the case (held at
    its start inputs, Fx_ex = F drove the body at (1 - A2) F / M = 143 m/s^2 past the
    declared |Vx| <= 1e4 m/s after 3.99e5 steps, and the importer stopped without a
    word); each repeat ends with the same doubles. A call that the FMU refuses (P = -1 in
    row 10) ends the run with exit status 3 and no rate, naming the call, the step and the
    FMU's message."""
    unzip, md, spec, _ = _fig13_case(scenes, native_fmus, fig13_expected, tmp_path)
    exe = _compile(tmp_path / "importer", str(IMPORTER), "-ldl")
    lib = unzip / "binaries" / "linux64" / f"{md.coSimulation.modelIdentifier}.so"
    args = [str(exe), str(lib), md.guid, md.coSimulation.modelIdentifier, "bench"]
    rows = scenes["fig13"].grid.size - 1
    proc = subprocess.run([*args, str(spec), str(3 * rows + 7)], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert float(proc.stdout) > 0.0
    lines = spec.read_text().splitlines()
    row = lines[3 + 10].split()
    row[2] = (-1.0).hex()  # P, the first input (scene.inputs)
    lines[3 + 10] = " ".join(row)
    bad = tmp_path / "bad.txt"
    bad.write_text("\n".join(lines) + "\n")
    proc = subprocess.run([*args, str(bad), str(rows)], capture_output=True, text=True)
    assert proc.returncode == 3 and proc.stdout == ""
    assert "fmi2SetReal at step 10 " in proc.stderr and "P = -1" in proc.stderr, proc.stderr


# A host that links nothing but the C library and loads the FMU with RTLD_NOW (every
# symbol bound at once): what a library needs and does not name in DT_NEEDED is missing.
PLAIN_HOST = r"""
#include <dlfcn.h>
#include <stdio.h>
int main(int argc, char **argv) {
    void *h = argc > 1 ? dlopen(argv[1], RTLD_NOW | RTLD_LOCAL) : NULL;
    if (h == NULL) { printf("%s\n", dlerror()); return 1; }
    printf("%s\n", dlsym(h, "fmi2Instantiate") ? "loaded" : "no fmi2Instantiate");
    return 0;
}
"""

# what a builder of the FMU's sources tells fmpy's cmake (docs/fmu.md): link libm
LINK_LIBM = {"CMAKE_C_STANDARD_LIBRARIES:STRING": "-lm"}


def _needed(lib: Path) -> list[str]:
    text = subprocess.run(["readelf", "-d", str(lib)], capture_output=True, text=True).stdout
    return re.findall(r"\(NEEDED\)\s+Shared library: \[(.+?)\]", text)


@pytest.mark.skipif(shutil.which("cmake") is None, reason="no cmake")
def test_source_fmu_built_by_fmpy_from_sources_alone_gives_the_same_numbers(
    scenes, native_fmus, fig13_expected, tmp_path
):
    """fmpy's build of a source FMU (cmake, its own CMakeLists and FMI headers) from the
    FMU's sources/ alone, the shipped binary removed first. Its CMakeLists links no
    library: the result does not name libm, and a host that has not loaded libm itself
    (a C program linked with libc only) cannot load it ("undefined symbol" of a libm
    function such as asin). Told to link libm (CMAKE_C_STANDARD_LIBRARIES = -lm, as
    docs/fmu.md says), the library names libm.so.6, that host loads it, and the C
    importer gets the same doubles from it as from the shipped binary."""
    from fmpy.build import build_platform_binary

    unzip, md, spec, expected = _fig13_case(scenes, native_fmus, fig13_expected, tmp_path)
    shutil.rmtree(unzip / "binaries")
    lib = unzip / "binaries" / "linux64" / f"{md.coSimulation.modelIdentifier}.so"
    (tmp_path / "host.c").write_text(PLAIN_HOST)
    host = tmp_path / "host"
    subprocess.run(["cc", "-o", str(host), str(tmp_path / "host.c"), "-ldl"], check=True)
    assert not any(n.startswith("libm.") for n in _needed(host))
    (tmp_path / "plain").mkdir()
    build_platform_binary(str(unzip), str(tmp_path / "plain"))
    assert not any(n.startswith("libm.") for n in _needed(lib))
    proc = subprocess.run([str(host), str(lib)], capture_output=True, text=True)
    assert proc.returncode == 1 and "undefined symbol" in proc.stdout, proc.stdout
    lib.unlink()
    (tmp_path / "libm").mkdir()
    build_platform_binary(str(unzip), str(tmp_path / "libm"), cmake_options=dict(LINK_LIBM))
    assert "libm.so.6" in _needed(lib)
    proc = subprocess.run([str(host), str(lib)], capture_output=True, text=True)
    assert proc.returncode == 0 and proc.stdout == "loaded\n", proc.stdout
    exe = _compile(tmp_path / "importer", str(IMPORTER), "-ldl")
    assert np.array_equal(_importer_run(exe, lib, md, spec), expected)


@pytest.mark.skipif(shutil.which("objdump") is None, reason="no objdump")
def test_c_library_versions_the_binaries_of_both_targets_need(native_fmus, python_fmus, tmp_path):
    """What docs/fmu.md states a Linux target needs, read with ``objdump -T`` from the
    built FMUs: the native FMU's binary, libm and libc with no glibc symbol version newer
    than 2.17 (GLIBC_2.14, memcpy); the pythonfmu FMU's own binary (the status shim) and
    its compiled stepper likewise; but pythonfmu's libpythonfmu-export.so, which the shim
    loads, needs GLIBC_2.32 (__libc_single_threaded) and libstdc++'s GLIBCXX_3.4.30 (GCC
    12's): the pythonfmu FMU loads on glibc 2.32 or newer with GCC 12's libstdc++ or
    newer, the native FMU on glibc 2.17 or newer."""
    from test_native import GLIBC_FLOOR, glibc_needed

    def versions(lib: Path, tag: str) -> tuple[int, ...]:
        text = subprocess.run(["objdump", "-T", str(lib)], capture_output=True, text=True).stdout
        found = {tuple(map(int, v.split("."))) for v in re.findall(rf"{tag}_([0-9.]+)\)", text)}
        return max(found, default=())

    for target, fmus in (("native", native_fmus), ("pythonfmu", python_fmus)):
        unzip = tmp_path / target
        with zipfile.ZipFile(fmus["fig13"]) as z:
            z.extractall(unzip)
        libs = {p.name: p for p in unzip.rglob("*.so")}
        if target == "native":
            (lib,) = libs.values()
            assert glibc_needed(lib) <= GLIBC_FLOOR
            assert sorted(_needed(lib)) == ["libc.so.6", "libm.so.6"]
            continue
        export = libs.pop("libpythonfmu-export.so")
        assert glibc_needed(export) == (2, 32)
        assert versions(export, "GLIBCXX") == (3, 4, 30)
        assert libs and all(glibc_needed(p) <= GLIBC_FLOOR for p in libs.values()), libs


def _sanitized(tmp_path: Path, unzip: Path) -> Path:
    return native_c.sanitized(tmp_path / "importer_asan", IMPORTER, unzip)


def test_sanitized_importer_runs_fig13_bad_inputs_and_random_extremes_cleanly(
    scenes, native_fmus, fig13_expected, tmp_path
):
    """The FMU's sources and the C importer in one program built with AddressSanitizer
    and UBSan (float-to-int overflow included, no recovery): Fig. 13 to the same doubles,
    then 2 x 2500 random calls (extreme and non-finite values of every variable, zero,
    negative, non-finite and huge steps, steps at the wrong time, states got, set,
    serialized, damaged and refused, state calls with a freed state, another live or
    freed instance's or a pointer into a buffer, resets) with no sanitizer report, no
    fmi2Fatal, no non-finite output served with fmi2OK, no damaged bytes and no pointer
    that is not a live state of the instance accepted (without instance.c's table of live
    states, ASan reports the use after free). Then 3000 states held at once, set and
    freed in shuffled orders: each set until freed, each refused after."""
    unzip, md, spec, expected = _fig13_case(scenes, native_fmus, fig13_expected, tmp_path)
    try:
        exe = _sanitized(tmp_path, unzip)
    except subprocess.CalledProcessError as e:  # pragma: no cover - gcc without libasan
        pytest.skip(f"no sanitizer runtime: {e.stderr[-300:]}")
    assert np.array_equal(_importer_run(exe, Path("-"), md, spec), expected)
    short = tmp_path / "params.txt"
    short.write_text(_spec(md, scenes["fig13"], scenes["fig13"].case("eta = 3"), rows=False))
    counts = native_c.fuzz(exe, md, short, 2, 2500)
    assert counts["ok"] > 1700 and counts["discard"] > 170 and counts["refused"] > 100, counts
    args = [str(exe), "-", md.guid, "fuzz", "states", str(short), "3000"]
    proc = subprocess.run(args, capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0 and "Sanitizer" not in proc.stderr, proc.stderr[-3000:]


@pytest.mark.skipif(not native_c.HAS_VALGRIND, reason="no valgrind")
def test_memcheck_finds_no_error_in_the_shipped_binary(
    scenes, native_fmus, fig13_expected, tmp_path
):
    """The binary as shipped (optimised, dlopened by the plain C importer) under
    valgrind's memcheck, which sees what the sanitizers' rebuild cannot: Fig. 13 to the
    same doubles, 2000 random calls (as the sanitized run's), 300 states held, set and
    freed in shuffled orders, with no invalid read or write, no use of an undefined
    value and no definite leak."""
    unzip, md, spec, expected = _fig13_case(scenes, native_fmus, fig13_expected, tmp_path)
    exe = str(_compile(tmp_path / "importer", str(IMPORTER), "-ldl"))
    ident = md.coSimulation.modelIdentifier
    head = (exe, str(unzip / "binaries" / "linux64" / f"{ident}.so"), md.guid, ident)
    got = native_c.memcheck(*head, "run", str(spec)).split("\n")
    got = np.array([[float.fromhex(x) for x in line.split()] for line in got if line])
    assert np.array_equal(got, expected)
    short = tmp_path / "params.txt"
    short.write_text(_spec(md, scenes["fig13"], scenes["fig13"].case("eta = 3"), rows=False))
    out = native_c.memcheck(*head, "fuzz", str(short), "0", "2000").split()
    counts = {k: int(v) for k, v in zip(out[::2], out[1::2], strict=True)}
    assert counts["ok"] > 500 and counts["discard"] + counts["refused"] > 100, counts
    native_c.memcheck(*head, "states", str(short), "300")


@pytest.mark.parametrize(
    "mode",
    [
        "contact",
        "full_contact",
        "rigid_body",
        "cornering",
        "rail_creep",
        "fig13_sdirk2",
        "full_body_sdirk2",
    ],
)
def test_sanitized_importer_runs_the_other_modes_through_random_extremes_cleanly(
    scenes, native_fmus, tmp_path, mode
):
    """The contact mode (the sweep scene's FMU: direct feedthrough, the directional
    derivatives and their difference path; the full contact FMU: the spin input's strip
    march on the grid built for each load and its forward-mode derivative), the
    rigid_body mode and SDIRK2 (Fig. 13's FMU with that scheme: the scalar stages; the
    full body FMU with scheme "sdirk2" and the quasistationary method: the vector stages,
    algebraic while rolling, with the masses in gross sliding) under the sanitized
    importer's random calls: no sanitizer report, no fmi2Fatal, no non-finite output
    served with fmi2OK, no damaged bytes accepted."""
    import dataclasses

    import fmpy

    if mode == "contact":
        path = native_fmus["sweep"]
    elif mode in ("cornering", "rail_creep"):
        path = native_fmus[mode]
    elif mode == "fig13_sdirk2":
        cfg = dataclasses.replace(scenes["fig13"].config, schemes=("sdirk2",))
        path = native_fmu.build(cfg, OUT).path
    elif mode == "full_body_sdirk2":
        cfg = ModelConfig.full("body")
        starts = {**cfg.starts, "scheme": "sdirk2", "method": "quasistationary"}
        path = native_fmu.build(dataclasses.replace(cfg, starts=starts), OUT).path
    else:
        path = native_fmu.build(ModelConfig.full(mode.removeprefix("full_")), OUT).path
    unzip = tmp_path / "fmu"
    fmpy.extract(str(path), str(unzip))
    md = fmpy.read_model_description(str(unzip))
    spec = tmp_path / "spec.txt"
    if mode in ("contact", "cornering", "rail_creep", "fig13_sdirk2"):
        scene = scenes[{"contact": "sweep", "fig13_sdirk2": "fig13"}.get(mode, mode)]
        spec.write_text(_spec(md, scene, scene.cases[0], rows=False))
    elif mode == "full_body_sdirk2":  # its inputs and Real outputs, the start parameters
        ins = [v.valueReference for v in md.modelVariables if v.causality == "input"]
        outs = [
            v.valueReference
            for v in md.modelVariables
            if v.causality == "output" and v.type == "Real"
        ]
        spec.write_text(
            f"{len(ins)} {' '.join(map(str, ins))}\n{len(outs)} {' '.join(map(str, outs))}\n0\n"
        )
    else:
        vr = {v.name: v.valueReference for v in md.modelVariables}
        ins, outs = ("Tx", "Fx_ex", "My_ex"), ("Vx", "Omega_y")
        if mode == "full_contact":  # every input, every Real output
            ins = ("P", "Vx", "Vy", "Omega_y", "Omega_z")
            outs = ("Tx", "Ty", "Mz", "vx", "vy", "xi_sp", "adhesion")
        spec.write_text(
            f"{len(ins)} {' '.join(str(vr[n]) for n in ins)}\n"
            f"{len(outs)} {' '.join(str(vr[n]) for n in outs)}\n0\n"
        )
    try:
        exe = _sanitized(tmp_path, unzip)
    except subprocess.CalledProcessError as e:  # pragma: no cover - gcc without libasan
        pytest.skip(f"no sanitizer runtime: {e.stderr[-300:]}")
    calls = 600 if mode in ("cornering", "full_body_sdirk2") else 2000  # the spin march: slower
    env = {**os.environ, "FMU_RESOURCES": (unzip / "resources").as_uri()}
    counts = native_c.fuzz(exe, md, spec, 1, calls, env)
    assert counts["ok"] > calls // 3 and counts["error"] > calls // 30, counts
    assert counts["refused"] > calls // 100, counts


def test_libcosim_runs_the_native_fmu_to_fmpys_numbers(scenes, native_fmus, fig13_expected):
    """libcosim (Open Simulation Platform) drives the native Fig. 13 FMU: 60 steps of the
    case eta = 3 give fmpy's doubles."""
    pytest.importorskip("libcosimpy")
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
    from libcosimpy.CosimManipulator import CosimManipulator
    from libcosimpy.CosimObserver import CosimObserver
    from libcosimpy.CosimSlave import CosimLocalSlave

    log_output_level(CosimLogLevel.ERROR)
    scene = scenes["fig13"]
    case = scene.case("eta = 3")
    fmu = native_fmus["fig13"]
    execution = CosimExecution.from_step_size(step_size=round(scene.step * 1e9))
    slave = execution.add_local_slave(CosimLocalSlave(fmu_path=str(fmu), instance_name="n"))
    vr = {v.name.decode(): v.reference for v in execution.slave_variables(slave)}
    for name, value in runner.start_values(scene, case).items():
        assert execution.real_initial_value(slave, vr[name], float(value))
    observer = CosimObserver.create_last_value()
    execution.add_observer(observer)
    override = CosimManipulator.create_override()
    execution.add_manipulator(override)
    table = runner.input_table(scene, case)
    reals = [o for o in scene.outputs if o != "regime"]
    got = []
    for k in range(60):
        override.slave_real_values(
            slave, [vr[i] for i in scene.inputs], [float(table[i][k]) for i in scene.inputs]
        )
        assert execution.step()
        got.append(observer.last_real_values(slave, [vr[o] for o in reals]))
    # libcosim's step is an integer count of nanoseconds, its double not always fmpy's
    # (1.75e-4 s): the substep differs by a rounding, the outputs by rounding times the
    # sensitivity of 60 steps
    want = fig13_expected[:60]
    err = np.abs(np.array(got) - want) / np.abs(want).max(axis=0)
    assert err.max() <= 1e-9, err.max()


def test_contact_fmu_outputs_follow_the_inputs_directly(native_fmus, python_fmus):
    """Contact mode (direct feedthrough): outputs read after setReal, before any doStep,
    are the law at the new inputs, the pythonfmu FMU's doubles without lateral slip; a
    new load P changes Tx at the same creepage (the ellipse of Eq. 34 follows it); a bad
    input answers fmi2Error at getReal (the last outputs are kept, not to be used)."""
    from fmpy.fmi1 import FMICallException

    got = []
    for path in (native_fmus["sweep"], python_fmus["sweep"]):
        with Instance(path, "c") as c:
            rows = []
            for xi, P in ((-0.01, 1000.0), (0.004, 1000.0), (0.004, 1500.0), (0.03, 700.0)):
                c.set("P", P)
                c.set("Omega_y", ex.speed_unit() / ex.Rx * (1.0 - xi))
                rows.append(c.outputs())
            with pytest.raises(FMICallException):
                c.set("Vx", math.nan)
            with pytest.raises(FMICallException) as e:
                c.get("Tx")
            assert e.value.status == ERROR
            assert "no outputs for the current inputs: Vx = nan is invalid" in c.messages[-1][1]
            got.append(rows)
    assert got[0] == got[1]
    assert got[0][2]["Tx"] != got[0][1]["Tx"]


# ---- contact mode: directional derivatives, a linearly implicit master -------------------------
def _contact_config(name: str = "force_element") -> ModelConfig:
    return ModelConfig(
        name=name,
        mode="contact",
        inputs=("P", "Vx", "Vy", "Omega_y"),
        outputs=("Tx", "Ty", "Mz", "vx", "xi_x", "adhesion"),
    )


def central_differences(inst: Instance, name: str, value: float, d: float) -> dict:
    """(outputs(value + d) - outputs(value - d)) / (2 d) along the input ``name`` (held at
    ``value`` before and after)."""
    inst.set(name, value + d)
    hi = inst.outputs()
    inst.set(name, value - d)
    lo = inst.outputs()
    inst.set(name, value)
    return {o: (hi[o] - lo[o]) / (2 * d) for o in hi}


def test_directional_derivatives_of_the_force_element_are_its_slopes():
    """providesDirectionalDerivative in contact mode: d(Tx, Ty, Mz, vx)/d(Vx, Vy, Omega_y)
    analytic (the closed form's partials), d/dP and d(xi_x, adhesion) by central
    differences, against central differences of the outputs (step 1e-7 of the input's
    scale, truncation and rounding below 1e-6 of mu P per unit input) over partial slip,
    full slip, lateral slip and both rolling directions."""
    path = native_fmu.build(_contact_config(), OUT).path
    md = _md(path)
    assert md.find("CoSimulation").get("providesDirectionalDerivative") == "true"
    rng = np.random.default_rng(2)
    with Instance(path, "dd") as c:
        vr = {n: v.valueReference for n, v in c.vars.items()}
        outs = ["Tx", "Ty", "Mz", "vx", "xi_x", "adhesion"]
        law = ex.contact()
        for _ in range(40):
            Vx = float(rng.choice([-1.0, 1.0]) * 10 ** rng.uniform(-1, 1.3))
            xi = rng.uniform(-1.5, 1.5, 2) * law.creep_full_slip  # beyond full slip too
            Oy = (Vx - xi[0] * abs(Vx)) / ex.Rx
            u = {"P": float(rng.uniform(500, 1500)), "Vx": Vx, "Vy": xi[1] * abs(Vx), "Omega_y": Oy}
            for k, v in u.items():
                c.set(k, v)
            for name in ("Vx", "Vy", "Omega_y", "P"):
                got = c.fmu.getDirectionalDerivative([vr[o] for o in outs], [vr[name]], [1.0])
                d = 1e-7 * max(abs(u[name]), 1e-3 * abs(Vx))
                diff = central_differences(c, name, u[name], d)
                for o, g in zip(outs, got, strict=True):
                    fd = diff[o]
                    scale = {"Tx": MU_P, "Ty": MU_P, "Mz": MU_P * law.a1}.get(o, 1.0)
                    tol = 1e-6 * scale / max(abs(u[name]), 1e-3) + 1e-6 * abs(fd)
                    if name == "P" or o in ("xi_x", "adhesion"):
                        # differences of two step sizes: their truncation errors, up to
                        # 1e-5 relative where the adhesion's slope steepens at full slip
                        tol = 1e-4 * abs(fd) + 1e-9 * scale
                    assert abs(g - fd) <= tol, (o, name, g, fd, u)


def _coupled(h: float, implicit: bool, t_end: float = 0.03) -> np.ndarray:
    """A master coupling the native contact FMU (Tx of Vx, Omega_y) and the native
    rigid_body FMU (Eqs. 8-9), Fig. 13's body with eta = 3 under Fx_ex = F, My_ex =
    -0.1 F Rx, step h. Explicit: the body steps under the last Tx. Linearly implicit
    (Rosenbrock-Euler): Tx over the step is Tx_n + a dVx + b dOmega_y with (a, b) =
    d Tx/d(Vx, Omega_y) from the FMU's directional derivatives, and the increments solve
    M dVx = h (Fx - Tx), Iy dOmega_y = h (My + Rx Tx) with it. Tx per step."""
    M, Rx, Iy, Fx, My = ex.M, ex.Rx, ex.M * ex.Rx**2 / 3.0, F, -0.1 * F * ex.Rx
    contact = ModelConfig(name="force", mode="contact", inputs=("P", "Vx", "Omega_y"),
                          outputs=("Tx",))  # fmt: skip
    c_path = native_fmu.build(contact, OUT).path
    b_path = native_fmu.build(ModelConfig.full("rigid_body"), OUT).path
    V0 = ex.speed_unit()
    with (
        Instance(c_path, "c") as c,
        Instance(b_path, "b", {"Iy": Iy, "Vx0": V0}) as b,
    ):
        vr = {n: v.valueReference for n, v in c.vars.items()}
        b.set("Fx_ex", Fx)
        b.set("My_ex", My)
        Vx, Oy = V0, V0 / Rx
        out = []
        for _ in range(int(round(t_end / h))):
            c.set("Vx", Vx)
            c.set("Omega_y", Oy)
            T = c.get("Tx")
            if implicit:
                a, bb = (
                    c.fmu.getDirectionalDerivative([vr["Tx"]], [vr[n]], [1.0])[0]
                    for n in ("Vx", "Omega_y")
                )
                # [M + h a, h b; -h Rx a, Iy - h Rx b] (dVx, dOy) = h (Fx - T, My + Rx T)
                A = np.array([[M + h * a, h * bb], [-h * Rx * a, Iy - h * Rx * bb]])
                dV, dO = np.linalg.solve(A, h * np.array([Fx - T, My + Rx * T]))
                T = T + a * dV + bb * dO
            b.set("Tx", T)
            assert c.step(h) == OK and b.step(h) == OK
            Vx, Oy = b.get("Vx"), b.get("Omega_y")
            out.append(T)
        return np.array(out)


def test_linearly_implicit_master_is_stable_at_vehicle_steps_where_explicit_oscillates():
    """With the force element's analytic Jacobian a linearly implicit master couples the
    contact and rigid-body FMUs at h = 1e-3 s, 70 slip relaxation times (tau = 1.4e-5 s,
    test_cosim_libcosim): Tx settles to Eq. (26), A2 Fx_ex - A1 My_ex/Rx = 0.325 F, within
    1e-3 of mu P (Rosenbrock-Euler is L-stable on the slip mode; what remains is the
    slope change of the law along a step). The explicit coupling at the same step swings
    between about +mu P and -mu P."""
    target = 0.25 * F + 0.75 * 0.1 * F
    Ti = _coupled(1e-3, implicit=True)
    assert np.all(np.abs(Ti) <= MU_P)
    assert np.max(np.abs(Ti[-10:] - target)) <= 1e-3 * MU_P, Ti[-10:]
    Te = _coupled(1e-3, implicit=False)
    swing = Te[-10:]
    assert swing.max() > 0.9 * MU_P and swing.min() < -0.9 * MU_P, swing


def test_cornering_state_with_its_kept_newton_matrix_repeats_bit_for_bit(scenes, native_fmus):
    """The vector path's state (Vy, Omega_z, the kept Newton matrix of the stage solve)
    through get/set and through bytes into a fresh instance (which builds its own spin
    grid at the state's load): the same steps give the same doubles."""
    scene = scenes["cornering"]
    case = scene.cases[0]
    table = runner.input_table(scene, case)
    starts = runner.start_values(scene, case)
    path = native_fmus["cornering"]

    def drive(inst: Instance, k0: int, n: int) -> dict:
        for k in range(k0, k0 + n):
            for name in scene.inputs:
                inst.set(name, float(table[name][k]))
            assert inst.step(scene.step) == OK, inst.messages[-1:]
        return inst.outputs()

    with Instance(path, "a", starts) as a, Instance(path, "b", starts) as b:
        drive(a, 0, 30)  # past the lateral force's onset at 0.5 ms
        state = a.get_state()
        data = a.serialize_state(state)
        first = drive(a, 30, 10)
        a.set_state(state)
        assert drive(a, 30, 10) == first
        b.set_state(b.deserialize_state(data, state[1]))
        assert drive(b, 30, 10) == first
        assert first["Vy"] != 0.0 and first["Omega_z"] != 0.0


def test_a_damaged_or_missing_table_resource_is_refused_at_instantiation(native_fmus, tmp_path):
    """The half-space FMU reads its creep-force table from its resources at
    instantiation: a flipped byte (checksum) or a missing file is refused there with a
    logged reason (fmpy raises), never read."""
    import fmpy

    unzip = tmp_path / "fmu"
    fmpy.extract(str(native_fmus["rail_creep"]), str(unzip))
    table = unzip / "resources" / "table.bin"
    data = bytearray(table.read_bytes())
    data[len(data) // 2] ^= 0x01
    table.write_bytes(bytes(data))
    with pytest.raises(Exception, match="nstantiate"):
        Instance(native_fmus["rail_creep"], "t", unzip_dir=unzip)
    table.unlink()
    with pytest.raises(Exception, match="nstantiate"):
        Instance(native_fmus["rail_creep"], "t", unzip_dir=unzip)
