"""The stiff and extreme cases (contact_fmu.report.stiff_cases) through the body-mode FMU,
and the checks themselves on synthetic records (each one can fail).

The case list is the one `contact-fmu report --stiff` tabulates; tolerances are the
constants of contact_fmu.report.stiff, each derived there.
"""

from __future__ import annotations

import math
import shutil
from pathlib import Path

import numpy as np
import pytest

from contact_fmu.report import stiff
from contact_fmu.report.metrics import oscillation
from contact_fmu.report.stiff_cases import StiffCase, cases, params

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "out" / "fmu"


@pytest.fixture(scope="module")
def fmu_dir():
    d = stiff.prepare(OUT)
    yield d
    shutil.rmtree(d, ignore_errors=True)


@pytest.mark.parametrize("case", cases(), ids=lambda c: c.name)
def test_stiff_and_extreme_case(case: StiffCase, fmu_dir: Path):
    """Finite, |Tx| <= mu P, T.v >= 0, no step-to-step oscillation, convergence at h/2 and
    h/4, no memory growth (stiff.Check, tolerances in contact_fmu.report.stiff)."""
    result = stiff.run_case(case, fmu_dir)
    problems = [
        f"{c.name}: {c.value!r} (limit {c.limit!r}) {c.note}" for c in result.checks if not c.ok
    ]
    assert not problems, f"{case.name} ({case.what}): " + "; ".join(problems)
    names = [c.name for c in result.checks]
    assert names == [n for n in stiff.CHECK_NAMES if case.memory or n != "memory"]


def test_case_list_covers_the_issue():
    """eta 1 .. inf, epsilon 1e-1 .. 1e-5, loads to 0.999 and beyond, mu 1e-3 .. 1, Vx
    through zero, kb + ks -> 0 and large, h from 1e-7 s to 10 s, a run of 1e6 steps."""
    cs = cases()
    eta = [c.params["M"] * c.params["Rx"] ** 2 / c.params["Iy"] if c.params["Iy"] else math.inf
           for c in cs if c.group == "eta"]  # fmt: skip
    assert eta[-1] == math.inf and np.allclose(eta[:-1], [1.0, 2.5, 10.0, 1e3], rtol=1e-12)
    # epsilon = a1/Rx itself: test_epsilon_is_set_through_the_layers
    assert [c.name for c in cs if c.group == "epsilon"] == [
        f"epsilon={e:g}" for e in (1e-1, 1e-2, 1e-3, 1e-4, 1e-5)
    ]
    loads = [c.name for c in cs if c.group == "load"]
    assert {"load=0.999", "load=1.5 full"} <= set(loads)
    assert {c.params["kb"] / 3.2e-13 for c in cs if c.group == "layer"} >= {1e-9, 30.0}
    assert {c.h for c in cs if c.group == "step"} == {1e-7, 1e-5, 1e-3, 1e-1, 10.0}
    assert {c.params["mu"] for c in cs if c.group == "mu"} == {1e-3, 1e-2, 1e-1, 1.0}
    long = [c for c in cs if "long" in c.tags and not c.lateral]
    assert long and long[0].steps == 1_000_000 and long[0].substeps == 1
    assert len({c.name for c in cs}) == len(cs)
    # the lateral degrees of freedom: both methods, beyond the capacity, Vx through
    # zero, eta = inf, a small epsilon, a long step, memory on a long run of its own
    lat = [c for c in cs if c.lateral]
    assert {c.method for c in lat} == {"full", "quasistationary"}
    names = {c.name for c in lat}
    assert {"lateral 1.2 quasistationary", "lateral reversal full", "lateral eta=inf",
            "lateral epsilon=0.001", "lateral h=0.1"} <= names  # fmt: skip
    assert [c.name for c in lat if c.memory] == ["lateral long run"]


@pytest.mark.parametrize("eps", [1e-1, 1e-3, 1e-5])
def test_epsilon_is_set_through_the_layers(eps):
    """a1/Rx = epsilon (Eq. 34) and the full-slip creepage 0.64 mu epsilon, to rounding."""
    from contact_fmu.laws.thin_layer import LayerContact

    p = params(epsilon=eps)
    c = LayerContact(1000.0, p["Rx"], p["Ry"], p["k1"], p["k2"], p["kb"], p["ks"], p["mu"])
    assert c.a1 / p["Rx"] == pytest.approx(eps, rel=1e-12)
    assert c.creep_full_slip == pytest.approx(0.64 * p["mu"] * eps, rel=1e-12)


# ---- the checks on synthetic records -------------------------------------------------
def _case(**kw) -> StiffCase:
    base = dict(name="synthetic", group="test", what="", params=params(),
                inputs={"P": 1000.0, "Fx_ex": 0.0, "My_ex": 0.0}, h=1e-3, steps=64)  # fmt: skip
    base.update(kw)
    return StiffCase(**base)


