"""The native FMUs (FMI 2.0 and 3.0) with a held spin ratio and vx the only stage unknown
(spin = "ratio" without vy = "eq10": Omega_z = spin_ratio Vx, Vy = vy_ratio Vx) against
the pythonfmu FMU.

The pythonfmu FMU solves these stages in Python (integrator.RollingBody's scalar path,
the stage slope by a forward difference: the laws' analytic slopes have no spin); the
native FMU runs the same operations in C (stepper.c's advance_held on cf_advance) and the
law with spin through the same compiled strip march (cf_layer_forces), so every output is
the pythonfmu FMU's double except the adhesion, whose area sum over the spin grid runs
in another order than numpy's (1e-12).
"""

from __future__ import annotations

import dataclasses
import itertools
import math
import shutil
from pathlib import Path

import native_c
import numpy as np
import pytest
from fmpy.fmi1 import FMICallException
from fmpy.validation import validate_fmu
from test_native_fmi3 import Instance3

import fmu_build
from contact_fmu.fmu.config import ModelConfig
from contact_fmu.laws.thin_layer import LayerContact
from contact_fmu.scenario import load, runner
from contact_fmu.scenario.instance import ERROR, OK, Instance
from fmu_build import native_fmu, native_fmu3

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "out" / "fmu"
pytestmark = pytest.mark.skipif(shutil.which("cc") is None, reason="no C compiler")

# fig13's contact (P = 1000 N): a spin ratio of half the onset of full slip per a1
# (phi a1/|Vx| = 0.5 creep_full_slip: the spin moves Tx by percent of mu P) and a lateral
# slip ratio of 0.3 of that onset
LAW = LayerContact(1000.0, 0.05, 0.10, 5e-13, 5e-13, 3.2e-13, 3.2e-13, 0.3)
RZ = 0.5 * LAW.creep_full_slip / LAW.a1
RY = 0.3 * LAW.creep_full_slip
MU_P = 0.3 * 1000.0


def _fig13(spin: bool):
    """fig13's first case (eta = 1.5), with the held ratios where ``spin``."""
    scene = load(ROOT / "scenarios" / "fig13.toml")
    scene = dataclasses.replace(scene, cases=scene.cases[:1])
    if not spin:
        return scene
    d = scene.config.to_dict()
    starts = d["starts"] | {"spin_ratio": RZ, "vy_ratio": RY}
    cfg = ModelConfig.from_dict(d | {"name": "fig13_held_spin", "spin": "ratio", "vy": "ratio",
                                     "starts": starts})  # fmt: skip
    return dataclasses.replace(scene, config=cfg)


def test_fig13_with_held_spin_gives_the_pythonfmu_doubles_on_both_native_fmus():
    """fig13 (eta = 1.5) with a held spin and lateral slip: both native FMUs validate and
    build; every recorded output of the FMI 2.0 native FMU is the pythonfmu FMU's double
    (adhesion: 1e-12), the FMI 3.0 FMU's are the FMI 2.0 one's; the spin matters: Tx
    differs from fig13's without it by more than 1e-3 mu P."""
    scene, plain = _fig13(True), _fig13(False)
    cfg = scene.config
    nat, nat3 = native_fmu.build(cfg, OUT).path, native_fmu3.build(cfg, OUT).path
    py = fmu_build.build(cfg, OUT).path
    assert validate_fmu(str(nat)) == [] and validate_fmu(str(nat3)) == []
    (got,), (got3,), (ref,) = (runner.simulate(p, scene) for p in (nat, nat3, py))
    assert got.error is None and got3.error is None and ref.error is None
    for k in ref.columns:
        assert np.array_equal(got3.columns[k], got.columns[k]), k
        if k == "adhesion":
            assert np.max(np.abs(got.columns[k] - ref.columns[k])) <= 1e-12
        else:
            assert np.array_equal(got.columns[k], ref.columns[k]), k
    (base,) = runner.simulate(native_fmu.build(plain.config, OUT).path, plain)
    assert np.max(np.abs(got.columns["Tx"] - base.columns["Tx"])) > 1e-3 * MU_P


@pytest.fixture(scope="module")
def held() -> dict[str, Path]:
    """The full body FMU with both ratios held (both methods and schemes), both targets."""
    d = ModelConfig.full("body").to_dict()
    cfg = ModelConfig.from_dict(
        d | {"name": "full_body_held", "vy": "ratio", "spin": "ratio",
             "inputs": ["P", "Fx_ex", "My_ex"], "starts": {"spin_ratio": RZ, "vy_ratio": RY}}
    )  # fmt: skip
    return {"native": native_fmu.build(cfg, OUT).path, "pythonfmu": fmu_build.build(cfg, OUT).path,
            "fmi3": native_fmu3.build(cfg, OUT).path}  # fmt: skip


