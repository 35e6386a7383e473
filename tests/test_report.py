"""The work-precision report: its references against independent results, the sweep it
derives from scene data, the FMU runs in quick mode, the files and the command line."""

from __future__ import annotations

import csv
import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest

from contact_fmu import cli
from contact_fmu import examples as ex
from contact_fmu.dynamics.body import Loads
from contact_fmu.dynamics.integrator import RollingBody
from contact_fmu.dynamics.simulate import load_history, simulate
from contact_fmu.fmu.factory import make_body, thin_layer_law
from contact_fmu.report import output, reference, sweep
from contact_fmu.report.metrics import norms, observed_order, pairwise_orders
from contact_fmu.report.workprecision import run_scene
from contact_fmu.scenario import load
from contact_fmu.scenario.signals import parse

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "out" / "fmu"


def scene(name: str):
    return load(ROOT / "scenarios" / f"{name}.toml")


# ---- signals: the breakpoints the reference integrator restarts at ------------------------
def test_signal_breakpoints_are_the_jumps_and_kinks():
    s = parse("u", [1.0, {"step": {"time": 0.2, "height": 1.0}},
                    {"ramp": {"start": 0.5, "duration": 0.25, "height": 2.0}},
                    {"sine": {"amplitude": 1.0, "period": 1.0, "start": 0.1}},
                    {"table": {"time": [0.0, 0.3], "value": [0.0, 1.0]}}])  # fmt: skip
    assert s.breakpoints == (0.0, 0.1, 0.2, 0.3, 0.5, 0.75)
    assert parse("P", 1000.0).breakpoints == ()


# ---- references against independent results ------------------------------------------------
def test_radau_reference_is_coulomb_while_sliding():
    """Brake scene, 0.8-2.4 ms: gross sliding (the scene's own window). Coulomb's law gives
    Tx = mu P exactly (h(beta >= 2) = 1) and a constant slip acceleration
    dvx/dt = (A2 Fx - A1 My/Rx - mu P)/(M A2) = (450 - 300) N / (1/3 kg) = 450 m/s^2
    (Eq. 20); Radau at rtol 1e-11 reproduces the slope to 1e-9. Tx = mu P h is evaluated
    in floating point from the slip and the law's constants, so h = 1 holds to rounding
    (seen: 300 - 5.7e-14 N on one CPU, 1 ulp of 300): allowed 1e-13 relative, a few
    hundred ulp, far below any law error (h(beta < 2) < 1 - 1e-6 within 1e-3 of beta = 2)."""
    s = scene("brake")
    t = np.linspace(0.0, 2.4e-3, 121)
    sol = reference.full_continuous(s, s.cases[0], t)
    w = t >= 0.8e-3
    assert np.allclose(sol.Tx[w], 300.0, rtol=1e-13, atol=0.0)
    slope = np.diff(sol.vx[w]) / np.diff(t[w])
    assert np.allclose(slope, 450.0, rtol=1e-9, atol=0.0)


def test_radau_reference_agrees_with_the_refined_stepper():
    """Fig. 13 (eta = 3) over 2 ms, loads continuous: Radau (rtol 1e-11) against the core
    stepper (Lobatto IIIC, a different method) sampling the same load function at its
    stage times. Their difference must be explained by the stepper's own error: by
    Richardson (second order) the run at h/2 is off by about (1/3) max|y(h) - y(h/2)|;
    allowed twice that, plus 1e-9 of the scale for the reference's own error."""
    s = scene("fig13")
    case = s.case("eta = 3")
    T_end, h = 2e-3, 2.5e-6
    t = np.arange(0, int(round(T_end / h)) + 1) * h
    sol = reference.full_continuous(s, case, t)
    sig = case.inputs
    loads = load_history(
        Fx_ex=lambda tt: float(sig["Fx_ex"](np.array([tt]))[0]),
        My_ex=lambda tt: float(sig["My_ex"](np.array([tt]))[0]),
    )
    p = case.parameters
    body = make_body(p)
    runs = [
        simulate(thin_layer_law(p, 1000.0), body, loads, T_end, h, Vx0=p["Vx0"], substeps=k)
        for k in (1, 2)
    ]
    for var, scale in (("Tx", ex.mu * ex.P), ("vx", 0.0099 * p["Vx0"])):
        coarse, fine = getattr(runs[0], var), getattr(runs[1], var)
        estimate = np.max(np.abs(coarse - fine)) / 3.0
        diff = np.max(np.abs(fine - getattr(sol, var)))
        assert diff <= 2.0 * estimate + 1e-9 * scale, (var, diff, estimate)


