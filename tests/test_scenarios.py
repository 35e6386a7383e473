"""Scenes: signals, the TOML schema, every scene against its reference, the command line."""

from __future__ import annotations

import math
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import fmu_build
from contact_fmu import cli
from contact_fmu import examples as ex
from contact_fmu.fmu import variables as fv
from contact_fmu.scenario import ScenarioError, discover, load, runner
from contact_fmu.scenario.signals import SignalError, held, parse

ROOT = Path(__file__).resolve().parents[1]
SCENARIOS = ROOT / "scenarios"
OUT = ROOT / "out" / "fmu"


# ---- signals ------------------------------------------------------------------------------
def test_signal_pieces_and_their_sum():
    t = np.array([0.0, 0.5, 1.0, 1.5, 2.0, 3.0])
    assert np.array_equal(parse("u", 2.5)(t), np.full(6, 2.5))
    assert np.array_equal(parse("u", {"constant": -1.0})(t), np.full(6, -1.0))
    assert np.array_equal(parse("u", {"step": {"time": 1.0, "height": 3.0}})(t), [0, 0, 3, 3, 3, 3])
    ramp = parse("u", {"ramp": {"start": 1.0, "duration": 1.0, "height": 4.0}})(t)
    assert np.array_equal(ramp, [0, 0, 0, 2, 4, 4])
    sine = parse("u", {"sine": {"amplitude": 2.0, "period": 4.0, "phase": 0.0, "start": 1.0}})
    assert np.allclose(sine(t), [0, 0, 0, 2 * math.sin(math.pi / 4), 2.0, 0.0], atol=1e-15)
    table = {"table": {"time": [0.0, 1.0, 2.0], "value": [0.0, 10.0, 0.0]}}
    assert np.array_equal(parse("u", table)(t), [0, 5, 10, 5, 0, 0])
    hold = {"table": {"time": [0.0, 1.0, 2.0], "value": [0.0, 10.0, 0.0], "hold": True}}
    assert np.array_equal(parse("u", hold)(t), [0, 0, 10, 10, 0, 0])
    total = parse("u", [1.0, {"step": {"time": 1.0, "height": 3.0}}])(t)
    assert np.array_equal(total, [1, 1, 4, 4, 4, 4])


@pytest.mark.parametrize(
    ("spec", "fragment"),
    [
        ({"pulse": {"time": 1.0}}, "unknown piece 'pulse'"),
        ({"ramp": {"start": 0.0, "duration": -1.0, "height": 1.0}}, "'duration' = -1.0"),
        ({"step": {"time": 1.0}}, "missing 'height'"),
        ({"step": {"time": 1.0, "height": "big"}}, "'height' = 'big' must be a finite number"),
        ({"sine": {"amplitude": 1.0, "period": 0.0}}, "'period' = 0.0 must be > 0"),
        ({"table": {"time": [0.0, 0.0], "value": [1.0, 2.0]}}, "must increase strictly"),
        ({"table": {"time": [0.0], "value": [1.0, 2.0]}}, "the same length"),
        ("1.0", "a piece is one of"),
        ([], "an empty list"),
    ],
)
def test_malformed_signal_is_refused_naming_the_input(spec, fragment):
    with pytest.raises(SignalError) as e:
        parse("My_ex", spec)
    assert "inputs.My_ex" in str(e.value) and fragment in str(e.value)


def test_held_inputs_are_those_of_the_step_ending_at_each_point():
    assert np.array_equal(held(np.array([1.0, 2.0, 3.0, 4.0])), [1.0, 1.0, 2.0, 3.0])


# ---- schema -------------------------------------------------------------------------------
GOOD = """
name = "mini"
[model]
mode = "body"
[run]
stop_time = 1.0e-3
step = 1.0e-4
outputs = ["Tx"]
[parameters]
mu = 0.3
Rx = 0.05
Ry = 0.10
k1 = 5.0e-13
k2 = 5.0e-13
kb = 3.2e-13
ks = 3.2e-13
M = 1.0
Iy = 8.333333333333335e-4
Vx0 = 5.6418958354775635
[inputs]
P = 1000.0
"""