def _drive(b, n: int = 16) -> list[list[float]]:
    """n steps of 2.5e-4 s: the load P swept by 20 %, Fx_ex from 0.3 to 4.8 mu P (the
    full body's A2 = 1/4: the demand A2 Fx_ex goes from 0.075 to 1.2 mu P, into gross
    sliding), My_ex swept."""
    rows = []
    for k in range(n):
        s = math.sin(k / 3)
        b.set("P", 1000.0 * (1.0 + 0.2 * s))
        b.set("Fx_ex", (0.3 + 4.5 * (k > n // 2)) * MU_P)
        b.set("My_ex", -0.01 * MU_P * s)
        assert b.step(2.5e-4) == OK, b.messages[-1:]
        rows.append(list(b.outputs().values()))
    return rows


def test_both_methods_and_schemes_with_held_spin_give_the_pythonfmu_doubles(held):
    """For each method and scheme, 16 steps under a swept load and loads into gross
    sliding: the native FMU's outputs are the pythonfmu FMU's doubles (adhesion: 1e-12),
    the FMI 3.0 FMU's the FMI 2.0 one's; both regimes are visited; Omega_z and Vy are
    the held ratios times Vx."""
    names = None
    for method, scheme in itertools.product(("full", "quasistationary"), ("lobatto3c", "sdirk2")):
        start = {"method": method, "scheme": scheme}
        runs = {}
        for target in ("native", "pythonfmu"):
            with Instance(held[target], target, start) as b:
                names = list(b.outputs())
                runs[target] = np.array(_drive(b))
        with Instance3(held["fmi3"], start=start) as b3:
            assert np.array_equal(np.array(_drive(b3)), runs["native"]), (method, scheme)
        got, ref = runs["native"], runs["pythonfmu"]
        for i, n in enumerate(names):
            if n == "adhesion":
                assert np.max(np.abs(got[:, i] - ref[:, i])) <= 1e-12, (method, scheme)
            else:
                assert np.array_equal(got[:, i], ref[:, i]), (method, scheme, n)
        regime = got[:, names.index("regime")]
        assert regime.min() == 0 and regime.max() == 1, (method, scheme)
        Vx = got[:, names.index("Vx")]  # the held ratios (BodyState._apply_ratios)
        assert np.array_equal(got[:, names.index("Omega_z")], RZ * Vx)
        assert np.array_equal(got[:, names.index("Vy")], RY * Vx)


def test_a_bad_spin_ratio_is_refused_in_the_same_words(held):
    """spin_ratio = inf: refused at setReal and the model does not start, by both targets
    with the same statuses and messages."""
    answers = []
    for target in ("pythonfmu", "native"):
        with Instance(held[target], "bad", initialise=False) as b:
            statuses = []
            for call in (lambda: b.set("spin_ratio", math.inf), b.initialise):
                try:
                    call()
                    statuses.append(OK)
                except FMICallException as e:
                    statuses.append(int(e.status))
            answers.append((statuses, b.messages))
    assert answers[0] == answers[1]
    assert answers[0][0] == [ERROR, ERROR]
    assert any("spin_ratio = inf is invalid" in m for _, m in answers[0][1]), answers


def test_sanitized_importer_runs_the_held_spin_fmu_through_random_extremes_cleanly(held, tmp_path):
    """The full body FMU with both ratios held (the scalar step with spin on the vector
    path's state and grid) under the sanitized importer's random calls (extreme and
    non-finite values of every input, states got, set, serialized and damaged): no
    sanitizer report, no fmi2Fatal, no non-finite output served with fmi2OK."""
    counts = native_c.sanitized_fuzz(held["native"], tmp_path, 600)
    assert counts["ok"] > 200 and counts["error"] + counts["discard"] > 20, counts


@pytest.mark.parametrize("target", ["native", "fmi3"])
def test_held_spin_sources_compile_strictly_exporting_only_fmi(held, tmp_path, target):
    """The held-spin FMU's sources compile warning-free under -Wall -Wextra -pedantic
    -Werror and export the FMI functions only (FMI 2.0: 34, FMI 3.0: 75)."""
    from test_native_table_loads import strict_build

    names = strict_build(held[target], tmp_path)
    prefix, count = ("fmi2", 34) if target == "native" else ("fmi3", 75)
    assert len(names) == count and all(n.startswith(prefix) for n in names), names


def test_rail_traction_with_held_spin_gives_the_pythonfmu_outputs():
    """rail_traction (the half-space table, case "full") with a held spin creepage of 0.5
    1/m (a third of the table's spin range): the native FMU's outputs are the pythonfmu
    FMU's within 1e-12 of each output's scale (the table with spin in C, its patch sums
    in another order than numpy's; measured: 5e-16), and the spin moves Tx by more than
    1 N against the scene without it."""
    scene = load(ROOT / "scenarios" / "rail_traction.toml")
    scene = dataclasses.replace(scene, cases=scene.cases[:1])
    d = scene.config.to_dict()
    cfg = ModelConfig.from_dict(d | {"name": "rail_traction_held_spin", "spin": "ratio",
                                     "starts": d["starts"] | {"spin_ratio": 0.5}})  # fmt: skip
    spun = dataclasses.replace(scene, config=cfg)
    paths = (native_fmu.build(cfg, OUT).path, fmu_build.build(cfg, OUT).path)
    (got,), (ref,) = (runner.simulate(p, spun) for p in paths)
    assert got.error is None and ref.error is None
    for k, r in ref.columns.items():
        assert np.max(np.abs(got.columns[k] - r)) <= 1e-12 * np.max(np.abs(r)), k
    (base,) = runner.simulate(native_fmu.build(scene.config, OUT).path, scene)
    assert np.max(np.abs(got.columns["Tx"] - base.columns["Tx"])) > 1.0
