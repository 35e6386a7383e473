"""An independent engine: libcosim (Open Simulation Platform) runs the same FMUs.

1. The Fig. 13 and cornering scenes' FMUs under libcosim give fmpy's numbers (within
   1e-9).
2. A contact-mode FMU and a separate rigid-body FMU (Eqs. 8-9), connected through
   libcosim (Vx, Omega_y -> contact; Tx -> body), reproduce the body-mode FMU.

Why the coupled run needs small steps. libcosim's fixed-step algorithm exchanges
values between steps, so the body integrates with the creep force of the previous
exchange: the slip equation M A2 dvx/dt = -Tx(vx) + ... is integrated explicitly, with
a delay of one step. Linearised (Tx = k vx, relaxation time tau = M A2 / k, a = h/tau)
the slip obeys x_{n+1} = x_n - a x_{n-1}: both roots of z^2 - z + a lie inside the
unit circle only for a < 1. Here tau = M A2 |Vx| / (dT/dxi) = 0.25 x 5.64 / 1.02e5 =
1.4e-5 s (eta = 3, Vx0 = Rx/T_c, dT/dxi >= 0.93 dT/dxi(0) at Tx = 0.21 mu P), so
h = 2e-6 s (a = 0.15) is stable and accurate, and h = 1.6e-5 s (a > 1) is not. The
body-mode FMU has no such limit: it solves the stiff slip implicitly inside the FMU.
"""

from __future__ import annotations

from pathlib import Path

import fmpy
import numpy as np
import pytest
from fmpy.validation import validate_fmu
from libcosimpy.CosimEnums import CosimVariableType
from libcosimpy.CosimExecution import CosimExecution
from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
from libcosimpy.CosimManipulator import CosimManipulator
from libcosimpy.CosimObserver import CosimObserver
from libcosimpy.CosimSlave import CosimLocalSlave

import fmu_build
from contact_fmu import examples as ex
from contact_fmu.fmu.config import ModelConfig
from contact_fmu.scenario import load, runner

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "out" / "fmu"
F = ex.force_unit()
IY = ex.M * ex.Rx**2 / 3.0  # eta = 3
MY = -0.1 * F * ex.Rx  # constant moment: Tx -> A2 F - A1 My/Rx = 0.325 F
T_END = 1.0e-3  # s: 70 relaxation times


def ns(seconds: float) -> int:
    return int(round(seconds * 1e9))


def references(execution: CosimExecution, slave: int) -> dict[str, int]:
    return {v.name.decode(): v.reference for v in execution.slave_variables(slave)}


@pytest.fixture(scope="module", autouse=True)
def quiet():
    log_output_level(CosimLogLevel.ERROR)


@pytest.mark.parametrize(("name", "case_name"), [("fig13", "eta = 3"), ("cornering", "cornering")])
def test_libcosim_matches_fmpy_on_the_scene(name, case_name):
    """The scene's FMU under libcosim against fmpy, 60 steps: Fig. 13 (the compiled
    doStep) and cornering (Eqs. 10-11, the compiled vector step with its kept Newton
    matrix; the lateral force steps at 0.5 ms, step 25)."""
    scene = load(ROOT / "scenarios" / f"{name}.toml")
    fmu = fmu_build.build(scene.config, OUT).path
    case = scene.case(case_name)
    n = 60
    assert ns(scene.step) * 1e-9 == scene.step  # libcosim counts integer nanoseconds

    execution = CosimExecution.from_step_size(step_size=ns(scene.step))
    slave = execution.add_local_slave(CosimLocalSlave(fmu_path=str(fmu), instance_name=name))
    vr = references(execution, slave)
    for name, value in runner.start_values(scene, case).items():
        assert execution.real_initial_value(slave, vr[name], float(value))
    observer = CosimObserver.create_last_value()
    execution.add_observer(observer)
    override = CosimManipulator.create_override()  # drives the inputs step by step
    execution.add_manipulator(override)
    table = runner.input_table(scene, case)
    reals = [o for o in scene.outputs if o != "regime"]
    got, regime = [], []
    for k in range(n):
        override.slave_real_values(
            slave, [vr[i] for i in scene.inputs], [float(table[i][k]) for i in scene.inputs]
        )
        assert execution.step()
        got.append(observer.last_real_values(slave, [vr[o] for o in reals]))
        regime.append(observer.last_integer_values(slave, [vr["regime"]])[0])

    (fmpy_result,) = [r for r in runner.simulate(fmu, scene) if r.case == case.name]
    expected = np.array([fmpy_result.columns[o][1 : n + 1] for o in reals]).T
    assert np.max(np.abs(np.array(got) - expected)) <= 1e-9
    assert regime == list(fmpy_result.columns["regime"][1 : n + 1].astype(int))


