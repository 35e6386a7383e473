"""The native FMUs (FMI 2.0 and 3.0) of the body on the transient traction field with Vy
(Eq. 10) and/or Omega_z (Eq. 11) as stage unknowns besides vx, against the pythonfmu FMU.

Both run the field's stage in C (field.c's cf_field_stage with its Jacobian); the
pythonfmu FMU solves the stages in Python (TransientRollingBody._solve_vector: Newton's
method with that Jacobian, a backtracking line search on |r|, numpy's LAPACK solve),
the native FMU the same iteration in C (field.c's solve_vector: Gaussian elimination),
so the two agree to rounding and the stage tolerance (solvers.SOLVE_RTOL = 1e-13 of the
unknowns' scale): 1e-12 of each output's scale over a scene.
"""

from __future__ import annotations

import dataclasses
import shutil
from pathlib import Path

import native_c
import numpy as np
import pytest
from fmpy.validation import validate_fmu

import fmu_build
from contact_fmu.dynamics.thin_layer_field import MAX_STAGE_ITERATIONS
from contact_fmu.fmu import variables as fv
from contact_fmu.fmu.config import ModelConfig
from contact_fmu.scenario import load, runner
from fmu_build import native_fmu, native_fmu3

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "out" / "fmu"
pytestmark = pytest.mark.skipif(shutil.which("cc") is None, reason="no C compiler")

# the unknowns besides vx: Vy (Eq. 10), Omega_z (Eq. 11; Iz = 2e-4 kg m^2), both
VARIANTS = {"eq10": ("eq10", "zero"), "eq11": ("zero", "eq11"), "both": ("eq10", "eq11")}


def _scene(variant: str):
    """fig12_transient's case eta = 2.92 with ``variant``'s unknowns, started with Vy0 =
    0.01 m/s and Omega_z0 = 1 rad/s where they are unknowns (the lateral slip and spin
    then relax on the field while the field forms), Mz and the unknowns recorded too."""
    scene = load(ROOT / "scenarios" / "fig12_transient.toml")
    vy, spin = VARIANTS[variant]
    case = scene.cases[1]
    case = dataclasses.replace(
        case, parameters={k: v for k, v in case.parameters.items() if k != "vy_ratio"}
    )
    d = scene.config.to_dict()
    starts = {k: v for k, v in d["starts"].items() if k != "vy_ratio"}
    if vy == "eq10":
        starts["Vy0"] = 0.01
    if spin == "eq11":
        starts |= {"Iz": 2e-4, "Omega_z0": 1.0}
    cfg = ModelConfig.from_dict(
        d | {"name": f"fig12_transient_{variant}", "vy": vy, "spin": spin, "starts": starts,
             "outputs": [*d["outputs"], "Mz", *(["Vy"] if vy == "eq10" else []),
                                 *(["Omega_z"] if spin == "eq11" else [])]}
    )  # fmt: skip
    return dataclasses.replace(scene, config=cfg, cases=[case])


@pytest.fixture(scope="module")
def fmus():
    built = {}

    def get(variant: str) -> tuple:
        if variant not in built:
            scene = _scene(variant)
            cfg = scene.config
            built[variant] = (scene, {"native": native_fmu.build(cfg, OUT).path,
                                      "fmi3": native_fmu3.build(cfg, OUT).path,
                                      "pythonfmu": fmu_build.build(cfg, OUT).path})  # fmt: skip
        return built[variant]

    return get


@pytest.mark.parametrize("variant", list(VARIANTS))
def test_eqs_10_11_on_the_field_give_the_pythonfmu_outputs(fmus, variant):
    """The scene through each target: the native FMUs validate; every recorded output of
    the FMI 2.0 native FMU is the pythonfmu FMU's within 1e-12 of its scale over the run
    (measured: 1e-14), the FMI 3.0 FMU's the FMI 2.0 one's doubles; the unknowns move
    (Vy and Omega_z leave their starts by more than 1 %), the held ones stay 0."""
    scene, paths = fmus(variant)
    assert validate_fmu(str(paths["native"])) == [] and validate_fmu(str(paths["fmi3"])) == []
    (got,), (got3,), (ref,) = (runner.simulate(paths[t], scene)
                               for t in ("native", "fmi3", "pythonfmu"))  # fmt: skip
    assert got.error is None and got3.error is None and ref.error is None
    for k, r in ref.columns.items():
        assert np.array_equal(got3.columns[k], got.columns[k]), k
        assert np.max(np.abs(got.columns[k] - r)) <= 1e-12 * np.max(np.abs(r)), k
    vy, spin = VARIANTS[variant]
    for name, kind, start in (("Vy", vy, 0.01), ("Omega_z", spin, 1.0)):
        x = ref.columns.get(name, np.zeros(1))  # an output where it moves
        if kind == "zero":
            assert not np.any(x), name
        else:
            assert np.max(np.abs(x - start)) > 0.01 * start, name