def _runs(Tx, vx, Vx=5.0, blocks=(1000, 1000), order=1.0, status=None, lateral=None
          ) -> list[stiff.Run]:  # fmt: skip
    """A run at h and its refinements: differences to the limit fall as h^order.
    ``lateral``: the records of Ty, vy, Mz, Omega_z at h (refined as Tx, vx are)."""
    n = len(Tx)
    out = []
    for i in range(3):
        m = n * 2**i
        t = np.arange(1, m + 1) * (1e-3 / 2**i)
        # values on the fine grid: the coarse record plus a perturbation that changes
        # sign and shrinks by 2^order from run to run (differences fall at that order)
        err = 1e-3 * (-1.0) ** i * 2.0 ** (-order * i)
        vals = {
            "Tx": np.repeat(np.asarray(Tx, float), 2**i) + 300.0 * err,
            "vx": np.repeat(np.asarray(vx, float), 2**i) + 0.05 * err,
            "Vx": np.full(m, Vx),
            "regime": np.zeros(m),
        }
        for name, y in (lateral or {}).items():
            vals[name] = np.repeat(np.asarray(y, float), 2**i) + (
                300.0 if name in ("Ty", "Mz") else 0.05) * err  # fmt: skip
        out.append(stiff.Run(t, vals, status=status, blocks=blocks))
    return out


def _checks(runs, case=None) -> dict[str, stiff.Check]:
    res = stiff.evaluate(case or _case(), runs, runs[2])
    return {c.name: c for c in res.checks}


SMOOTH_T = 100.0 + 50.0 * np.sin(np.linspace(0, 3, 64))
SMOOTH_V = 1e-3 + 5e-4 * np.sin(np.linspace(0, 3, 64))


def test_checks_pass_a_smooth_converging_record():
    c = _checks(_runs(SMOOTH_T, SMOOTH_V))
    assert all(k.ok for k in c.values()), c


def test_failed_step_fails_finite():
    c = _checks(_runs(SMOOTH_T, SMOOTH_V, status="doStep 3: status 2"))
    assert not c["finite"].ok and "status 2" in c["finite"].note


def test_force_beyond_capacity_fails_bound():
    Tx = SMOOTH_T.copy()
    Tx[10] = 300.0 * (1 + 1e-12) - 0.3  # mu P = 300 N: 1e-12 beyond is not rounding
    c = _checks(_runs(Tx, SMOOTH_V))  # (_runs adds 1e-3 mu P = 0.3 N to the coarse run)
    assert not c["bound"].ok


def test_negative_friction_power_fails_dissipation():
    vx = SMOOTH_V.copy()
    vx[20] = -1e-4  # slip against the force
    assert not _checks(_runs(SMOOTH_T, vx))["dissipation"].ok


def test_ringing_fails_oscillation():
    """An alternating remnant of 1 N on a ramp of 0.1 N per step (trapezoidal rule on a
    stiff mode: R(z) -> -1)."""
    Tx = 100.0 + 0.1 * np.arange(64) + 1.0 * (-1.0) ** np.arange(64)
    assert not _checks(_runs(Tx, SMOOTH_V))["oscillation"].ok


def test_no_convergence_fails_convergence():
    c = _checks(_runs(SMOOTH_T, SMOOTH_V, order=0.0))
    assert not c["convergence"].ok and c["convergence"].value == pytest.approx(0.0, abs=1e-12)


def test_block_growth_fails_memory():
    c = _checks(_runs(SMOOTH_T, SMOOTH_V, blocks=(1000, 1000 + stiff.MEM_BLOCKS + 1)))
    assert not c["memory"].ok


@pytest.mark.parametrize("steps", [64, 100, 200])
def test_memory_limit_lies_between_the_free_lists_fill_and_a_leak_of_one_object_per_step(
    steps,
):
    """Over the measured window (the second half of the run at h/4: 2 steps for each of
    the case's steps) a leak of one object per step adds one block per step and fails;
    the free lists' fill measured on the eta cases, up to 201 blocks over 400 steps,
    passes where the window is that long (a 128-step window cannot tell it from a leak:
    its limit is below the window's steps)."""
    T = 100.0 + 50.0 * np.sin(np.linspace(0, 3, steps))
    v = 1e-3 + 5e-4 * np.sin(np.linspace(0, 3, steps))
    window = 2 * steps
    leak = _checks(_runs(T, v, blocks=(1000, 1000 + window)))["memory"]
    assert not leak.ok and leak.limit < window
    if window >= 400:
        assert _checks(_runs(T, v, blocks=(1000, 1201)))["memory"].ok


