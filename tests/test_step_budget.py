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
"taken in N steps" on both targets (the native FMU's FMI 2.0 and FMI 3.0 front ends), and
by counting the stepper's internal steps in process (the pythonfmu FMU's adapter,
ContactSlave). The transient FMU (fig12_transient) also takes the other hostile loads of
the same runs on every target: mu = 5e-324 after a normal start, and a tiny mass with
the reported sequence of steps.
"""

from __future__ import annotations

import ctypes
import re
import sys
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
from contact_fmu.scenario.instance import DISCARD, ERROR, FATAL, OK, Instance

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
    if model == "full-body-held-spin":  # Vy and Omega_z held at ratios of Vx, no Eqs. 10-11
        d = ModelConfig.full("body").to_dict()
        starts = {"vy_ratio": 0.002, "spin_ratio": 1.0}
        return ModelConfig.from_dict(d | {"name": "full_body_held_spin", "vy": "ratio",
                                          "spin": "ratio", "inputs": ["P", "Fx_ex", "My_ex"],
                                          "starts": starts})  # fmt: skip
    return load(ROOT / "scenarios" / f"{model}.toml").config


def build(target: str, model: str) -> Path:
    """The FMU of ``model`` for a target: "pythonfmu", "native" (FMI 2.0) or "native3"
    (the native FMU's FMI 3.0 front end)."""
    cfg = config(model)
    if target == "native":
        from fmu_build import native_fmu

        return native_fmu.build(cfg, OUT).path
    if target == "native3":
        from fmu_build import native_fmu3

        return native_fmu3.build(cfg, OUT).path
    return fmu_build.build(cfg, OUT).path


def open_fmu(target: str, path: Path, start_values: dict | None = None):
    """An initialised instance: scenario.Instance (FMI 2.0), or for "native3" the FMI 3.0
    driver of tests/test_native_fmi3.py (the same shape)."""
    if target == "native3":
        from test_native_fmi3 import Instance3

        return Instance3(path, "budget3", start_values)
    return Instance(path, "budget", start_values)


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
# a held spin on the thin-layer law marches the spin grid in every evaluation: 2.3-2.8 s
# for doStep(1e-4, 1.0) at the scalar path's cost of 1 (10,000 internal steps)
HELD_SPIN = ("full-body-held-spin", WORK_VECTOR, [(0.0, 1e-4)], {"Fx_ex": 100.0}, (1e-4, 1.0))
SLOW = {"full body, yaw": FULL_YAW, "full body, loaded": FULL_LOADED, "cornering": CORNERING,
        "fig12_transient": TRANSIENT, "held spin": HELD_SPIN}  # fmt: skip
TARGETS: dict[str, tuple[str, ...]] = {}  # models not on both targets (none: all native)


def _do_step(b, t: float, h: float) -> int:
    """doStep from t by h on either front end: its status, Warning included (fmpy raises
    only above it)."""
    try:
        if isinstance(b, Instance):
            return b.fmu.fmi2DoStep(b.fmu.component, t, h, 1)
        from fmpy.fmi3 import fmi3Boolean, fmi3Float64

        flags, last = [fmi3Boolean() for _ in range(3)], fmi3Float64()
        refs = [ctypes.byref(f) for f in flags]
        return b.fmu.fmi3DoStep(b.fmu.component, t, h, fmi3Boolean(True), *refs, ctypes.byref(last))
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
    evals = f"{WORK_SCALAR_EVAL}, {WORK_VECTOR_EVAL} with Eqs. 10-11 or the spin grid, nx ny / "
    assert evals + f"{1 / WORK_PER_CELL_EVAL:g} on the field" in var.description


@pytest.mark.parametrize("case", SLOW, ids=list(SLOW))
@pytest.mark.parametrize("target", ("pythonfmu", "native", "native3"))
def test_a_slow_call_returns_within_the_budget(target, case):
    """Each call returns with Warning or Discard; where it is taken (Warning) its note
    states the internal steps, and their work N x cost is within max_work; with
    another budget (a tenth; twice for the field, whose steps before need the default)
    the same call takes that many steps (the parameter reaches the step). The native
    FMU through both of its front ends (FMI 2.0, FMI 3.0)."""
    model, cost, before, inputs, (t, h) = SLOW[case]
    if target not in TARGETS.get(model, ("pythonfmu", "native", "native3")):
        pytest.skip(f"{model} has no {target} FMU")
    fmu = build(target, model)
    other = 2 * MAX_WORK if model == "fig12_transient" else MAX_WORK // 10
    for budget in (MAX_WORK, other):
        with open_fmu(target, fmu, {"max_work": budget}) as b:
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
    and in C (the n of the compiled paths' cf_advance and cf_advance_vector where the
    adapter's fast path does not take the step, the substeps of the transient body's
    compiled advance, cf_field_advance; the fast path's are counted by its note's n)."""

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
        for kernel_cls in (native.Kernel, native.VectorKernel):
            advance = kernel_cls.__dict__["advance"]

            def counted_advance(kernel, rb, h, loads, n, advance=advance):
                self.compiled.append(n)
                return advance(kernel, rb, h, loads, n)

            monkeypatch.setattr(kernel_cls, "advance", counted_advance)
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


# ---- the transient FMU under the other hostile loads, every target ---------------------
TRANSIENT_TARGETS = ("pythonfmu", "native", "native3")
FIELD_STEP = 32 * 16 * WORK_PER_CELL  # the work of one internal step of the 32 x 16 field
# The tiny-mass sequence of the hostile runs (fig13 with M = 1e-300, test_fmu_liftoff):
# steps of h (s) at the FMU's time, then Fx_ex = -38.2284 N and a step of 1e-12 s.
TINY_MASS_STEPS = (1.75e-4, 4.03e-9, 1.75e-5, 1.75e-5, ("Fx_ex", -38.2284), 1e-12)


def _notes_within(messages: list[tuple[int, str]], budget: float) -> None:
    """Each capped-step note of ``messages`` states the field's cost and at most the
    budget's internal steps (N x cost <= max_work, N = max(1, max_work // cost))."""
    for _, text in messages:
        note = NOTE.search(text)
        if note:
            n, c = int(note["n"]), float(note["cost"])
            assert c == FIELD_STEP and float(note["budget"]) == budget, text
            assert n == max(1, int(budget // c)) and (n * c <= budget or n == 1), text


@pytest.mark.parametrize("target", TRANSIENT_TARGETS)
def test_friction_coefficient_5e_324_after_start_is_refused_on_the_transient_field(target):
    """mu = 5e-324 after a normal start (fmi2Fatal, ZeroDivisionError, on the pythonfmu
    FMU of the steady phase once): refused at the setter with Error naming mu and its
    minimum; the next doStep answers Discard naming mu, the outputs unchanged; with mu =
    0.3 again the step is OK, and mu = MU_MIN itself is taken: the field's traction is
    bounded by mu p, so abs(Tx) <= MU_MIN P (to 1e-12)."""
    with open_fmu(target, build(target, "fig12_transient")) as b:
        assert _do_step(b, 0.0, 1e-4) == OK
        with pytest.raises(FMICallException) as e:
            b.set("mu", 5e-324)
        assert e.value.status == ERROR
        assert f"mu = 5e-324 is invalid: must be >= {fv.MU_MIN:g}" in b.messages[-1][1]
        before = b.outputs()
        assert _do_step(b, 1e-4, 1e-4) == DISCARD
        assert "mu = 5e-324 is invalid" in b.messages[-1][1], b.messages[-1:]
        assert b.outputs() == before
        b.set("mu", 0.3)
        assert _do_step(b, 1e-4, 1e-4) == OK
        b.set("mu", fv.MU_MIN)
        assert _do_step(b, 2e-4, 1e-4) == OK
        assert abs(b.get("Tx")) <= fv.MU_MIN * b.get("P") * (1 + 1e-12)


def _tiny_mass_run(b, budget: float) -> list[tuple[int, float, dict, dict]]:
    """TINY_MASS_STEPS at the FMU's time (it moves on OK and Warning only): per step
    (status, h, outputs and Fx_ex before, outputs after); the notes within ``budget``."""
    t, out = 0.0, []
    for h in TINY_MASS_STEPS:
        if isinstance(h, tuple):
            b.set(*h)
            continue
        before = b.outputs() | {"Fx_ex": b.get("Fx_ex")}
        start = len(b.messages)
        status = _do_step(b, t, h)
        assert status in (OK, WARNING, DISCARD), (status, b.messages[start:])
        _notes_within(b.messages[start:], budget)
        if status == DISCARD:
            assert b.messages[start:], "discarded without a message"
        else:
            t += h
        out.append((status, h, before, b.outputs()))
    return out


@pytest.mark.parametrize("M", (1e-300, 1e-6))
@pytest.mark.parametrize("target", TRANSIENT_TARGETS)
def test_tiny_mass_sequence_on_the_transient_field_keeps_the_momentum_balance(target, M):
    """The tiny-mass sequence on the transient field, at the default budget and at one
    internal step's work (max_work = 2 nx ny: every longer step capped to one): each
    doStep answers OK, Warning or Discard, its capped-step note within the budget; a
    discarded step leaves the outputs as they were; a step taken keeps the momentum
    balance of Eq. (8), M dVx = (Fx_ex - Tx) h with abs(Tx) <= mu P over the step
    (SDIRK2's weights 1 - gamma and gamma are positive), to rounding of Vx (8 eps); and
    Eq. (9) with My_ex = 0, Iy dOmega_y = Rx Tx h, Omega_y = (Vx - vx)/Rx (to its
    rounding, 8 eps Vx/Rx). M = 1e-300
    drives the body beyond what the field resolves at every step (each discarded); M =
    1e-6 beyond the speed range at the first step only."""
    eps = sys.float_info.epsilon
    fmu = build(target, "fig12_transient")
    for budget in (MAX_WORK, FIELD_STEP):
        with open_fmu(target, fmu, {"M": M, "max_work": budget}) as b:
            mu, P, Iy, Rx = (b.get(n) for n in ("mu", "P", "Iy", "Rx"))
            run = _tiny_mass_run(b, budget)
        taken = [r for r in run if r[0] != DISCARD]
        for status, h, before, after in run:
            if status == DISCARD:
                assert after == {k: v for k, v in before.items() if k != "Fx_ex"}
                continue
            dV = after["Vx"] - before["Vx"]
            slack = mu * P * h * (1 + 1e-9) + 8 * eps * M * max(abs(after["Vx"]), 1.0)
            assert abs(M * dV - before["Fx_ex"] * h) <= slack, (h, dV)
            omega = [(o["Vx"] - o["vx"]) / Rx for o in (before, after)]
            spin = Iy * (omega[1] - omega[0])
            # Omega_y read back through vx = Vx - Rx Omega_y: rounded at eps Vx / Rx
            rounding = Iy * 8 * eps * max(abs(after["Vx"]), abs(before["Vx"])) / Rx
            assert abs(spin) <= Rx * mu * P * h * (1 + 1e-9) + rounding, (h, spin)
        assert len(taken) == (0 if M == 1e-300 else 4), [r[0] for r in run]


def test_tiny_mass_discard_names_the_lattice_roll_on_both_targets():
    """M = 1e-300: the first step would roll the field's lattice by more than 1e9
    columns (thin_layer_field.SHIFT_MAX, field.c's limit): both FMUs discard the step and
    say so in the same words (the loads or the step drive the body beyond what the field
    resolves), where Python's floor would overflow a C long."""
    said = {}
    for target in ("native", "pythonfmu"):
        with open_fmu(target, build(target, "fig12_transient"), {"M": 1e-300}) as b:
            assert _do_step(b, 0.0, 1.75e-4) == DISCARD
            said[target] = b.messages[-1][1]
            assert "traction field's lattice by more than 1e+09 columns" in said[target]
    assert said["native"] == said["pythonfmu"]


def test_hostile_loads_on_the_transient_field_take_bounded_internal_steps_in_process(
    monkeypatch,
):
    """The pythonfmu FMU's adapter on the transient field with the internal steps counted
    (Python and the compiled cf_field_advance): mu = 5e-324 after a start and the
    tiny-mass sequence (M = 1e-6 and 1e-300) take at most max_work // (2 nx ny) internal
    steps per doStep, whatever each answers."""
    cfg = config("fig12_transient")
    cap = max(1, int(MAX_WORK // FIELD_STEP))
    for params in ({}, {"M": 1e-6}, {"M": 1e-300}):
        s, cell = slave(cfg, params)
        vr = {v.name: k for k, v in s.vars.items()}
        counter = Counter(monkeypatch)
        if not params:  # mu = 5e-324 after a start
            calls: list = [1e-4, ("mu", 5e-324), 1e-4, ("mu", 0.3), 1e-4]
        else:
            calls = list(TINY_MASS_STEPS)
        t = 0.0
        for call in calls:
            if isinstance(call, tuple):
                cell.value = OK
                s.set_real([vr[call[0]]], [call[1]])
                # mu = 5e-324 refused (Error in the shim's cell), the others taken
                assert cell.value == (ERROR if call == ("mu", 5e-324) else OK), call
                continue
            python, compiled = counter.python, len(counter.compiled)
            cell.value = OK
            s.do_step(t, call)
            if cell.value <= WARNING:  # taken: the FMU's time moves on
                t += call
            assert counter.python - python <= cap
            assert all(n <= cap for n in counter.compiled[compiled:]), counter.compiled


def test_transient_state_round_trips_through_the_fmi3_front_end_and_damage_is_refused():
    """The native transient FMU's state through FMI 3.0 (the FMI 2.0 front end's:
    tests/test_native_transient.py): got while the field forms, steps, set back, the same
    steps give the same doubles; serialized into a fresh instance, the same again. Bytes
    with a flipped byte, cut short, or the FMI 2.0 FMU's state of the same field (another
    instantiation token) are refused with Error naming why; the outputs stay, the
    instance steps on."""
    h = 2e-5  # the scene's communication step
    with Instance(build("native", "fig12_transient"), "fmi2") as b:
        assert _do_step(b, 0.0, h) == OK
        foreign = b.serialize_state(b.get_state())
    path = build("native3", "fig12_transient")
    with open_fmu("native3", path) as a, open_fmu("native3", path) as fresh:

        def steps(inst, n: int) -> None:
            for _ in range(n):
                assert inst.step(h) == OK, inst.messages[-1:]

        steps(a, 20)
        state, at = a.fmu.getFMUState(), a.time
        steps(a, 10)
        first = a.outputs()
        a.fmu.setFMUState(state)
        a.time = at
        steps(a, 10)
        assert a.outputs() == first
        data = a.fmu.serializeFMUState(state)
        fresh.fmu.setFMUState(fresh.fmu.deserializeFMUState(data))
        fresh.time = at
        steps(fresh, 10)
        assert fresh.outputs() == first
        flipped = bytearray(data)
        flipped[len(data) // 2] ^= 0x10  # inside the field's tractions
        cases = {
            "flipped": (bytes(flipped), "checksum"),
            "cut short": (data[:-9], "length"),
            "fmi2": (foreign, "another FMU"),
        }
        for case, (raw, reason) in cases.items():
            before = a.outputs()
            with pytest.raises(FMICallException) as e:
                a.fmu.deserializeFMUState(raw)
            assert e.value.status == ERROR, case
            assert reason in a.messages[-1][1], (case, a.messages[-1:])
            assert a.outputs() == before
            steps(a, 1)
        a.fmu.freeFMUState(state)
        assert all(s < FATAL for s, _ in a.messages)