@pytest.mark.parametrize(
    ("edit", "fragment"),
    [
        (("", 'colour = "red"\n'), "inputs.colour = 'red': no FMU variable is called 'colour'"),
        (('name = "mini"', 'name = "mini"\ncolour = "red"'), "unknown key(s) ['colour']"),
        (("step = 1.0e-4", "step = 3.0e-4"), "must be stop_time/step whole"),
        (("step = 1.0e-4", "step = -1.0e-4"), "run.step = -0.0001 is invalid: must be a finite"),
        (('outputs = ["Tx"]', 'outputs = ["Ty"]'), "run.outputs = ['Ty']: Ty is a variable"),
        (('mode = "body"', 'mode = "body"\ncontact_law = "halfspace"'),
         "parameters.Ry = 0.1: Ry is a parameter of the layer law: a halfspace model takes its "
         "contact from [halfspace]"),
        (('mode = "body"', 'mode = "body"\nphase = "transient"\nmethod = "quasistationary"'),
         "model.method = ['quasistationary'] is invalid"),
        (
            ('outputs = ["Tx"]', 'outputs = ["Tx"]\nfield = { times = [0.0], file = "f.csv" }'),
            'needs phase = "transient"',
        ),
        (('mode = "body"', 'mode = "body"\nmethod = "euler"'), "model.method = 'euler' is invalid"),
        (("P = 1000.0", "P = 1000.0\nFx_ex = { pulse = 1 }"), "unknown piece 'pulse'"),
        (("P = 1000.0", ""), "inputs.P is missing"),
        (("mu = 0.3", "mu = 0.0"), f"parameters.mu = 0.0 is invalid: must be >= {fv.MU_MIN:g}"),
        (("mu = 0.3", "mu = 0.3\nIz = 1.0e-3"), 'Iz is a variable of this body-mode model only '
         'with model.spin = "eq11"'),
        (('name = "mini"', 'name = "mini scene"'), "must be an identifier"),
    ],
)  # fmt: skip
def test_malformed_scene_is_refused_naming_the_file_and_key(tmp_path, edit, fragment):
    old, new = edit
    text = (GOOD + new) if old == "" else GOOD.replace(old, new)
    path = tmp_path / "mini.toml"
    path.write_text(text)
    with pytest.raises(ScenarioError) as e:
        load(path)
    msg = str(e.value)
    assert msg.startswith(f"{path}: ") and msg.count(str(path)) == 1 and "\n" not in msg
    assert fragment in msg, msg


def test_minimal_scene_loads(tmp_path):
    path = tmp_path / "mini.toml"
    path.write_text(GOOD)
    scene = load(path)
    assert scene.n_steps == 10 and scene.grid[-1] == pytest.approx(1e-3, rel=1e-15)
    assert scene.config.inputs == ("P",) and [c.name for c in scene.cases] == ["default"]


def test_scene_numbers_are_the_example_parameter_set():
    """The scenes write the numbers of contact_fmu.examples as data: they must agree.
    (The half-space scenes use the railway set instead: tests/test_fmu_halfspace.py.)"""
    c = ex.contact()
    for path in discover(SCENARIOS):
        scene = load(path)
        if scene.config.contact_law != "layer":
            continue
        for case in scene.cases:
            p = case.parameters
            for name in ("mu", "Rx", "Ry", "k1", "k2", "kb", "ks"):
                assert p[name] == getattr(c, name), (scene.name, name)
            assert float(case.inputs["P"](np.zeros(1))[0]) == ex.P
            if scene.config.mode == "body":
                assert p["M"] == ex.M and p["Vx0"] == ex.speed_unit()
                # pure rolling; liftoff starts sliding (its reference is gross sliding)
                assert p["vx0"] == (0.5 if scene.name == "liftoff" else 0.0)
            if case.name.startswith("eta = "):
                eta = float(case.name.split("=")[1])
                assert p["Iy"] == pytest.approx(ex.M * ex.Rx**2 / eta, rel=1e-15)


def test_fig13_loads_are_those_of_the_paper():
    scene = load(SCENARIOS / "fig13.toml")
    F, Tc = ex.force_unit(), ex.time_unit()
    t = scene.grid
    for case in scene.cases:
        assert np.all(case.inputs["Fx_ex"](t) == F)
        My = 0.2 * F * ex.Rx * np.sin(t / Tc)  # Fig. 13: 0.2 mu p0 Rx a1 a2 sin(t/T_c)
        assert np.allclose(case.inputs["My_ex"](t), My, rtol=0, atol=1e-14)
    assert sorted(float(c.name.split("=")[1]) for c in scene.cases) == sorted(ex.ETA_FIG13)


def test_fig12_holds_the_lateral_creepage_of_the_paper():
    scene = load(SCENARIOS / "fig12.toml")
    assert scene.config.vy == "ratio"
    assert all(c.parameters["vy_ratio"] == 0.002 for c in scene.cases)
    assert sorted(float(c.name.split("=")[1]) for c in scene.cases) == sorted(ex.ETA_FIG6_12)
    assert all(np.all(c.inputs["Fx_ex"](scene.grid) == ex.force_unit()) for c in scene.cases)


# ---- every scene against its reference ----------------------------------------------------
@pytest.fixture(scope="session")
def results():
    """Each scene run once through fmpy: {name: (scene, results)}."""
    out = {}
    for path in discover(SCENARIOS):
        scene = load(path)
        out[scene.name] = (scene, runner.simulate(fmu_build.build(scene.config, OUT).path, scene))
    return out


