"""The built FMUs through fmpy, call by call: FMU state, bad input, step sizes, two FMUs.

Every status here is the one fmpy receives from the FMU binary (pythonfmu's C layer),
and every message the one its logger callback receives.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from fmpy.fmi1 import FMICallException

import fmu_build
from contact_fmu import examples as ex
from contact_fmu.dynamics.body import Body
from contact_fmu.dynamics.simulate import load_history, simulate
from contact_fmu.scenario import load, runner
from contact_fmu.scenario.instance import FATAL, OK, Instance

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "out" / "fmu"
F = ex.force_unit()
MU_P = ex.mu * ex.P


@pytest.fixture(scope="session")
def scenes():
    return {n: load(ROOT / "scenarios" / f"{n}.toml") for n in ("fig13", "railway", "sweep")}


@pytest.fixture(scope="session")
def fmus(scenes) -> dict[str, Path]:
    return {n: fmu_build.build(s.config, OUT).path for n, s in scenes.items()}


def body(fmus, **params) -> Instance:
    """The Fig. 13 FMU (body mode, eta = 3) under Fx_ex = F, My_ex = -0.1 F Rx."""
    inst = Instance(fmus["fig13"], "body", params)
    inst.set("Fx_ex", F)
    inst.set("My_ex", -0.1 * F * ex.Rx)
    return inst


def steps(inst: Instance, n: int, h: float) -> None:
    """n doSteps of h, each fmi2OK."""
    for _ in range(n):
        assert inst.step(h) == OK, inst.messages[-1:]


def test_fmu_state_in_contact_mode(fmus):
    with Instance(fmus["sweep"], "contact") as c:
        c.set("Omega_y", ex.speed_unit() / ex.Rx * 0.998)
        assert c.step(2e-3) == OK
        state = c.get_state()
        before = c.outputs()
        c.set("Omega_y", ex.speed_unit() / ex.Rx * 1.004)
        assert c.step(2e-3) == OK and c.outputs() != before
        c.set_state(state)
        assert c.outputs() == before


RESTORE_SCRIPT = """
import json, sys
from contact_fmu.scenario.instance import Instance
with Instance(sys.argv[1], "restored") as b:
    data = open(sys.argv[2], "rb").read()
    b.set_state(b.deserialize_state(data, float(sys.argv[3])))
    for _ in range(3):
        assert b.step(1.75e-4) == 0, b.messages
    print(json.dumps({k: v.hex() for k, v in b.outputs().items() if isinstance(v, float)}))
