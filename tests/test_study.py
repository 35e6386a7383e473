"""Parameter studies on dask.distributed (contact_fmu.study, ``contact-fmu sweep``).

What is checked: a sweep on a LocalCluster of two worker processes gives the serial
sweep's rows exactly (each run is deterministic; the engine only moves it); a failed
run (the FMU's fmi2Discard, a value the scene rejects) is a row with its reason while
the other rows keep their values; a creep-force table built through Dask is the serial
build, bit for bit; the study scene's peak traction agrees with Eq. (26); the values'
grammar, the scene's [sweep] checks, the metrics' reductions and the command line.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq
import pytest

from contact_fmu import InputError, cli
from contact_fmu.halfspace.railway import wheel_on_rail
from contact_fmu.halfspace.table import TableData, build_table
from contact_fmu.report.workprecision import run_scene
from contact_fmu.scenario import ScenarioError, load, variation
from contact_fmu.scenario.schema import Metric, Vary, sweep_values
from contact_fmu.study import metrics, sweep
from contact_fmu.study import tables as study_tables
from contact_fmu.study.engine import Engine, batches
from fmu_build import tables as fmu_tables

ROOT = Path(__file__).resolve().parents[1]
SCENARIOS = ROOT / "scenarios"
OUT = ROOT / "out" / "fmu"
STUDY = SCENARIOS / "studies" / "fig13_peak.toml"
# Numbers of scenarios/fig13.toml: F = mu p0 a1 a2 (N), the moment's period 2 pi T_c (s).
F = 190.98593171027443
PERIOD = 0.055683279968317075
RX = 0.05
MU_P = 300.0


@pytest.fixture(scope="module")
def engine():
    """One LocalCluster of two worker processes for the module (its start costs seconds)."""
    with Engine(workers=2, progress=False) as eng:
        yield eng


def _short_scene(tmp_path: Path, p_step: float = -500.0) -> Path:
    """fig13 cut to 20 steps, with P stepping by ``p_step`` at t = 1.75 ms."""
    text = (SCENARIOS / "fig13.toml").read_text()
    text = text.replace("stop_time = 0.056", "stop_time = 3.5e-3")
    text = text.replace(
        "P = 1000.0", f"P = [1000.0, {{ step = {{ time = 1.75e-3, height = {p_step} }} }}]"
    )
    text = text[: text.index("[[reference]]")] + text[text.index("[plot]") :]
    path = tmp_path / "short.toml"
    path.write_text(text)
    return path


# ---- the engine ---------------------------------------------------------------------------
def test_sweep_on_two_workers_equals_the_serial_sweep_row_for_row(engine):
    """2 x 2 values x 3 cases of fig13: the same rows, in the same order, bit for bit
    (the run index, the values, the case, the status and every metric)."""
    scene = load(SCENARIOS / "fig13.toml")
    vary = (Vary("mu", (0.25, 0.35)), Vary("My_ex.sine.amplitude", (1.0, 6.0)))
    with Engine(workers=0, progress=False) as serial:
        rows_serial = sweep.sweep(scene, vary, serial, OUT)
    rows_dask = sweep.sweep(scene, vary, engine, OUT, share_by_path=False)  # FMU shipped
    assert len(rows_serial) == 12 and all(r["status"] == "ok" for r in rows_serial)
    assert [r["run"] for r in rows_dask] == list(range(12))
    np.testing.assert_equal(rows_dask, rows_serial)


def test_sweep_through_a_running_scheduler_ships_the_fmu(engine):
    """--scheduler ADDRESS: a client of a running cluster (here the module's), the FMU sent
    to the workers as bytes: the rows of the serial sweep."""
    scene = load(SCENARIOS / "fig13.toml")
    vary = (Vary("Fx_ex", (50.0, 150.0)),)
    with Engine(workers=0, progress=False) as serial:
        want = sweep.sweep(scene, vary, serial, OUT)
    with Engine(scheduler=engine.client.scheduler.address, progress=False) as remote:
        assert "1 workers" not in remote.describe() and "2 workers" in remote.describe()
        np.testing.assert_equal(sweep.sweep(scene, vary, remote, OUT), want)


def test_report_families_on_two_workers_give_the_serial_errors(engine):
    """The work-precision families of fig12 (quick) as Dask tasks: every point's errors
    and settings are the serial report's (only the measured times differ)."""
    scene = load(SCENARIOS / "fig12.toml")
    kw = {"quick": True, "repeats": 1, "log": lambda _m: None}
    serial = run_scene(scene, OUT, **kw)
    dask = run_scene(scene, OUT, engine=engine, **kw)
    keys = ("family", "level", "h", "Tx_max", "Tx_rms", "vx_max", "vx_rms", "error")
    assert len(serial.rows) == len(dask.rows) > 4
    for a, b in zip(serial.rows, dask.rows, strict=True):
        np.testing.assert_equal([getattr(b, k) for k in keys], [getattr(a, k) for k in keys])


def test_a_failed_run_is_a_row_and_the_others_keep_their_values(tmp_path, engine):
    """P steps to -1000 N in one run: the FMU refuses the value with fmi2Error at its
    setReal (Eq. 33 needs P > 0) and the row says so; mu = -0.1 is refused by the scene check; every other run is ok
    with the values of a sweep without the failing ones."""
    scene = load(_short_scene(tmp_path))
    vary = (Vary("P.step.height", (-500.0, -2000.0)), Vary("mu", (0.3, -0.1)))
    rows = sweep.sweep(scene, vary, engine, OUT)
    assert len(rows) == 2 * 2 * 3
    by = {(r["P.step.height"], r["mu"], r["case"]): r for r in rows}
    for case in ("eta = 1.5", "eta = 3", "eta = 10"):
        bad = by[(-2000.0, 0.3, case)]["status"]
        assert bad.startswith("error:") and "at t = 0.00175 s" in bad, bad
        assert "P = -1000.0 is invalid" in bad, bad
        assert math.isnan(by[(-2000.0, 0.3, case)]["Tx_final"])
        for h in (-500.0, -2000.0):
            rejected = by[(h, -0.1, case)]["status"]
            assert rejected.startswith("rejected:") and "mu" in rejected, rejected
    good = [r for r in rows if r["status"] == "ok"]
    assert len(good) == 3
    alone = sweep.sweep(scene, (Vary("P.step.height", (-500.0,)), Vary("mu", (0.3,))), engine, OUT)
    keep = [k for k in good[0] if k != "run"]
    assert [{k: r[k] for k in keep} for r in good] == [{k: r[k] for k in keep} for r in alone]


def test_creep_force_table_built_through_dask_equals_the_serial_build(engine):
    """A 7 x 5 x 3 table on an 8 x 8 grid: every nodal value and onset identical."""
    contact = wheel_on_rail(n=8)
    serial = build_table(contact, nodes=(7, 5, 3))
    dask = build_table(contact, nodes=(7, 5, 3), map_tasks=engine.mapper("table", batch=3))
    assert np.array_equal(dask.data.values, serial.data.values)
    assert np.array_equal(dask.data.onset, serial.data.onset)
    assert all(np.array_equal(a, b) for a, b in zip(dask.data.axes, serial.data.axes, strict=True))


def test_scene_table_through_dask_is_the_fmu_builds_file(tmp_path, engine):
    """study.tables.ensure (the engine) and fmu_build.tables.ensure (a subprocess, serial)
    on rail_creep's declaration cut to 8 x 8 elements and 5 x 5 x 3 nodes: the same file
    name (content key) and the same nodal values and onsets."""
    text = (SCENARIOS / "rail_creep.toml").read_text()
    text = text.replace("grid = 32 ", "grid = 8 ").replace(
        "nodes = [25, 21, 3]", "nodes = [5, 5, 3]"
    )
    path = tmp_path / "tiny.toml"
    path.write_text(text[: text.index("[[reference]]")])
    cfg = load(path).config
    a = study_tables.ensure(cfg, engine, cache=tmp_path / "dask")
    b = fmu_tables.ensure(cfg, tmp_path / "serial")
    assert a.name == b.name
    ta, tb = TableData.load(a), TableData.load(b)
    assert ta.values.shape == (1, 5, 5, 3, 4)
    assert np.array_equal(ta.values, tb.values) and np.array_equal(ta.onset, tb.onset)


def test_engine_keeps_the_order_and_reports_failures_per_item(engine):
    def work(shared, x):
        if x == 3:
            raise ValueError("three")
        return shared * x

    out = engine.map(work, list(range(7)), shared=10, batch=2, on_error=lambda x, e: str(e))
    assert out == [0, 10, 20, "three", 40, 50, 60]
    with pytest.raises(ValueError, match="three"):
        engine.map(work, list(range(7)), shared=10)


def test_batches_cover_the_items_in_order():
    parts = batches(64, 2)
    assert [p.start for p in parts] == list(range(0, 64, 8)) and parts[-1].stop == 64
    assert batches(3, 16) == [slice(0, 1), slice(1, 2), slice(2, 3)]


def test_engine_refuses_bad_settings():
    with pytest.raises(InputError, match="workers"):
        Engine(workers=-1)
    with pytest.raises(InputError, match="workers"):
        Engine(workers=2, scheduler="tcp://localhost:8786")


def test_runs_in_one_process_do_not_grow_sys_path():
    """pythonfmu prepends the FMU's resources folder at every instantiation: after 6 runs
    at most one entry is new."""
    scene = load(SCENARIOS / "fig13.toml")
    before = len(sys.path)
    with Engine(workers=0, progress=False) as serial:
        sweep.sweep(scene, (Vary("mu", (0.2, 0.3)),), serial, OUT)
    assert len(sys.path) - before <= 1


# ---- the study scene: Eq. (26) -------------------------------------------------------------
def test_study_peak_traction_follows_eq26(engine):
    """fig13_peak at eta = 3 and 10, a = 0.2 and 1 F Rx: after the slip transient
    Tx = A2 Fx_ex - A1 My_ex/Rx with the loads held over each step (Eq. 26), so the peak
    |Tx|/(mu P) is its largest value over the grid from 2 ms on. Tolerance 0.2 N / (mu P):
    the scene fig13's, derived there for eta >= 1.5."""
    scene = load(STUDY)
    etas = (3.0, 10.0)
    amps = (0.2 * F * RX, F * RX)
    vary = (Vary("Iy", tuple(RX**2 / e for e in etas)), Vary("My_ex.sine.amplitude", amps))
    rows = sweep.sweep(scene, vary, engine, OUT)
    t = scene.grid
    for r in rows:
        eta = RX**2 / r["Iy"]
        A1, A2 = eta / (1 + eta), 1 / (1 + eta)
        held = np.concatenate([t[:1], t[:-1]])
        My = r["My_ex.sine.amplitude"] * np.sin(2 * np.pi * held / PERIOD)
        Tx = A2 * F - A1 * My / RX
        want = np.max(np.abs(Tx[t >= 2e-3])) / MU_P
        assert r["status"] == "ok" and r["gross_sliding"] == 0.0
        assert r["peak_traction"] == pytest.approx(want, abs=0.2 / MU_P), (eta, r)


# ---- scene data: values, [sweep], variation, metrics ---------------------------------------
@pytest.mark.parametrize(
    ("text", "values"),
    [("0.1:0.5:5", (0.1, 0.2, 0.3, 0.4, 0.5)), ("0.1,0.2, 0.3", (0.1, 0.2, 0.3)),
     ([1, 2.5], (1.0, 2.5)), ("-1:1:2", (-1.0, 1.0))],
)  # fmt: skip
def test_values_as_list_or_range(text, values):
    assert sweep_values("x", text) == pytest.approx(values, rel=1e-15)


@pytest.mark.parametrize("text", ["0.1:0.5", "0.1:0.5:1", "0.1:0.5:2.5", "a,b", "", [], [1, 1],
                                  "1:2:3:4", [math.inf]])  # fmt: skip
def test_bad_values_are_refused_naming_them(text):
    with pytest.raises(InputError, match="mu"):
        sweep_values("mu", text)


SWEEP = '\n[sweep]\nvary = { mu = "0.2:0.4:3" }\n'


@pytest.mark.parametrize(
    ("extra", "fragment"),
    [
        ('\n[sweep]\nvary = { nope = [1.0] }\n', "sweep.vary.nope"),
        ('\n[sweep]\nvary = { "My_ex.ramp.height" = [1.0] }\n', "'ramp' pieces"),
        ('\n[sweep]\nvary = { "My_ex.sine.color" = [1.0] }\n', "sine.color"),
        ('\n[sweep]\nvary = { mu = "1:2" }\n', "sweep.vary.mu"),
        (SWEEP + 'metrics = [{ name = "m", of = "Tz", reduce = "max" }]\n', "'Tz' is not recorded"),
        (SWEEP + 'metrics = [{ name = "m", of = "Tx", reduce = "median" }]\n', "'median'"),
        (SWEEP + 'metrics = [{ name = "m", of = "Tx", reduce = "settle_time" }]\n', "'tol'"),
        (SWEEP + 'metrics = [{ name = "m", of = "Tx", reduce = "max", per = ["Mz"] }]\n',
         "'Mz' is not recorded"),
        (SWEEP + 'plot = { metric = "none" }\n', "sweep.plot.metric"),
        (SWEEP + 'colour = 1\n', "unknown key(s) ['colour']"),
    ],
)  # fmt: skip
def test_malformed_sweep_is_refused_naming_the_key(tmp_path, extra, fragment):
    path = tmp_path / "s.toml"
    path.write_text((SCENARIOS / "fig13.toml").read_text() + extra)
    with pytest.raises(ScenarioError) as e:
        load(path)
    assert str(path) in str(e.value) and fragment in str(e.value)


def test_variation_holds_for_every_case_and_keeps_the_fmu():
    scene = load(SCENARIOS / "fig13.toml")
    v = variation.apply(scene, {"Iy": 5e-4, "My_ex.sine.amplitude": 3.0, "Fx_ex": 100.0})
    assert v.config == scene.config  # the same FMU: values are start values and inputs
    t = np.array([0.25 * PERIOD])
    for c in v.cases:
        assert c.parameters["Iy"] == 5e-4
        assert c.inputs["My_ex"](t)[0] == pytest.approx(3.0, rel=1e-15)
        assert c.inputs["Fx_ex"](t)[0] == 100.0
    assert [c.name for c in v.cases] == [c.name for c in scene.cases]


def test_metric_reductions():
    t = np.linspace(0.0, 1.0, 101)
    tau = 0.1
    cols = {"time": t, "y": np.exp(-t / tau), "P": np.full(t.size, 2.0)}
    # settle time: exp(-t/tau) - exp(-1/tau) <= tol from t* = -tau ln(tol + exp(-1/tau))
    tol = 1e-2
    t_star = -tau * math.log(tol + math.exp(-1 / tau))
    got = metrics.value(Metric("s", "y", "settle_time", tol=tol), cols, {})
    assert t_star <= got < t_star + 0.01  # the first grid time at or after t*
    m = Metric("m", "y", "max_abs", per=("mu", "P"), after=0.5)
    assert metrics.value(m, cols, {"mu": 0.5}) == pytest.approx(math.exp(-5.0), rel=1e-12)
    assert metrics.value(Metric("a", "y", "any_below", threshold=0.01), cols, {}) == 1.0
    assert metrics.value(Metric("a", "y", "any_above", threshold=1.5), cols, {}) == 0.0
    assert metrics.value(Metric("f", "y", "final"), cols, {}) == math.exp(-10.0)
    assert math.isnan(metrics.value(Metric("f", "y", "final", after=2.0), cols, {}))


# ---- command line ---------------------------------------------------------------------------
def test_cli_sweep_writes_rows_trajectories_and_a_plot(tmp_path, capsys):
    out = tmp_path / "study"
    code = cli.main(["sweep", str(_short_scene(tmp_path)), "--vary", "mu=0.2,0.3", "--vary",
                     "Fx_ex=0:190:2", "--workers", "0", "--out", str(out), "--trajectories",
                     "--no-progress"])  # fmt: skip
    assert code == 0, capsys.readouterr()
    rows = pq.read_table(out / "results.parquet").to_pylist()
    assert len(rows) == 2 * 2 * 3 and {r["status"] for r in rows} == {"ok"}
    assert list(rows[0])[:6] == ["run", "mu", "Fx_ex", "case", "status", "Tx_final"]
    traj = pq.read_table(out / "trajectories.parquet")
    assert traj.num_rows == 12 * 21 and "Tx" in traj.column_names
    assert (out / "Tx_final.png").stat().st_size > 0


def test_cli_sweep_refuses_bad_arguments_naming_them(tmp_path, capsys):
    scene = str(_short_scene(tmp_path))
    with pytest.raises(SystemExit):
        cli.main(["sweep", scene, "--vary", "mu=0.1:0.5"])
    assert "--vary mu" in capsys.readouterr().err
    with pytest.raises(SystemExit, match="sweep.vary.nope"):
        cli.main(["sweep", scene, "--vary", "nope=1,2", "--workers", "0"])
    with pytest.raises(SystemExit, match="nothing varied"):
        cli.main(["sweep", scene, "--workers", "0"])
