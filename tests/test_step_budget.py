"""The work of one doStep is bounded by the parameter max_work, on both targets.

A communication step takes at most max_work // (the cost of one internal step) internal
steps: 1 per step of the scalar path, WORK_VECTOR per step with Vy and/or Omega_z as
unknowns (Eqs. 10-11), WORK_PER_CELL nx ny per step of the transient field
(fmu/body_model.py). Beyond it the step is taken in those fewer, longer steps and
answered fmi2Warning, or refused with fmi2Discard where it fails (docs/reliability.md).
Where Python solves the stages, each evaluation of the law counts too (WORK_VECTOR_EVAL,
or WORK_PER_CELL_EVAL nx ny for the field): a step whose evaluations exceed the budget
is discarded. The calls below once ran for tens
of seconds (a randomised run of hostile, legal call sequences): the full body FMU's
doStep(3e-4, 1000) 27.8 s, the cornering scene's doStep(1e6 + 0.0135, 1e6) at P = 1898
N, Fy_ex = 4509 N 22.8 s, fig12_transient's doStep(5.2e-4, 0.401) beyond 40 s: 10,000
internal steps of 0.3 to 8 ms each. The work is counted, never timed: from the warning's
"taken in N steps" on both targets, and by counting the stepper's internal steps in
process (the pythonfmu FMU's adapter, ContactSlave).
"""

from __future__ import annotations

import ctypes
import re
from pathlib import Path

import pytest
from fmpy.fmi1 import FMICallException

import fmu_build
from contact_fmu import native
from contact_fmu.dynamics.integrator import EvalBudget, RollingBody
from contact_fmu.dynamics.thin_layer_field import TransientRollingBody
from contact_fmu.fmu import body_model
from contact_fmu.fmu import variables as fv
from contact_fmu.fmu.body_model import (
    MAX_WORK,
    WORK_PER_CELL,
    WORK_PER_CELL_EVAL,
    WORK_SCALAR,
    WORK_SCALAR_EVAL,
    WORK_VECTOR,
    WORK_VECTOR_EVAL,
)
from contact_fmu.fmu.config import ModelConfig
from contact_fmu.fmu.slave import CELL_VR, ContactSlave
from contact_fmu.native import field as native_field
from contact_fmu.scenario import load
from contact_fmu.scenario.instance import DISCARD, OK, Instance

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "out" / "fmu"
WARNING = 1
NOTE = re.compile(
    r"communication step h = \S+ s needs more internal steps \((?P<limits>[^)]*)\) than "
    r"max_work = (?P<budget>\S+) allows \(each costs (?P<cost>\S+)\): taken in (?P<n>\d+) "
    r"steps of \S+ s"
)


def config(model: str) -> ModelConfig:
    if model == "full-body":
        return ModelConfig.full("body")
    return load(ROOT / "scenarios" / f"{model}.toml").config


def build(target: str, model: str) -> Path:
    cfg = config(model)
    if target == "native":
        from fmu_build import native_fmu

        return native_fmu.build(cfg, OUT).path
    return fmu_build.build(cfg, OUT).path


# The slow calls, reconstructed: (model, cost of one internal step, calls before, inputs
# set before the slow call, (t, h) of the slow call, its statuses). The full body FMU
# with a yaw moment only (Omega_z reaches 1e3 rad/s in 1000 s, within its range): the
# step is taken, capped; with a lateral force and a longitudinal one as well, the speeds
# leave their range (Discard, after the capped work).
FULL_YAW = ("full-body", WORK_VECTOR, [(0.0, 3e-4)], {"Mz_ex": 1e-3}, (3e-4, 1000.0))
FULL_LOADED = (
    "full-body",
    WORK_VECTOR,
    [(0.0, 3e-4)],
    {"Fx_ex": 60.0, "Fy_ex": 90.0, "Mz_ex": 1e-3},
    (3e-4, 1000.0),
)
CORNERING = (
    "cornering",
    WORK_VECTOR,
    [(0.0, 1e6), (1e6, 0.0135)],
    {"P": 1898.0, "Fy_ex": 4509.0},
    (1e6 + 0.0135, 1e6),
)
TRANSIENT = ("fig12_transient", 32 * 16 * WORK_PER_CELL, [(0.0, 5.2e-4)], {}, (5.2e-4, 0.401))
SLOW = {"full body, yaw": FULL_YAW, "full body, loaded": FULL_LOADED, "cornering": CORNERING,
        "fig12_transient": TRANSIENT}  # fmt: skip
TARGETS: dict[str, tuple[str, ...]] = {}  # models not on both targets (none: all native)