@pytest.mark.parametrize(
    "name",
    [
        "fig13",
        "fig12",
        "railway",
        "brake",
        "sweep",
        "rail_creep",
        "rail_traction",
        "fig12_transient",
    ],
)
def test_scene_matches_its_reference(results, name):
    scene, res = results[name]
    assert all(r.error is None for r in res), [r.error for r in res]
    checks = runner.compare(scene, res)
    assert checks and all(c.points > 0 for c in checks)
    bad = [c for c in checks if not c.ok]
    assert not bad, [(c.reference, c.case, c.variable, c.max_error, c.tolerance) for c in bad]
    # every case is checked against at least one reference
    assert {c.case for c in checks} == {c.name for c in scene.cases}


def test_forces_stay_within_mu_p_in_every_scene(results):
    for scene, res in results.values():
        for r in res:
            mu = scene.case(r.case).parameters.get("mu", ex.mu)
            # P: recorded input, per step; the output at t_k has the P held over the step
            # ending there, P(t_(k-1)) (liftoff ramps it): the larger of the two
            P = np.asarray(r.columns["P"], float)
            cap = mu * np.maximum(P, np.r_[P[:1], P[:-1]]) * (1 + 1e-12)
            assert np.all(np.hypot(r.columns.get("Tx", 0.0), r.columns.get("Ty", 0.0)) <= cap)


def test_brake_scene_slides_and_returns_to_rolling(results):
    scene, (r,) = results["brake"]
    regime, t = r.columns["regime"], r.columns["time"]
    assert np.any(regime == 1) and regime[0] == 0 and regime[-1] == 0
    sliding = t[regime == 1]
    assert 5e-4 < sliding[0] < 8e-4 and 2.5e-3 < sliding[-1] < 4.0e-3


# ---- command line -------------------------------------------------------------------------
def _copy_scene(name: str, dest: Path) -> Path:
    scene = load(SCENARIOS / f"{name}.toml")
    (dest / "references").mkdir(parents=True, exist_ok=True)
    for ref in scene.references:
        shutil.copy(ref.file, dest / "references" / ref.file.name)
    return Path(shutil.copy(scene.path, dest / scene.path.name))


def test_cli_run_writes_csv_and_png_and_passes(tmp_path):
    proc = subprocess.run(
        [sys.executable, "-m", "contact_fmu.cli", "run", str(SCENARIOS / "sweep.toml"),
         "--out", str(tmp_path)],
        capture_output=True, text=True, cwd=ROOT,
    )  # fmt: skip
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert "PASS" in proc.stdout
    csv, png = tmp_path / "scenes/sweep/sweep.csv", tmp_path / "scenes/sweep/sweep.png"
    assert png.stat().st_size > 10_000
    lines = csv.read_text().splitlines()
    assert lines[0].startswith("case,time,P,Vx,Vy,Omega_y,Tx")
    assert len(lines) == 1 + 2 * 201  # two cases on 201 grid points


def test_cli_run_exits_non_zero_on_a_mismatch(tmp_path):
    path = _copy_scene("sweep", tmp_path / "scenes")
    ref = tmp_path / "scenes/references/sweep_traction.csv"
    tables = runner.read_reference(ref)
    for d in tables.values():
        d["Tx"] = d["Tx"] * 1.01  # 1 % off: far beyond the 0.028 N tolerance
    runner.write_reference(ref, tables)
    code = cli.main(["run", str(path), "--out", str(tmp_path / "out"), "--no-plot"])
    assert code == 1


def test_cli_run_all_runs_every_scene(tmp_path, capsys):
    code = cli.main(["run", "--all", "--scenarios", str(SCENARIOS), "--out", str(tmp_path),
                     "--no-plot"])  # fmt: skip
    out = capsys.readouterr().out
    assert code == 0, out
    assert out.count("PASS") == len(discover(SCENARIOS))
    assert len(list((tmp_path / "scenes").glob("*/*.csv"))) == len(discover(SCENARIOS))


def test_cli_reports_a_malformed_scene(tmp_path, capsys):
    bad = tmp_path / "bad.toml"
    bad.write_text("name = 'bad'\n[run]\nstop_time = 1.0\n")
    assert cli.main(["run", str(bad), "--out", str(tmp_path)]) == 1
    assert "bad.toml" in capsys.readouterr().err


def test_console_entry_keeps_the_status_and_messages(tmp_path):
    """The console script ends the process without finalisation (cli.entry, pythonfmu
    teardown): a failure's status and message, and --help's 0, still come out."""
    bad = tmp_path / "bad.toml"
    bad.write_text("name = 'bad'\n[run]\nstop_time = 1.0\n")
    cmd = [sys.executable, "-m", "contact_fmu.cli"]
    proc = subprocess.run([*cmd, "run", str(bad), "--out", str(tmp_path)],
                          capture_output=True, text=True, cwd=ROOT)  # fmt: skip
    assert proc.returncode == 1 and "bad.toml" in proc.stderr
    proc = subprocess.run([*cmd, "--help"], capture_output=True, text=True, cwd=ROOT)
    assert proc.returncode == 0 and "usage" in proc.stdout
    proc = subprocess.run([*cmd, "no-such-command"], capture_output=True, text=True, cwd=ROOT)
    assert proc.returncode == 2 and "invalid choice" in proc.stderr
