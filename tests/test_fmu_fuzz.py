"""Randomised hostile-input runs of every kind of FMU we build ("Must show").

hypothesis draws runs of FMI calls (``fmu_fuzz.strategies``); each run goes to a
persistent worker subprocess per FMU (``fmu_fuzz.pool``), so that a crash is counted
and the worker replaced; the call records are checked against the target behaviour
(``fmu_fuzz.invariants``, whose docstring lists the rules and their tolerances).

Every session first replays the runs that once broke the contract (``fmu_fuzz.known``,
hypothesis explicit examples). Default suite: a short fixed-seed run (derandomized,
CONTACT_FMU_FUZZ_SHORT examples per kind, 15 unless set); the first violation fails the
kind's test with the run as its reproducer (no shrinking: set CONTACT_FMU_FUZZ_SHRINK=1
for a minimal one, or use ``python -m fmu_fuzz.shrink``). Long run (`make fuzz`):
CONTACT_FMU_FUZZ_EXAMPLES runs per kind, every violation counted instead of raised
(CONTACT_FMU_FUZZ_SECONDS: a time budget per kind); the summary (runs, calls, statuses
per call, crashes, failure classes with the shortest run showing each) goes to
out/fuzz/long/summary.md and .json, and the last test fails if anything was found.
CONTACT_FMU_FUZZ_COLLECT=1 counts instead of raising in the short run too.
"""

from __future__ import annotations

import json
import os
import time

import pytest
from fmu_fuzz import invariants, strategies
from fmu_fuzz.kinds import KINDS, ROOT
from fmu_fuzz.known import KNOWN
from fmu_fuzz.pool import Pool
from fmu_fuzz.summary import Stats
from hypothesis import HealthCheck, Phase, example, given, settings

LONG = int(os.environ.get("CONTACT_FMU_FUZZ_EXAMPLES", "0"))
BUDGET = float(os.environ.get("CONTACT_FMU_FUZZ_SECONDS", "inf"))
SHRINK = os.environ.get("CONTACT_FMU_FUZZ_SHRINK") == "1"
# count instead of raising (the long run always; the short one when measuring it)
COLLECT = bool(LONG) or os.environ.get("CONTACT_FMU_FUZZ_COLLECT") == "1"
OUT = ROOT / "out" / "fuzz"
_HEALTH = [HealthCheck.too_slow, HealthCheck.data_too_large, HealthCheck.filter_too_much]
settings.register_profile(
    "fmu-fuzz-short",
    max_examples=int(os.environ.get("CONTACT_FMU_FUZZ_SHORT", "15")),
    derandomize=True,
    deadline=None,
    database=None,
    phases=[Phase.explicit, Phase.generate] + ([Phase.shrink] if SHRINK else []),
    suppress_health_check=_HEALTH,
    print_blob=False,
)
settings.register_profile(
    "fmu-fuzz-long",
    max_examples=max(LONG, 1),
    deadline=None,
    database=None,
    phases=[Phase.explicit, Phase.generate] + ([Phase.shrink] if SHRINK else []),
    suppress_health_check=_HEALTH,
)
PROFILE = settings.get_profile("fmu-fuzz-long" if LONG else "fmu-fuzz-short")


class FuzzViolationError(AssertionError):
    """A run broke an invariant of the FMUs' contract (the message holds the reproducer)."""


@pytest.fixture(scope="module")
def pool():
    p = Pool(OUT)
    yield p
    p.close()


@pytest.fixture(scope="module")
def stats():
    s = Stats()
    yield s
    command = f"CONTACT_FMU_FUZZ_EXAMPLES={LONG} make fuzz" if LONG else "pytest (default suite)"
    s.write(OUT / ("long" if LONG else "short"), command)


def _report(kind: str, ops: list[dict], violations, res) -> str:
    v = violations[0]
    rec = res.records[v.index] if 0 <= v.index < len(res.records) else None
    classes = sorted({x.cls for x in violations})
    return (
        f"{kind}: {v.cls} ({len(violations)} violations: {classes})\n"
        f"detail: {v.detail}\nat record: {json.dumps(rec)[:600]}\n"
        f"reproducer (worker ops): {json.dumps(ops)}"
    )


@pytest.mark.parametrize("kind", list(KINDS))
def test_fmu_under_hostile_calls(kind, pool, stats):
    k = KINDS[kind]
    path = k.path  # built (or taken from the cache) before hypothesis starts timing
    t_end = time.monotonic() + BUDGET

    def run(ops):
        if LONG and time.monotonic() > t_end:
            return
        res = pool.execute(path, ops)
        violations = invariants.check(k, ops, res)
        stats.add(kind, ops, res, violations)
        if violations and not COLLECT:
            raise FuzzViolationError(_report(kind, ops, violations, res))

    for ops in reversed(KNOWN.get(kind, [])):  # the runs that once failed, replayed first
        run = example(ops=ops)(run)
    run = PROFILE(given(ops=strategies.runs(k))(run))
    try:
        run()
    finally:
        pool.release(path)


@pytest.mark.skipif(not LONG, reason="the long run's verdict (make fuzz)")
def test_long_fuzz_found_nothing(stats):
    summary = stats.write(OUT / "long", f"CONTACT_FMU_FUZZ_EXAMPLES={LONG} make fuzz")
    found = stats.as_dict()["violations"]
    assert not found, f"failure classes {list(found)}: see {summary}"