def test_quasistationary_closed_form_is_what_the_stepper_solves():
    """Railway scene, quasistationary stepper with the inputs held over each step (Lobatto
    IIIC: trapezoidal rule for Vx, exact for held loads; Eq. 26 in each stage): the held
    closed form equals it to the stage-solve tolerance (1e-12 of mu P and of v_s)."""
    s = scene("railway")
    case = s.case("quasistationary")
    grid = s.grid[:101]
    ref = reference.quasistationary_held(s, case, grid)
    p = case.parameters
    rb = RollingBody(thin_layer_law(p, 1000.0), make_body(p), method="quasistationary",
                     Vx0=p["Vx0"], Omega_y0=p["Vx0"] / p["Rx"])  # vx0 = 0  # fmt: skip
    My = case.inputs["My_ex"](grid)
    v_s = rb.law.creep_full_slip * p["Vx0"]
    for k in range(1, grid.size):
        rb.advance(s.step, Loads(0.0, 0.0, float(My[k - 1]), 0.0), 4)
        assert rb.out.Tx == pytest.approx(ref.Tx[k], abs=1e-12 * 300.0)
        assert rb.vx == pytest.approx(ref.vx[k], abs=1e-12 * v_s)
        assert rb.Vx == pytest.approx(ref.Vx[k], rel=1e-14)


@pytest.mark.parametrize("creep", [0.0003, 0.003, 0.0098, 0.02])
@pytest.mark.parametrize("Vx", [5.0, -5.0])
def test_traction_quadrature_matches_the_closed_form(creep, Vx):
    """The contact-mode reference (nested quad of Eq. 36) against Eqs. (40)-(43),
    corrected: 1e-10 relative (quad at 1e-12 with the kinks as breakpoints)."""
    c = ex.contact()
    vx, vy = creep * abs(Vx) * 0.8, creep * abs(Vx) * 0.6
    Tq = reference.traction_resultant(c, vx, vy, Vx)
    Tc = c.force(vx, vy, Vx)
    assert Tq[0] == pytest.approx(float(Tc[0]), rel=1e-10)
    assert Tq[1] == pytest.approx(float(Tc[1]), rel=1e-10)


# ---- the sweep from scene data --------------------------------------------------------------
def test_sweep_follows_the_scene():
    """fig13: loads admissible, so both steppers x two schemes x internal steps; brake: loads
    beyond mu P, no quasistationary family (its closed form does not hold in sliding);
    the contact scene has no time integration: one family."""
    fams, cfg = sweep.families(scene("fig13"))
    assert len(fams) == 2 * 2 * len(sweep.SUBSTEPS)
    assert cfg.methods == ("full", "quasistationary") and cfg.schemes == ("lobatto3c", "sdirk2")
    brake, _ = sweep.families(scene("brake"))
    assert {f.value("method") for f in brake} == {"full"}
    why = reference.quasistationary_allowed(
        scene("brake"), scene("brake").cases[0], scene("brake").grid
    )
    assert why is not None and "beyond mu P" in why
    contact, ccfg = sweep.families(scene("sweep"), quick=True)
    assert [f.label for f in contact] == ["law evaluation"] and ccfg == scene("sweep").config


def test_scene_without_a_reference_is_listed_not_run(monkeypatch):
    """A setting without a reference (here the transient phase's, removed) is listed as
    not compared, without building or running its FMU."""
    from contact_fmu.report import workprecision

    refs = dict(workprecision.REFERENCES)
    del refs[("body", "transient", "full")]
    monkeypatch.setattr(workprecision, "REFERENCES", refs)
    rep = run_scene(scene("fig12_transient"), OUT, quick=True, repeats=1, log=lambda _m: None)
    assert rep.rows == [] and rep.fmu == ""
    assert any("phase 'transient'" in n for n in rep.notes)
    assert "Not compared: fig12_transient" in output.summary_markdown([rep])