def _do_step(b: Instance, t: float, h: float) -> int:
    try:
        return b.fmu.fmi2DoStep(b.fmu.component, t, h, 1)
    except FMICallException as e:
        return int(e.status)


def test_the_costs_in_the_declaration_are_the_models():
    """max_work's description states the costs body_model counts (1, WORK_VECTOR, nx ny
    WORK_PER_CELL) and its default is MAX_WORK."""
    var = fv.BY_NAME["max_work"]
    assert var.start == MAX_WORK and var.type == "Real" and var.min == 1.0
    assert WORK_SCALAR == 1
    assert f"costs 1 (vx the only unknown), {WORK_VECTOR} (Vy and/or Omega_z" in var.description
    assert f'{WORK_PER_CELL} nx ny (phase "transient")' in var.description
    evals = f"{WORK_SCALAR_EVAL}, {WORK_VECTOR_EVAL} with Eqs. 10-11, nx ny / "
    assert evals + f"{1 / WORK_PER_CELL_EVAL:g} on the field" in var.description


@pytest.mark.parametrize("case", SLOW, ids=list(SLOW))
@pytest.mark.parametrize("target", ("pythonfmu", "native"))
def test_a_slow_call_returns_within_the_budget(target, case):
    """Each call returns with Warning or Discard; where it is taken (Warning) its note
    states the internal steps, and their work N x cost is within max_work; with
    another budget (a tenth; twice for the field, whose steps before need the default)
    the same call takes that many steps (the parameter reaches the step)."""
    model, cost, before, inputs, (t, h) = SLOW[case]
    if target not in TARGETS.get(model, ("pythonfmu", "native")):
        pytest.skip(f"{model} has no {target} FMU")
    fmu = build(target, model)
    other = 2 * MAX_WORK if model == "fig12_transient" else MAX_WORK // 10
    for budget in (MAX_WORK, other):
        with Instance(fmu, "slow", {"max_work": budget}) as b:
            for t0, h0 in before:
                assert _do_step(b, t0, h0) in (OK, WARNING)
            for name, value in inputs.items():
                b.set(name, value)
            start = len(b.messages)
            status = _do_step(b, t, h)
            assert status in (WARNING, DISCARD), (status, b.messages[start:])
            assert b.messages[start:], "answered without a message"
            notes = [NOTE.search(m) for _, m in b.messages[start:]]
            notes = [m for m in notes if m]
            if status == WARNING:
                (note,) = notes
                n, c = int(note["n"]), float(note["cost"])
                assert c == cost and float(note["budget"]) == budget
                assert n * c <= budget and n == max(1, int(budget // cost))


# ---- in process: the internal steps counted where they are taken ----------------------
class Counter:
    """Internal steps taken: in Python (RollingBody._step, TransientRollingBody._step)
    and in C (the n of the compiled vector path's cf_advance_vector, the substeps of
    the transient body's compiled advance, cf_field_advance; the scalar path's are the
    fast path's, counted by its note's n)."""

    def __init__(self, monkeypatch: pytest.MonkeyPatch) -> None:
        self.python = 0
        self.compiled: list[int] = []
        self.evals = 0  # the law's (the field's) evaluations in Python stage solves
        spend = EvalBudget.spend

        def counted_spend(stepper):
            self.evals += 1
            return spend(stepper)

        monkeypatch.setattr(EvalBudget, "spend", counted_spend)
        for cls in (RollingBody, TransientRollingBody):
            step = cls._step

            def counted(rb, *a, step=step, **k):
                self.python += 1
                return step(rb, *a, **k)

            monkeypatch.setattr(cls, "_step", counted)
        advance = native.VectorKernel.advance

        def counted_advance(kernel, rb, h, loads, n):
            self.compiled.append(n)
            return advance(kernel, rb, h, loads, n)

        monkeypatch.setattr(native.VectorKernel, "advance", counted_advance)
        field_advance = native_field.CompiledField.advance

        def counted_field_advance(compiled, *a):  # the transient body's internal steps in C
            self.compiled.append(a[-1])  # substeps
            return field_advance(compiled, *a)

        monkeypatch.setattr(native_field.CompiledField, "advance", counted_field_advance)


def slave(cfg: ModelConfig, params: dict) -> tuple[ContactSlave, ctypes.c_int]:
    cls = type("Model", (ContactSlave,), {"CONFIG": cfg.to_dict()})
    s = cls(instance_name="budget")
    cell = ctypes.c_int(0)  # the shim's status cell (pythonfmu_shim.c)
    s.set_string([CELL_VR], [f"status cell {hex(ctypes.addressof(cell))}"])
    vr = {v.name: k for k, v in s.vars.items()}
    s.setup_experiment(0.0)
    s.enter_initialization_mode()
    for k, v in params.items():
        s.set_real([vr[k]], [v])
    s.exit_initialization_mode()
    return s, cell


@pytest.mark.parametrize("case", SLOW, ids=list(SLOW))
def test_internal_steps_taken_in_process_are_within_the_budget(monkeypatch, case):
    """The pythonfmu FMU's adapter with the stepper's internal steps counted: the slow
    call takes at most max_work // cost of them in Python and at most that many in C
    (the compiled vector path declines a stage it cannot solve and Python takes the
    step again: the cap twice, the compiled one at a tenth of the cost), and evaluates
    the law (the field) in Python at most max_work // (its cost) times, whatever it
    answers; where that stops it, the message names max_work."""
    model, cost, before, inputs, (t, h) = SLOW[case]
    cfg = config(model)
    s, cell = slave(cfg, {})
    vr = {v.name: k for k, v in s.vars.items()}
    for t0, h0 in before:
        assert s.do_step(t0, h0)
    for name, value in inputs.items():
        s.set_real([vr[name]], [value])
    counter = Counter(monkeypatch)
    cell.value = OK
    s.do_step(t, h)
    assert cell.value >= WARNING
    cap = max(1, int(MAX_WORK // cost))
    assert counter.python <= cap, counter.python
    assert all(n <= cap for n in counter.compiled), counter.compiled
    assert counter.python + sum(counter.compiled) >= 1  # the step did run
    eval_cost = 32 * 16 * WORK_PER_CELL_EVAL if model == "fig12_transient" else WORK_VECTOR_EVAL
    limit = int(MAX_WORK // eval_cost)
    assert counter.evals <= limit + 1, counter.evals  # the last one refused, not made
    last = s.log_queue[-1].msg
    if "WorkBudgetError" in last:
        assert counter.evals == limit + 1
        assert (
            f"WorkBudgetError: the stage solves need more than {limit} evaluations of the "
            f"law, beyond max_work = {MAX_WORK:g} (each costs {eval_cost:g})" in last
        )


def test_a_field_whose_one_step_exceeds_the_budget_is_discarded_naming_max_work():
    """The transient field costs WORK_PER_CELL nx ny per internal step: a 128 x 128
    field cannot take one step within the default budget: fmi2Discard naming max_work
    and the work it needs, state unchanged; with max_work raised the step is taken."""
    need = WORK_PER_CELL * 128 * 128
    fmu = build("pythonfmu", "fig12_transient")
    with Instance(fmu, "big", {"nx": 128, "ny": 128}) as b:
        before = b.outputs()
        assert _do_step(b, 0.0, 1e-6) == DISCARD
        assert (
            f"max_work = {float(MAX_WORK)!r} is invalid: must be >= {need:g}, the work of one "
            "internal step on the 128 x 128 field" in b.messages[-1][1]
        )
        assert b.outputs() == before
    with Instance(fmu, "big", {"nx": 128, "ny": 128, "max_work": need}) as b:
        assert _do_step(b, 0.0, 1e-6) == OK


def test_budget_of_the_scalar_path_is_the_old_cap():
    """The scalar path's cap at the default budget is MAX_SUBSTEPS = 10,000 steps (its
    cost is 1): stepper.c's CF_MAX_SUBSTEPS, the default of cf_body.max_substeps."""
    assert body_model.MAX_SUBSTEPS == 10_000 == body_model.step_cap(MAX_WORK, WORK_SCALAR)
    assert body_model.step_cap(MAX_WORK, WORK_VECTOR) == MAX_WORK // WORK_VECTOR
    assert body_model.step_cap(1, WORK_VECTOR) == 1  # at least one step


def test_both_targets_word_the_capped_step_the_same():
    """The full body FMU's capped step (Eqs. 10-11 on the vector path): the pythonfmu
    FMU words the note in Python, the native one in C, from the same budget: the same
    status and the same words."""
    model, _, before, inputs, (t, h) = FULL_YAW
    answers = []
    for target in ("pythonfmu", "native"):
        with Instance(build(target, model), "words", {"max_work": 2500.0}) as b:
            for t0, h0 in before:
                assert _do_step(b, t0, h0) == OK
            for name, value in inputs.items():
                b.set(name, value)
            start = len(b.messages)
            answers.append((_do_step(b, t, h), b.messages[start:]))
    assert answers[0] == answers[1]
    assert answers[0][0] == WARNING
    assert (
        f"(each costs {WORK_VECTOR}): taken in {2500 // WORK_VECTOR} steps" in answers[0][1][-1][1]
    )