"""


def test_serialized_state_restores_bit_for_bit_in_another_process(fmus, tmp_path):
    """fmi2SerializeFMUstate: a checkpoint of the body FMU (the compiled step's state
    included), restored by a fresh instance in another Python process (the vendored
    package found anew), steps to the same doubles as the original."""
    import json
    import subprocess
    import sys

    with body(fmus) as b:
        steps(b, 4, 1.75e-4)
        state = b.get_state()
        path = tmp_path / "state.bin"
        path.write_bytes(b.serialize_state(state))
        steps(b, 3, 1.75e-4)
        first = {k: v.hex() for k, v in b.outputs().items() if isinstance(v, float)}
        b.free_state(state)
    args = [sys.executable, "-c", RESTORE_SCRIPT, str(fmus["fig13"]), str(path), repr(state[1])]
    proc = subprocess.run(args, capture_output=True, text=True, cwd=ROOT, timeout=120)
    assert proc.returncode == 0, proc.stderr
    assert json.loads(proc.stdout) == first


def test_serialized_state_in_contact_mode(fmus):
    """The contact FMU's state (the load of its law, the held outputs) through bytes into
    another instance, and back into the first after a step at another load (the law
    rebuilt at the state's load): the same outputs, and the same response to a new
    input."""
    with Instance(fmus["sweep"], "a") as a, Instance(fmus["sweep"], "b") as b:
        a.set("Omega_y", ex.speed_unit() / ex.Rx * 0.998)
        a.set("P", 0.8 * ex.P)
        assert a.step(2e-3) == OK
        state = a.get_state()
        before = a.outputs()
        b.set_state(b.deserialize_state(a.serialize_state(state), state[1]))
        assert b.outputs() == before
        a.set("P", 1.2 * ex.P)
        assert a.step(2e-3) == OK and a.outputs() != before
        a.set_state(state)
        assert a.outputs() == before
        for inst in (a, b):
            inst.set("Omega_y", ex.speed_unit() / ex.Rx * 1.004)
            assert inst.step(2e-3) == OK
        assert b.outputs() == a.outputs()
        assert all(s == OK for s, _ in b.messages), b.messages


def test_fmpy_simulate_fails_loudly_for_a_model_that_cannot_start(fmus):
    """fmpy's simulate_fmu (and `fmpy simulate`) raises instead of returning a
    two-row result (they took fmi2OK at initialisation before)."""
    import fmpy

    with pytest.raises(FMICallException):
        fmpy.simulate_fmu(
            str(fmus["fig13"]), start_values={"Rx": 5e-324, "Ry": 2.97e9, "Iy": 0.0},
            stop_time=1e-3, output_interval=1e-4,
        )  # fmt: skip


@pytest.mark.parametrize("h", [1e-6, 1e-5, 1e-4, 1e-3, 1e-2, 1e-1, 1.0])
def test_any_step_from_1e_6_to_1_s_gives_bounded_outputs(fmus, h):
    """Traction beyond the adhesion limit and back, for every communication step.

    h_max = 1e-2 s keeps a 1 s step at 100 internal steps; the L-stable scheme needs no
    step limit for the stiff slip, so every h yields |Tx| <= mu P and finite values.
    """
    with body(fmus, h_max=1e-2) as b:
        for My in (-0.1 * F * ex.Rx, 3.0 * MU_P * ex.Rx, 0.0):  # rolling, sliding, rolling
            b.set("My_ex", My)
            for _ in range(3):
                assert b.step(h) == OK, b.messages[-1:]
                out = b.outputs()
                assert all(math.isfinite(v) for v in out.values()), out
                assert abs(out["Tx"]) <= MU_P * (1 + 1e-12)


def test_result_converges_as_the_communication_step_shrinks(fmus, scenes):
    """Fig. 13 loads (sine moment) held over each step: first-order convergence in h.

    One internal step per communication step (h_max = h), so h is the only resolution.
    The reference is simulate() with the continuous loads and 16 times finer steps than
    the finest h; errors in Vx and Tx at t = 0.014 s must fall by >= 1.6 per halving of
    h (order 1 of the zero-order hold would give 2).
    """
    case = scenes["fig13"].case("eta = 3")
    t_end, Iy = 0.014, case.parameters["Iy"]
    My = case.inputs["My_ex"]
    loads = load_history(Fx_ex=F, My_ex=lambda t: float(My(np.array([t]))[0]))
    ref = simulate(ex.contact(), Body(ex.M, ex.Rx, Iy), loads, t_end, t_end / 1280,
                   Vx0=ex.speed_unit())  # fmt: skip
    errors = []
    for n in (20, 40, 80, 160):
        h = t_end / n
        with Instance(fmus["fig13"], "conv", {"Iy": Iy, "h_max": h}) as b:
            b.set("Fx_ex", F)
            for k in range(n):
                b.set("My_ex", float(My(np.array([k * h]))[0]))
                assert b.step(h) == OK
            errors.append((abs(b.get("Vx") - ref.Vx[-1]), abs(b.get("Tx") - ref.Tx[-1])))
    errors = np.array(errors)
    ratios = errors[:-1] / errors[1:]
    assert np.all(ratios >= 1.6), (errors, ratios)
    assert errors[-1, 1] < 0.01 * F


def test_two_scene_fmus_in_one_process_each_give_their_own_results(fmus, scenes):
    """Fig. 13 and railway FMUs, plus two instances of one FMU, stepped interleaved."""
    fig13, railway = scenes["fig13"], scenes["railway"]
    alone = {
        "fig13": runner.simulate(fmus["fig13"], fig13),
        "railway": runner.simulate(fmus["railway"], railway),
    }
    n = 30
    jobs = [
        ("fig13", fig13, fig13.case("eta = 1.5"), 0),
        ("railway", railway, railway.case("full"), 1),
        ("fig13", fig13, fig13.case("eta = 10"), 2),
    ]
    insts = [Instance(fmus[k], f"i{i}", runner.start_values(s, c)) for k, s, c, i in jobs]
    try:
        tables = [runner.input_table(s, c) for _, s, c, _ in jobs]
        for k in range(n):
            for inst, (_, scene, _, _), table in zip(insts, jobs, tables, strict=True):
                for name in scene.inputs:
                    inst.set(name, float(table[name][k]))
                # the step fmpy's simulate_fmu passes: a difference of grid points, which
                # differs from scene.step in the last bits (bit-identity needs the same h)
                assert inst.step((k + 1) * scene.step - k * scene.step) == OK
        for inst, (key, scene, case, _) in zip(insts, jobs, strict=True):
            own = alone[key][[c.name for c in scene.cases].index(case.name)]
            for name in scene.outputs:
                assert inst.get(name) == own.columns[name][n], (key, case.name, name)
    finally:
        for inst in insts:
            inst.close()


def test_full_body_fmu_lateral_dynamics_and_method_parameter():
    """The full FMU: Eqs. (10)-(11) and the string parameter choosing the stepper."""
    from contact_fmu.fmu.config import ModelConfig

    path = fmu_build.build(ModelConfig.full("body"), OUT).path
    for method in ("full", "quasistationary"):
        with Instance(path, method, {"method": method, "h_max": 1e-4}) as b:
            assert b.get("method") == method
            b.set("Fx_ex", 0.2 * MU_P)
            b.set("Fy_ex", 0.2 * MU_P)
            for _ in range(3):
                assert b.step(1e-4) == OK, b.messages[-1:]
            out = b.outputs()
            assert out["Vy"] > 0.0 and out["Ty"] > 0.0  # the lateral force drives Vy
            assert math.hypot(out["Tx"], out["Ty"]) <= MU_P * (1 + 1e-12)
            if method == "full":
                # the lateral traction's moment spins the body: Iz dOmega_z/dt = -Mz (Eq. 11)
                assert out["Mz"] != 0.0 and np.sign(out["Omega_z"]) == -np.sign(out["Mz"])
            else:  # Eqs. (26), (29), (30): the fast variables balance the loads exactly
                A2 = 0.25  # default Iy: eta = 3
                assert out["Tx"] == pytest.approx(A2 * 0.2 * MU_P, rel=1e-12)
                assert out["Ty"] == pytest.approx(0.2 * MU_P, rel=1e-12)
                assert out["Mz"] == pytest.approx(0.0, abs=1e-9)
    with Instance(path, "bad", initialise=False) as b:
        with pytest.raises(FMICallException):
            b.set("method", "euler")  # refused at once, and held
        with pytest.raises(FMICallException):
            b.initialise()
        assert any("method = 'euler' is invalid" in m for _, m in b.messages), b.messages
        b.set("method", "full")  # not initialised: a parameter may still be corrected
        b.initialise()
        assert b.step(1e-4) == OK


def test_full_body_fmu_state_with_lateral_dynamics_repeats_bit_for_bit():
    """The full body FMU steps Eqs. (10)-(11) compiled (stepper.c's vector step), keeping
    its Newton matrix from step to step: the FMU state holds it, so get state, step, set
    state, step again repeats the outputs bit for bit, here and through bytes in a fresh
    instance."""
    from contact_fmu.fmu.config import ModelConfig

    path = fmu_build.build(ModelConfig.full("body"), OUT).path
    with Instance(path, "a", {"h_max": 5e-5}) as a, Instance(path, "b") as b:
        a.set("Fx_ex", 0.2 * MU_P)
        a.set("Fy_ex", 0.3 * MU_P)
        a.set("Mz_ex", 0.01 * MU_P * ex.Rx)
        steps(a, 5, 1e-4)
        state = a.get_state()
        steps(a, 3, 1e-4)
        first = a.outputs()
        assert first["Omega_z"] != 0.0 and first["Vy"] != 0.0
        a.set_state(state)
        steps(a, 3, 1e-4)
        assert a.outputs() == first
        b.set_state(b.deserialize_state(a.serialize_state(state), state[1]))
        steps(b, 3, 1e-4)
        assert b.outputs() == first


def _lateral_history(kind: str, t: float) -> dict[str, float]:
    """Loads of the lateral extremes at time t (s), in units of mu P (and mu P Rx)."""
    on = 5e-4 <= t < 2.5e-3
    return {
        "beyond": {"Fy_ex": 1.2 * on * MU_P},
        "combined": {"Fx_ex": 0.7 * MU_P * min(t / 1e-3, 1.0),
                     "My_ex": -0.7 * MU_P * ex.Rx * min(t / 1e-3, 1.0),
                     "Fy_ex": 0.7 * MU_P * min(t / 1e-3, 1.0)},
        "yaw": {"Fy_ex": 0.3 * MU_P, "Mz_ex": (0.05 if on else -0.1) * MU_P * ex.contact().a1},
        "reversal": {"Fx_ex": -0.75 * MU_P, "Fy_ex": 0.2 * MU_P},
    }[kind]  # fmt: skip


@pytest.mark.parametrize("method", ["full", "quasistationary"])
@pytest.mark.parametrize("kind", ["beyond", "combined", "yaw", "reversal"])
def test_full_body_fmu_lateral_extremes(kind, method):
    """The full body FMU (Eqs. 8-11, the law with spin, the compiled vector step) through
    fmpy at its edges, both methods: a lateral force of 1.2 mu P for 2 ms (gross sliding
    sideways, then rolling again), Tx and Fy_ex each at 0.7 mu P (|T| = 0.99 mu P),
    yaw-moment steps, and Vx through zero under a lateral force (at 2 ms, a
    communication point). Every doStep OK, every output finite, |T| <= mu P to rounding
    (16 eps), and the power of the creep forces on the rigid slip of Eq. (3), Tx vx +
    Ty vy + Mz Omega_z, never negative beyond the stage tolerance (100 SOLVE_RTOL mu P
    v_s, as the stiff suite's dissipation check)."""
    from contact_fmu.dynamics.solvers import SOLVE_RTOL
    from contact_fmu.fmu.config import ModelConfig

    path = fmu_build.build(ModelConfig.full("body"), OUT).path
    h = 1e-5
    V0 = 0.3 if kind == "reversal" else ex.speed_unit()
    starts = {"h_max": h / 4, "Vx0": V0, "Iy": ex.M * ex.Rx**2 / 2,
              "method": method}  # fmt: skip
    cfs = ex.contact().creep_full_slip
    with Instance(path, f"{kind}_{method}", starts) as b:
        b.set("P", ex.P)
        for k in range(400):
            for name, value in _lateral_history(kind, k * h).items():
                b.set(name, value)
            assert b.step(h) == OK, b.messages[-1:]
            o = b.outputs()
            assert all(math.isfinite(v) for v in o.values() if isinstance(v, float))
            assert math.hypot(o["Tx"], o["Ty"]) <= MU_P * (1 + 16 * np.finfo(float).eps)
            power = o["Tx"] * o["vx"] + o["Ty"] * o["vy"] + o["Mz"] * o["Omega_z"]
            vs = cfs * max(abs(o["Vx"]), 1e-9)
            assert power >= -100 * SOLVE_RTOL * MU_P * vs, (k, power)
        if kind == "reversal":
            assert o["Vx"] < -0.2  # through zero and backwards
        assert all(s < FATAL for s, _ in b.messages)