# ---- the checker itself, on synthetic call records (no FMU run) ------------------------
def _records(kind, ops, steps):
    """Records of an initialised fig13-like run: ops[0:3] = setup, enter, exit, then one
    doStep op per entry of ``steps`` = (status, before, after) with getReal values."""
    recs = [{"i": -1, "call": "instantiate", "status": 0, "log": []}]
    recs += [
        {"i": i, "call": c, "status": 0, "log": []}
        for i, c in enumerate(("setupExperiment", "enterInitializationMode"))
    ]
    recs.append({"i": 2, "call": "exitInitializationMode", "status": 0, "log": []})
    for n, (st, before, after) in enumerate(steps):
        i = 3 + n
        h = ops[i]["h"]
        recs += [
            {
                "i": i,
                "call": "getReal",
                "status": 0,
                "log": [],
                "values": before,
                "phase": "before",
            },
            {"i": i, "call": "doStep", "status": st, "log": [], "t": 1e-4 * n, "h": h},
            {"i": i, "call": "getReal", "status": 0, "log": [], "values": after, "phase": "after"},
        ]
    return recs


def _check(kind, steps, h=1e-4, **result):
    from fmu_fuzz.pool import Result

    ops = [{"op": "setup"}, {"op": "enter"}, {"op": "exit"}] + [{"op": "step", "h": h}] * len(steps)
    res = Result(records=_records(kind, ops, steps), **result)
    return {v.cls for v in invariants.check(KINDS[kind], ops, res)}


def test_checker_momentum_balance_bound():
    """fig13 (M = 1 kg, Fx_ex = F = 190.99 N, mu P = 300 N, h = 1e-4 s): Eq. (8) allows
    dVx = h (Fx_ex -+ mu P)/M = 0.0191 +- 0.03 m/s; 0.049 passes, 0.0492 does not."""
    base = {"Vx": 5.6, "Omega_y": 112.0, "Tx": 0.0}
    ok = dict(base, Vx=5.6 + 0.0490)
    bad = dict(base, Vx=5.6 + 0.0492)
    assert "momentum_balance" not in _check("fig13", [(0, base, ok)])
    assert "momentum_balance" in _check("fig13", [(0, base, bad)])
    # a discarded step changes nothing and is not checked
    assert "momentum_balance" not in _check("fig13", [(2, base, bad)])


def test_checker_flags_fatal_nan_friction_and_crash():
    k = KINDS["fig13"]
    base = {"Vx": k.start("Vx0"), "Omega_y": k.start("Vx0") / k.start("Rx"), "Tx": 0.0}
    over = dict(base, Tx=300.0 * (1 + 1e-9))  # mu P = 300 N
    assert "T_exceeds_muP" in _check("fig13", [(0, base, over)])
    assert "T_exceeds_muP" not in _check("fig13", [(0, base, dict(base, Tx=300.0))])
    assert "nonfinite_ok:output" in _check("fig13", [(0, base, dict(base, Tx="nan"))])
    assert "fatal:doStep" in _check("fig13", [(4, base, base)])
    assert "crash" in _check("fig13", [(0, base, base)], crashed=True, returncode=-11)


def test_checker_roundtrip_is_bit_for_bit():
    """get state, k steps, set state, k steps: outputs compared as float.hex strings, so a
    last-bit difference (or -0.0 for 0.0) is a violation and an equal series is not."""
    from fmu_fuzz.pool import Result

    ops = [{"op": "setup"}, {"op": "enter"}, {"op": "exit"}, {"op": "roundtrip", "h": 1e-4, "k": 1}]
    recs = _records("fig13", ops, [])

    def classes(second):
        first = [[0, 0, {"Vx": (5.6).hex(), "Tx": (0.0).hex()}]]
        rt = {"i": 3, "call": "freeFMUstate", "status": 0, "log": [], "phase": "roundtrip"}
        res = Result(records=[*recs, dict(rt, series=[first, second])])
        return {v.cls for v in invariants.check(KINDS["fig13"], ops, res)}

    same = [[0, 0, {"Vx": (5.6).hex(), "Tx": (0.0).hex()}]]
    last_bit = [[0, 0, {"Vx": (5.6 + 8.9e-16).hex(), "Tx": (0.0).hex()}]]
    signed_zero = [[0, 0, {"Vx": (5.6).hex(), "Tx": (-0.0).hex()}]]
    assert 5.6 + 8.9e-16 != 5.6
    assert "roundtrip_not_bitexact" not in classes(same)
    assert "roundtrip_not_bitexact" in classes(last_bit)
    assert "roundtrip_not_bitexact" in classes(signed_zero)


def test_checker_rigid_body_update_is_exact():
    """The rigid body's update with Tx held (Eqs. 8-9) is exact up to rounding: Fx_ex =
    0, Tx = 0 (the start values) leave Vx unchanged; a change of 1e-12 m/s is flagged."""
    base = {"Vx": 5.6418958354775635, "Omega_y": 112.83791670955127}
    assert "momentum_balance" not in _check("full_rigid_body", [(0, base, base)])
    moved = dict(base, Vx=base["Vx"] + 1e-12)
    assert "momentum_balance" in _check("full_rigid_body", [(0, base, moved)])