def test_ladders_follow_the_scene():
    """The transient phase refines its field's grid (nx x 1/2, 1, 2, the scene's ny/nx) at
    the scene's step, with no stepper, scheme or substeps axis (its internal step follows
    cells_per_step); the half-space contact scene refines its table's nodes along xi and
    eta (spacing halved); every other scene the communication step. Quick mode drops the
    finest rung, and cuts the transient run to its first steps."""
    tr = scene("fig12_transient")
    fams, cfg = sweep.families(tr)
    assert [f.label for f in fams] == ["field grid"] and cfg == tr.config
    lad, rs = sweep.rungs(tr)
    assert lad.name == "grid" and [r.value for r in rs] == [(16, 8), (32, 16), (64, 32)]
    assert {r.h for r in rs} == {tr.step} and [r.spacing for r in rs] == [1 / 16, 1 / 32, 1 / 64]
    assert [r.value for r in sweep.rungs(tr, quick=True)[1]] == [(16, 8), (32, 16)]
    cut = sweep.for_report(tr, quick=True)
    assert cut.n_steps == sweep.QUICK_TRANSIENT_STEPS and sweep.for_report(tr, False) is tr
    rail = scene("rail_creep")
    lad, rs = sweep.rungs(rail)
    assert lad.name == "table" and lad.reading == "held"
    assert [r.value for r in rs] == [(13, 11, 3), (25, 21, 3), (49, 41, 3)]
    cfgs = [lad.configure(rail.config, r.value) for r in rs]
    assert [c.law_spec["nodes"] for c in cfgs] == [[13, 11, 3], [25, 21, 3], [49, 41, 3]]
    assert cfgs[1] == rail.config
    assert sweep.ladder(scene("fig13")) is sweep.STEP_LADDER


def test_transient_reference_steps_as_the_scene_reference():
    """The report's transient field (held loads) is stepped exactly as the scene's stored
    reference path (scenario.references.by_transient, checked against the FMU by the
    scene's tolerances): equal to rounding on the same grid, first 20 steps."""
    from contact_fmu.scenario.references import by_transient
    from contact_fmu.scenario.schema import Reference

    s = dataclasses.replace(scene("fig12_transient"), stop_time=20 * 2.0e-5)
    case = s.cases[1]
    opts = {"grid": [48, 12], "cells": case.parameters["cells_per_step"], "every": 1}
    theirs = by_transient(s, Reference(Path("-"), "transient", {"Tx": 1.0, "vx": 1.0}, (),
                                       opts), case)  # fmt: skip
    ours = reference._transient_run(s, case, s.grid, 48, 12, continuous=False)
    assert np.allclose(ours.Tx, theirs["Tx"], rtol=0.0, atol=1e-12 * 300.0)
    assert np.allclose(ours.vx, theirs["vx"], rtol=0.0, atol=1e-15)
    # constant loads: the continuous reading is the same
    cont = reference._transient_run(s, case, s.grid, 48, 12, continuous=True)
    assert np.allclose(cont.Tx, ours.Tx, rtol=0.0, atol=1e-12 * 300.0)