@pytest.fixture(scope="module")
def coupled_fmus() -> tuple[Path, Path]:
    contact = fmu_build.build(ModelConfig.full("contact"), OUT).path
    body = fmu_build.build(ModelConfig.full("rigid_body"), OUT).path
    return contact, body


def coupled(fmus: tuple[Path, Path], h: float) -> dict[str, np.ndarray]:
    """Contact FMU + rigid-body FMU through libcosim connections, step h (s)."""
    contact_fmu, body_fmu = fmus
    n = int(round(T_END / h))
    execution = CosimExecution.from_step_size(step_size=ns(h))
    c = execution.add_local_slave(CosimLocalSlave(fmu_path=str(contact_fmu), instance_name="c"))
    b = execution.add_local_slave(CosimLocalSlave(fmu_path=str(body_fmu), instance_name="b"))
    vc, vb = references(execution, c), references(execution, b)
    for name, value in (("Iy", IY), ("Fx_ex", F), ("My_ex", MY)):
        assert execution.real_initial_value(b, vb[name], value)
    execution.connect_real_variables(b, vb["Vx"], c, vc["Vx"])
    execution.connect_real_variables(b, vb["Omega_y"], c, vc["Omega_y"])
    execution.connect_real_variables(c, vc["Tx"], b, vb["Tx"])
    observer = CosimObserver.create_time_series()
    execution.add_observer(observer)
    series = [(c, vc["Tx"], "Tx"), (b, vb["Vx"], "Vx"), (b, vb["Omega_y"], "Omega_y")]
    for slave, ref, _ in series:
        observer.start_time_series(slave, ref, CosimVariableType.REAL)
    assert execution.simulate_until(target_time=ns(T_END))
    out = {}
    for slave, ref, name in series:
        t, _, values = observer.time_series_real_samples(slave, ref, from_step=1, sample_count=n)
        out["time"], out[name] = np.array(t) * 1e-9, np.array(values)
    assert out["time"].size == n
    return out


@pytest.fixture(scope="module")
def body_mode() -> np.ndarray:
    """The body-mode FMU (the stiff slip solved inside) under the same loads, via fmpy.

    h_max = 2.5e-7 s: its own error, (4/3)|y(h_max) - y(h_max/2)|, is 1e-7 N in Tx after
    the transient and 2e-8 m/s in Vx, far below what is compared here.
    """
    cfg = ModelConfig(
        name="cosim_body", mode="body", inputs=("P", "Fx_ex", "My_ex"),
        outputs=("Tx", "Vx", "Omega_y"), starts={"Iy": IY, "h_max": 2.5e-7},
    )  # fmt: skip
    fmu = fmu_build.build(cfg, OUT).path
    assert validate_fmu(str(fmu)) == []  # every FMU the project builds validates
    loads = np.array(
        [(0.0, ex.P, F, MY)],
        dtype=[("time", float), ("P", float), ("Fx_ex", float), ("My_ex", float)],
    )
    return fmpy.simulate_fmu(str(fmu), input=loads, output=["Tx", "Vx", "Omega_y"],
                             stop_time=T_END, output_interval=1e-6)  # fmt: skip


def errors(run: dict[str, np.ndarray], body_mode: np.ndarray) -> dict[str, float]:
    """test_system.errors of a run that carries its own times."""
    from test_system import errors as errors_at

    return errors_at(run["time"], run, body_mode)


def test_contact_and_body_fmus_coupled_in_libcosim_reproduce_the_body_mode(coupled_fmus, body_mode):
    e2 = errors(coupled(coupled_fmus, 2e-6), body_mode)
    e1 = errors(coupled(coupled_fmus, 1e-6), body_mode)
    # Rolling after the transient (t >= 0.5 ms = 35 tau): the coupled steady state is the
    # body mode's (constant Tx: the one-step delay changes nothing); what remains is the
    # transient's tail, exp(-35) x 62 N < 1e-13 N, and the body-mode FMU's own 1e-7 N.
    assert e2["Tx_late"] <= 1e-6 and e1["Tx_late"] <= 1e-6
    # During the slip transient the explicit coupling lags by O(h): the differences
    # halve with h (first order), i.e. vanish as the coupling step shrinks.
    for key in ("Tx", "Vx", "Omega_y"):
        assert 1.6 <= e2[key] / e1[key] <= 2.5, (key, e2[key], e1[key])
    # and at h = 1e-6 s they are small against the force and speed scales
    assert e1["Tx"] < 0.03 * ex.mu * ex.P and e1["Vx"] < 1e-4


def test_explicit_coupling_beyond_the_relaxation_time_is_unstable(coupled_fmus, body_mode):
    """h = 1.6e-5 s > tau: the exchanged creep force oscillates instead of settling."""
    e = errors(coupled(coupled_fmus, 1.6e-5), body_mode)
    assert e["Tx_late"] > 10.0  # N; the stable runs above agree to 1e-6 N