# ---- the lateral cases' checks (Vy, Omega_z integrated; the law with spin) ----------
LATERAL = dict(
    group="lateral",
    params={**params(eta=2.0), "Iz": 1e-3},
    lateral=True,
    inputs={"P": 1000.0, "Fx_ex": 0.0, "My_ex": 0.0, "Fy_ex": 90.0, "Mz_ex": 0.0},
)
SMOOTH_VY = 2e-4 + 1e-4 * np.sin(np.linspace(0, 3, 64))
SPIN = 0.02 + 0.01 * np.cos(np.linspace(0, 3, 64))  # rad/s: the law marches its grid


def _lateral(Ty=SMOOTH_T, vy=SMOOTH_VY, Mz=None, Oz=SPIN) -> dict[str, np.ndarray]:
    return {"Ty": Ty, "vy": vy, "Mz": np.zeros(64) if Mz is None else Mz, "Omega_z": Oz}


def test_lateral_checks_pass_a_smooth_record_and_fail_a_ringing_one():
    """The lateral record passes as the straight one does; a zig-zag of Ty of 0.01 mu P
    (far above the spin law's roughness along these states, 1e-5 mu P at most in the
    suite's runs) fails, and so does one of the spin rate, a state (floor NOISE)."""
    case = _case(**LATERAL)
    c = _checks(_runs(SMOOTH_T, SMOOTH_V, lateral=_lateral()), case)
    assert all(k.ok for k in c.values()), c
    ring = SMOOTH_T + 3.0 * (-1.0) ** np.arange(64)
    c = _checks(_runs(SMOOTH_T, SMOOTH_V, lateral=_lateral(Ty=ring)), case)
    assert not c["oscillation"].ok and c["oscillation"].note.startswith("Ty")
    spin = SPIN + 1e-4 * (-1.0) ** np.arange(64)
    c = _checks(_runs(SMOOTH_T, SMOOTH_V, lateral=_lateral(Oz=spin)), case)
    assert not c["oscillation"].ok and c["oscillation"].note.startswith("Omega_z")


def test_lateral_bound_is_on_the_resultant_and_dissipation_includes_the_spin():
    """|T| = hypot(Tx, Ty) <= mu P (each component below it is not enough); the power
    on the rigid slip of Eq. (3), Tx vx + Ty vy + Mz Omega_z, with a spin moment
    against the spin: negative, fails."""
    case = _case(**LATERAL)
    Ty = np.full(64, 250.0)  # with Tx up to 150 N: |T| = 291.5 N < 300 N
    assert _checks(_runs(SMOOTH_T, SMOOTH_V, lateral=_lateral(Ty=Ty)), case)["bound"].ok
    Ty = np.full(64, 280.0)  # |T| up to 316 N > mu P
    assert not _checks(_runs(SMOOTH_T, SMOOTH_V, lateral=_lateral(Ty=Ty)), case)["bound"].ok
    Mz = np.full(64, -1e3)  # N m, against Omega_z > 0
    c = _checks(_runs(SMOOTH_T, SMOOTH_V, lateral=_lateral(Mz=Mz)), case)
    assert not c["dissipation"].ok


def test_spin_grid_roughness_vanishes_without_spin():
    """Without spin the law is the closed form (no grid): no roughness, exactly; with
    it, a positive one far below a node's share of mu P (mu P / 3072 = 3e-4 mu P)."""
    case = _case(**LATERAL)
    vals = {"vx": SMOOTH_V, "vy": SMOOTH_VY, "Omega_z": np.zeros(64), "Vx": np.full(64, 5.0)}
    assert not np.any(stiff.spin_grid_roughness(case, vals))
    r = stiff.spin_grid_roughness(case, {**vals, "Omega_z": SPIN})
    assert r.shape == (2, 63) and 0.0 < r.max() < 3e-4 * case.mu_P


def test_oscillation_measure():
    """Monotone relaxation after a jump and a sampled sine: no excess; a remnant that
    alternates with ratio -0.5 after a jump: excess (SDIRK2's worst, -0.21, is below its
    own variation); noise below the floor: none."""
    n = np.arange(40)
    jump = np.r_[np.zeros(5), 1.0 - 0.6 ** np.arange(1, 36)]
    assert oscillation(jump, 1e-12)[0] <= 0.0
    assert oscillation(np.sin(0.3 * n), 1e-12)[0] <= 0.0
    assert oscillation(np.r_[np.zeros(5), 1.0 + (-0.5) ** np.arange(1, 36)], 1e-12)[0] > 0.0
    assert oscillation(np.r_[np.zeros(5), 1.0 + (-0.21) ** np.arange(1, 36)], 1e-12)[0] <= 0.0
    noise = 1e-13 * (-1.0) ** n
    assert oscillation(noise, 1e-12)[0] <= 0.0
    assert oscillation(noise, 1e-14)[0] > 0.0