def test_halfspace_reference_is_the_direct_solve_saturated():
    """The half-space contact reference at three creepages of rail_creep (adhesion, near
    the onset of full slip, full slip): the direct solve of the scene's declaration, its
    force scaled radially onto the table's saturation s(m), which moves it (beyond
    rounding) only for m = |T|/(mu P) > 1 - 0.02 and then by at most (4/27) 0.02."""
    from contact_fmu.halfspace.table import saturate

    s = scene("rail_creep")
    case = s.cases[0]
    P, mu, Vx, Rx = 100.0e3, 0.3, 30.0, 0.46
    xi = np.array([0.001, 0.0045, 0.011])
    u = {"P": np.full(3, P), "Vx": np.full(3, Vx), "Vy": np.zeros(3), "Omega_z": np.zeros(3),
         "Omega_y": (Vx - xi * Vx) / Rx}  # fmt: skip
    sol = reference._contact(s, case, np.arange(3.0), u)
    c = s.config.table_spec.contact(P=P, mu=mu)
    for k in range(3):
        d = c.solve(xi[k])
        m = d.Tx / (mu * P)
        assert sol.Tx[k] == pytest.approx(float(saturate(np.array(m))) * mu * P, rel=1e-9)
        shift = sol.Tx[k] / (mu * P) - m
        assert -1e-12 <= shift <= 4.0 / 27.0 * 0.02 + 1e-12  # rounding of s(m)/m
        assert abs(shift) <= 1e-12 or m > 0.98
    assert sol.vx == pytest.approx(xi * Vx, rel=1e-12)


def test_orders_and_norms():
    h = np.array([4.0, 2.0, 1.0])
    e = 3.0 * h**2
    assert observed_order(h, e) == pytest.approx(2.0, abs=1e-12)
    assert np.allclose(pairwise_orders(h, e)[1:], 2.0) and math.isnan(pairwise_orders(h, e)[0])
    assert norms([3.0, -4.0, np.nan], 2.0) == (2.0, pytest.approx(math.sqrt(12.5) / 2.0))


# ---- through the FMU ---------------------------------------------------------------------------
@pytest.fixture(scope="module")
def fig12_quick():
    return run_scene(scene("fig12"), OUT, quick=True, repeats=1, log=lambda _m: None)


def test_quick_report_runs_every_point(fig12_quick):
    rep = fig12_quick
    assert len(rep.rows) == 2 * 2 * len(sweep.SUBSTEPS_QUICK) * len(sweep.LEVELS_QUICK)
    assert all(r.error is None and r.wall > 0 for r in rep.rows)
    assert all(math.isfinite(r.Tx_max) and math.isfinite(r.vx_max) for r in rep.rows)


def test_full_stepper_converges_at_second_order_in_fig12(fig12_quick):
    """Fig. 12's loads are constant (no zero-order-hold error): the error is the stepper's.
    With n = 4 the internal step (<= 1.5 us) is below the relaxation time (4.6-20 us),
    where both schemes are second order (docs/model.md: Lobatto IIIC's stiff reduction,
    to 1.35, needs h ~ 6 tau_r): observed order above 1.5. SDIRK2's error constant is a
    quarter of Lobatto IIIC's: its error is smaller at every step."""
    orders = fig12_quick.family_orders()
    for scheme in ("lobatto3c", "sdirk2"):
        pT, pv = orders[f"full {scheme} n=4"]
        assert pT > 1.5 and pv > 1.5, (scheme, pT, pv)
    lob = fig12_quick.of("full lobatto3c n=4")
    sd = fig12_quick.of("full sdirk2 n=4")
    assert all(b.Tx_max < a.Tx_max for a, b in zip(lob, sd, strict=True))


def test_quasistationary_stepper_is_exact_for_constant_loads(fig12_quick):
    """Constant Fx_ex: Eq. (26) fixes Tx = A2 Fx_ex, Vx grows linearly (the trapezoidal rule
    is exact), vx = Vx T_x^-1: the stepper is exact up to rounding and the stage solve
    (1e-12 of mu P, of v_s)."""
    for r in fig12_quick.rows:
        if r.settings["method"] == "quasistationary":
            assert r.Tx_max <= 1e-12 and r.vx_max <= 1e-12, r


def test_contact_mode_error_is_the_hold_only():
    """Contact mode: against the held kinematics the FMU's closed form agrees with the
    quadrature of the traction to 1e-11 of mu P; against the continuous sweep the error is
    the zero-order hold, first order in h (observed 0.9-1.1)."""
    rep = run_scene(scene("sweep"), OUT, quick=True, repeats=1, held=True, log=lambda _m: None)
    assert all(r.Tx_max_held <= 1e-11 for r in rep.rows)
    pT, _ = rep.family_orders()["law evaluation"]
    assert 0.9 < pT < 1.1