def test_the_stage_evaluations_count_against_the_budget():
    """field.c's advance with Vy and Omega_z as unknowns: a budget of evaluations it does
    not reach changes nothing (the same doubles as without one); a budget of 2 stops the
    first stage (its first Newton step needs a second evaluation), and the call declines
    (None: the Python path then takes the step and words it)."""
    from contact_fmu.dynamics.thin_layer_field import A21, GAMMA
    from contact_fmu.fmu import body_transient
    from contact_fmu.native import library

    if library() is None:
        pytest.skip("no kernel library")
    scene = _scene("both")
    cfg = scene.config
    case = scene.cases[0]
    params = {v.name: cfg.start(v) for v in cfg.variables} | case.parameters
    stepper = body_transient.make_stepper(cfg, params, params["P"], 0.0)
    compiled = stepper.field._compiled()
    assert compiled is not None
    b, law, f = stepper.body, stepper.law, stepper.field
    body = {"M": b.M, "Rx": b.Rx, "A1": b.A1, "A2": b.A2, "m_slip": b.m_slip, "ry": 0.0,
            "rz": 0.0, "creep_full_slip": law.creep_full_slip, "gamma": GAMMA, "a21": A21,
            "solve_rtol": 1e-13, "v_scale_floor": 1e-3, "max_iterations": MAX_STAGE_ITERATIONS,
            "dyn_vy": 1, "dyn_spin": 1, "Iz": b.Iz, "a1": law.a1}  # fmt: skip

    def advance(limit: int):
        return compiled.advance(body | {"eval_limit": limit}, stepper.y, stepper.t,
                                stepper.impulse, (f.theta, f.tau_x, f.tau_y, f.slip), 2e-5,
                                (3 * 190.98593171027443, 0.0, 0.0, 0.0), 2)  # fmt: skip

    free, budgeted = advance(0), advance(1000)
    assert free is not None and budgeted is not None
    assert np.array_equal(free[0], budgeted[0]) and free[4] == budgeted[4]
    assert np.any(free[0][2:] != stepper.y[2:])  # the lateral unknowns moved
    assert advance(2) is None


def test_sanitized_importer_runs_the_lateral_field_through_random_extremes_cleanly(fmus, tmp_path):
    """The FMU with both unknowns (field.c's vector stage solve, its Newton matrix and
    line search, the evaluations counted) under the sanitized importer's random calls
    (extreme and non-finite values of every input, states got, set, serialized and
    damaged): no sanitizer report, no fmi2Fatal, no non-finite output served with
    fmi2OK."""

    _, paths = fmus("both")
    counts = native_c.sanitized_fuzz(paths["native"], tmp_path, 400)
    assert counts["ok"] > 100 and counts["error"] + counts["discard"] > 10, counts


@pytest.mark.parametrize("target", ["native", "fmi3"])
def test_lateral_field_sources_compile_strictly_exporting_only_fmi(fmus, tmp_path, target):
    """The sources of the FMU with both unknowns compile warning-free under -Wall -Wextra
    -pedantic -Werror and export the FMI functions only (FMI 2.0: 34, FMI 3.0: 75)."""
    from test_native_table_loads import strict_build

    _, paths = fmus("both")
    names = strict_build(paths[target], tmp_path)
    prefix, count = ("fmi2", 34) if target == "native" else ("fmi3", 75)
    assert len(names) == count and all(n.startswith(prefix) for n in names), names


def test_a_step_beyond_the_evaluation_budget_is_discarded_in_the_same_words(tmp_path):
    """max_work = 1024 on the 32 x 16 field (one internal step: cap 1; 16 evaluations of
    the field) and loads that drive Vy and Omega_z hard (Mz_ex = 1e7 N m, Fy_ex = -3.3e6
    N) over h = 10 ms: the stage solves need more evaluations than the budget, and both
    targets discard the step with the state unchanged, in the same words (WorkBudgetError
    naming the limit, max_work and the cost of one evaluation); the FMI 3.0 FMU too."""
    from test_native_fmi3 import Instance3, in_fmi3_words

    from contact_fmu.scenario.instance import DISCARD, Instance

    scene = _scene("both")
    d = scene.config.to_dict()
    inputs = ["P", "Fx_ex", "Fy_ex", "My_ex", "Mz_ex"]
    cfg = ModelConfig.from_dict(d | {"name": "fig12_transient_loaded", "inputs": inputs})
    paths = {"pythonfmu": fmu_build.build(cfg, OUT).path,
             "native": native_fmu.build(cfg, OUT).path,
             "fmi3": native_fmu3.build(cfg, OUT).path}  # fmt: skip
    answers = {}
    for target, path in paths.items():
        make = Instance3 if target == "fmi3" else Instance
        with make(path, "budget", {"max_work": 1024.0}) as b:
            b.set("Fx_ex", 1e4)
            b.set("Fy_ex", -1e7 / 3)
            b.set("Mz_ex", 1e7)
            start = len(b.messages)
            statuses = [b.step(1e-2), b.step(1e-2)]
            answers[target] = (statuses, b.messages[start:], b.get("Vx"))
    assert answers["native"] == answers["pythonfmu"]
    statuses, words, Vx = answers["pythonfmu"]
    assert answers["fmi3"] == (statuses, in_fmi3_words(words), Vx)
    assert statuses == [DISCARD, DISCARD] and Vx == scene.config.start(fv.BY_NAME["Vx0"])
    text = ("WorkBudgetError: the stage solves need more than 16 evaluations of the law, "
            "beyond max_work = 1024 (each costs 64)")  # fmt: skip
    assert all(text in m for _, m in words), words