@pytest.fixture(scope="module")
def transient_quick():
    return run_scene(scene("fig12_transient"), OUT, quick=True, repeats=1, log=lambda _m: None)


def test_transient_error_falls_with_the_field_grid(transient_quick):
    """fig12_transient, quick (eta = 10.9, first 50 steps): the field on 16 x 8 and 32 x 16
    cells (internal step half a cell) against the extrapolated 64 x 32 / 128 x 64 field.
    The scheme is second order in the cell (docs/transient.md: 1.9-2.0 measured); at 16
    cells the body's oscillation on the layer (0.29 contact lengths, 4.6 cells) is barely
    resolved, so the first halving gains more (about 3 measured): the order is at least
    1.5 and below 4.5. The scene's own grid is within its stored tolerances (Tx 1.7 N =
    5.7e-3 mu P: three times the FMU's measured difference from a finer field)."""
    rows = transient_quick.of("field grid")
    assert [r.value for r in rows] == ["16 x 8", "32 x 16"]
    assert all(r.error is None and r.wall > 0 for r in rows)
    for var in ("Tx", "vx", "Ty"):
        e = [getattr(r, f"{var}_max") for r in rows]
        assert e[1] < e[0], (var, e)
    pT, pv = transient_quick.family_orders()["field grid"]
    assert 1.5 < pT < 4.5 and 1.5 < pv < 4.5, (pT, pv)
    assert rows[1].Tx_max <= 1.7 / 300.0


@pytest.fixture(scope="module")
def rail_quick():
    return run_scene(scene("rail_creep"), OUT, quick=True, repeats=1, log=lambda _m: None)


def test_creep_table_error_falls_with_its_nodes(rail_quick):
    """rail_creep, quick (100 kN): the FMU's creep-force table with 13 x 11 and 25 x 21
    nodes against direct solves (saturated as the table) at the kinematics the FMU
    holds. Hermite patches with Akima's nodal derivatives (second-order slopes) give
    third order where the creep force is smooth and second order across the onset of
    full slip, where its curvature jumps: the observed order is within 1.5 and 3.5. The
    scene's table is within its stored tolerance (Tx 125 N = 4.2e-3 mu P, twice the
    interpolation error measured by the half-space benchmark); vx is the held kinematics
    (no error), and without lateral creepage Ty is zero to the solver's rounding."""
    rows = rail_quick.of("creep-force table")
    assert [r.value for r in rows] == ["13x11x3", "25x21x3"]
    assert all(r.error is None and r.setup > 0 for r in rows)
    assert rows[1].Tx_max < rows[0].Tx_max
    pT, _ = rail_quick.family_orders()["creep-force table"]
    assert 1.5 < pT < 3.5, pT
    assert rows[1].Tx_max <= 125.0 / 30.0e3
    assert all(r.vx_max <= 1e-12 and r.Ty_max <= 1e-8 for r in rows)


def test_ladder_report_files(rail_quick, tmp_path):
    """A ladder's rows keep their setting, spacing and build time through the CSV, and
    the markdown names the refined setting."""
    back = output.read_csv(output.write_csv(rail_quick, tmp_path / "rail.csv"))
    assert [(r.value, r.spacing, r.setup, r.Tx_max) for r in back.rows] == [
        (r.value, r.spacing, r.setup, r.Tx_max) for r in rail_quick.rows
    ]
    assert back.refined == "table"
    text = output.scene_markdown(rail_quick)
    assert "| creep-force table | 25x21x3 |" in text and "table build (s)" in text
    assert "table 13x11x3 .. 25x21x3" in output.summary_markdown([rail_quick])
    assert output.plot(back, tmp_path / "rail.png").stat().st_size > 0


# ---- files and command line ---------------------------------------------------------------------
def test_report_command_writes_tables_and_plots(tmp_path, capsys):
    rc = cli.main(["report", "--quick", str(ROOT / "scenarios" / "fig12.toml"),
                   "--case", "eta=inf", "--repeats", "1", "--out", str(tmp_path)])  # fmt: skip
    assert rc == 0
    base = tmp_path / "workprecision" / "fig12"
    for suffix in (".csv", ".md", ".png"):
        assert base.with_suffix(suffix).stat().st_size > 0
    with base.with_suffix(".csv").open() as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == 16 and {r["method"] for r in rows} == {"full", "quasistationary"}
    assert "| eta=inf |" in (tmp_path / "stiff.md").read_text()
    assert "order Tx" in (tmp_path / "workprecision.md").read_text()
    assert "| eta=inf | eta |" in capsys.readouterr().out


def test_csv_round_trip_keeps_every_number(fig12_quick, tmp_path):
    """A report written to CSV and read back (to plot again) has the same rows, exactly
    (repr of floats)."""
    path = output.write_csv(fig12_quick, tmp_path / "fig12.csv")
    back = output.read_csv(path)
    assert [(r.family, r.h, r.Tx_max, r.vx_rms, r.wall) for r in back.rows] == [
        (r.family, r.h, r.Tx_max, r.vx_rms, r.wall) for r in fig12_quick.rows
    ]
    assert output.plot(back, tmp_path / "fig12.png").stat().st_size > 0


def test_report_refuses_bad_options_naming_them():
    with pytest.raises(SystemExit, match="--write-docs needs the full report"):
        cli.main(["report", "--quick", "--write-docs"])
    with pytest.raises(SystemExit, match="--repeats = 0 is invalid"):
        cli.main(["report", "--repeats", "0"])
    with pytest.raises(SystemExit, match="--case 'eta=7' is not a stiff case or group"):
        cli.main(["report", "--stiff", "--case", "eta=7"])


def test_accuracy_page_gets_both_parts_and_keeps_the_other(tmp_path):
    """docs/accuracy.md is created with its two sections; writing one part leaves the
    other's text and the page's own text alone."""
    from contact_fmu.report import command

    page = tmp_path / "accuracy.md"
    command.ensure_accuracy_page(page)
    assert page.read_text().startswith(command.ACCURACY_TITLE + "\n")
    output.replace_section(page, command.ACCURACY_STIFF, "stiff table")
    command.ensure_accuracy_page(page)  # idempotent
    output.replace_section(page, command.ACCURACY_WP, "wp table")
    text = page.read_text()
    assert text.count(command.ACCURACY_WP) == 1 and text.count(command.ACCURACY_STIFF) == 1
    assert text.index("wp table") < text.index(command.ACCURACY_STIFF) < text.index("stiff table")
    assert "Not run yet" not in text and "contact-fmu report --quick" in text
    # a page that lost a section gets it back, the rest kept
    page.write_text(command.ACCURACY_TITLE + "\n\nintro\n\n" + command.ACCURACY_WP + "\n\nwp\n")
    command.ensure_accuracy_page(page)
    text = page.read_text()
    assert "intro" in text and text.index("wp") < text.index(command.ACCURACY_STIFF)


def test_write_docs_targets_exist_with_their_sections():
    """The pages --write-docs rewrites hold the sections it replaces (so a rerun replaces
    them instead of appending)."""
    from contact_fmu.report import command

    accuracy = (command.ROOT / "docs" / "accuracy.md").read_text().split("\n")
    perf = (command.ROOT / "docs" / "performance.md").read_text().split("\n")
    assert command.ACCURACY_WP in accuracy and command.ACCURACY_STIFF in accuracy
    assert command.PERF_WP_SECTION in perf and command.PERF_STIFF_SECTION in perf


def test_replace_section_keeps_the_rest(tmp_path):
    doc = tmp_path / "doc.md"
    doc.write_text("# T\n\n## A\n\nold\n```\n## not a heading\n```\n### sub\nx\n\n## B\n\nkeep\n")
    output.replace_section(doc, "## A", "new")
    assert doc.read_text() == "# T\n\n## A\n\nnew\n\n## B\n\nkeep\n"
    output.replace_section(doc, "## C", "added")
    assert doc.read_text().endswith("## B\n\nkeep\n\n## C\n\nadded\n")
