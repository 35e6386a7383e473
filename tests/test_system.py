"""`contact-fmu system`: a scene's body as a contact-mode and a rigid_body-mode FMU,
written as an SSP 1.0 file and as libcosim's OspSystemStructure.xml, run as written by
fmpy (``fmpy.ssp.simulation.simulate_ssp``) and libcosim
(``CosimExecution.from_osp_config_file``).

The system is the coupling of tests/test_cosim_libcosim.py: Fig. 13's parameters with
eta = 3, Fx_ex = F = mu p0 a1 a2 and My_ex = -0.1 F Rx held. Its expectations hold here:
the explicit coupling lags the body-mode FMU (the stiff slip solved inside) by O(h) in
the slip transient and agrees once the slip has relaxed. The step is chosen by the
writer from the slip relaxation time tau = M A2 |Vx| / (dTx/dxi) = 1.38e-5 s (that
test's estimate, 1.4e-5 s): the power of ten at or below tau/5, 1e-6 s.
"""

from __future__ import annotations

import json
import math
import subprocess
import sys
import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path

import fmpy
import numpy as np
import pytest
from fmpy.ssp.simulation import simulate_ssp
from libcosimpy.CosimEnums import CosimVariableType
from libcosimpy.CosimExecution import CosimExecution
from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
from libcosimpy.CosimObserver import CosimObserver

import fmu_build
from contact_fmu import cli
from contact_fmu import examples as ex
from contact_fmu.dynamics.body import Body
from contact_fmu.dynamics.coupling import creep_slope, relaxation_time
from contact_fmu.fmu.config import ModelConfig
from contact_fmu.scenario import load
from fmu_build import system

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "out" / "fmu"
F = ex.force_unit()
IY = ex.M * ex.Rx**2 / 3.0  # eta = 3
MY = -0.1 * F * ex.Rx
T_END = 1.0e-3  # s: 70 relaxation times


@pytest.fixture(scope="module")
def made(tmp_path_factory) -> system.System:
    scene = load(ROOT / "scenarios" / "fig13.toml")
    folder = tmp_path_factory.mktemp("system")
    return system.write(scene, scene.case("eta = 3"), folder, None, {"My_ex": MY}, OUT)


@pytest.fixture(scope="module")
def body_mode() -> np.ndarray:
    """The body-mode FMU under the same loads (as in test_cosim_libcosim.py)."""
    cfg = ModelConfig(
        name="cosim_body", mode="body", inputs=("P", "Fx_ex", "My_ex"),
        outputs=("Tx", "Vx", "Omega_y"), starts={"Iy": IY, "h_max": 2.5e-7},
    )  # fmt: skip
    fmu = fmu_build.build(cfg, OUT).path
    loads = np.array(
        [(0.0, ex.P, F, MY)],
        dtype=[("time", float), ("P", float), ("Fx_ex", float), ("My_ex", float)],
    )
    return fmpy.simulate_fmu(str(fmu), input=loads, output=["Tx", "Vx", "Omega_y"],
                             stop_time=T_END, output_interval=1e-6)  # fmt: skip


def errors(t, run, body_mode) -> dict[str, float]:
    """The largest differences of a coupled run's Tx, Vx and Omega_y at the times t from
    the body-mode FMU's, interpolated (Tx_late: from 5e-4 s, after the start)."""
    ref = {k: np.interp(t, body_mode["time"], body_mode[k]) for k in ("Tx", "Vx", "Omega_y")}
    late = t >= 5e-4
    return {
        "Tx": float(np.max(np.abs(run["Tx"] - ref["Tx"]))),
        "Tx_late": float(np.max(np.abs(run["Tx"] - ref["Tx"])[late])),
        "Vx": float(np.max(np.abs(run["Vx"] - ref["Vx"]))),
        "Omega_y": float(np.max(np.abs(run["Omega_y"] - ref["Omega_y"]))),
    }


def check_coupling(e: dict[str, float]) -> None:
    """test_cosim_libcosim's expectations at h = 1e-6 s: after the transient (t >= 35
    tau) the coupled steady state is the body mode's (the transient's tail exp(-35) x
    62 N < 1e-13 N, the body-mode FMU's own error 1e-7 N); during it the lag is small
    against the force and speed scales."""
    assert e["Tx_late"] <= 1e-6, e
    assert e["Tx"] < 0.03 * ex.mu * ex.P and e["Vx"] < 1e-4, e


@pytest.fixture(scope="module")
def made_native(tmp_path_factory) -> system.System:
    """The same system of native (C) FMUs (``contact-fmu system --native``)."""
    scene = load(ROOT / "scenarios" / "fig13.toml")
    folder = tmp_path_factory.mktemp("system_native")
    return system.write(scene, scene.case("eta = 3"), folder, None, {"My_ex": MY}, OUT, True)


# libcosim in a child process: a libcosim that cannot read a system file ends the
# process (it did on an SSD without a step), which must fail one test, not end pytest
LIBCOSIM_SSP = """
import json, sys
from libcosimpy.CosimEnums import CosimVariableType
from libcosimpy.CosimExecution import CosimExecution
from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
from libcosimpy.CosimObserver import CosimObserver

log_output_level(CosimLogLevel.ERROR)
path, t_end = sys.argv[1], int(sys.argv[2])
execution = CosimExecution.from_ssp_file(path)  # the step from the file
c = execution.slave_index_from_instance_name("contact")
b = execution.slave_index_from_instance_name("body")
ref = {s: {v.name.decode(): v.reference for v in execution.slave_variables(s)} for s in (c, b)}
observer = CosimObserver.create_time_series()
execution.add_observer(observer)
series = [(c, "Tx"), (b, "Vx"), (b, "Omega_y")]
for s, name in series:
    observer.start_time_series(s, ref[s][name], CosimVariableType.REAL)
ok = execution.simulate_until(target_time=t_end)
out = {"ok": ok}
for s, name in series:
    t, _, values = observer.time_series_real_samples(s, ref[s][name], from_step=1,
                                                     sample_count=10**6)
    out["time"], out[name] = [x * 1e-9 for x in t], list(values)
print(json.dumps(out))
"""


def libcosim_ssp_run(ssp: Path) -> dict[str, np.ndarray]:
    """libcosim's from_ssp_file on ``ssp`` until T_END, in a child process."""
    done = subprocess.run(
        [sys.executable, "-c", LIBCOSIM_SSP, str(ssp), str(round(T_END * 1e9))],
        capture_output=True, text=True, timeout=600, cwd=ssp.parent,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr[-2000:]
    out = json.loads(done.stdout.strip().splitlines()[-1])
    assert out.pop("ok")
    return {k: np.array(v) for k, v in out.items()}


def test_step_follows_the_slip_relaxation_time(made):
    assert made.tau == pytest.approx(1.38e-5, rel=0.01)
    assert made.step == 1e-6
    assert made.ssp.is_file() and made.osp.is_file()


def test_fmpy_runs_the_ssp_as_written(made, body_mode):
    res = simulate_ssp(str(made.ssp), stop_time=T_END, step_size=made.step)
    # a row holds the time at the start of its step and the values at its end
    t = res["time"] + made.step
    run = {"Tx": res["contact.Tx"], "Vx": res["body.Vx"], "Omega_y": res["body.Omega_y"]}
    assert t.size == 1000
    check_coupling(errors(t, run, body_mode))


def osp_run(made) -> dict[str, np.ndarray]:
    log_output_level(CosimLogLevel.ERROR)
    execution = CosimExecution.from_osp_config_file(str(made.osp))
    assert execution.num_slaves() == 2
    c = execution.slave_index_from_instance_name("contact")
    b = execution.slave_index_from_instance_name("body")
    ref = {
        slave: {v.name.decode(): v.reference for v in execution.slave_variables(slave)}
        for slave in (c, b)
    }
    observer = CosimObserver.create_time_series()
    execution.add_observer(observer)
    series = [(c, "Tx"), (b, "Vx"), (b, "Omega_y")]
    for slave, name in series:
        observer.start_time_series(slave, ref[slave][name], CosimVariableType.REAL)
    assert execution.simulate_until(target_time=round(T_END * 1e9))
    n = round(T_END / made.step)
    out = {}
    for slave, name in series:
        t, _, values = observer.time_series_real_samples(
            slave, ref[slave][name], from_step=1, sample_count=n
        )
        out["time"], out[name] = np.array(t) * 1e-9, np.array(values)
    assert out["time"].size == n
    return out


def test_libcosim_runs_the_osp_file_as_written(made, body_mode):
    run = osp_run(made)
    check_coupling(errors(run["time"], run, body_mode))
    # both masters exchange once per step: the same sequence of numbers
    res = simulate_ssp(str(made.ssp), stop_time=T_END, step_size=made.step)
    assert np.max(np.abs(run["Tx"] - res["contact.Tx"])) <= 1e-9 * ex.mu * ex.P


def test_system_files_carry_the_scene_values(made):
    ssd = fmpy.ssp.ssd.read_ssd(str(made.ssp))  # validated against the SSP 1.0 schema
    (binding,) = ssd.system.parameterBindings
    values = {p.name: float(p.value) for p in binding.parameterValues[0].parameters}
    assert values["body.Iy"] == IY and values["contact.mu"] == ex.mu
    assert {(a.startElement, a.startConnector, a.endElement, a.endConnector)
            for a in ssd.system.connections} == {
        ("body", "Vx", "contact", "Vx"), ("body", "Omega_y", "contact", "Omega_y"),
        ("contact", "Tx", "body", "Tx")}  # fmt: skip
    for comp, fmu in made.fmus.items():  # the FMUs start from the same values
        md = fmpy.read_model_description(str(fmu))
        starts = {v.name: v.start for v in md.modelVariables if v.start is not None}
        for name, value in values.items():
            if name.startswith(comp + "."):
                assert float(starts[name.split(".", 1)[1]]) == value, name
        assert fmpy.validation.validate_fmu(str(fmu)) == []
    body = fmpy.read_model_description(str(made.fmus["body"]))
    held = {v.name: float(v.start) for v in body.modelVariables if v.name in ("Fx_ex", "My_ex")}
    assert held == {"Fx_ex": F, "My_ex": MY}


def test_creep_slope_by_difference_matches_the_closed_form():
    """dTx/dxi at zero creep of the thin layers, (8/3) a1^2 a2/(kb + ks): the central
    difference (for laws without a closed form) agrees to 1e-6. Tx is odd in vx with a
    vx |vx| term, so the difference's error is first order in the creepage: 1.2e-5 at
    xi = 1e-7 (measured), 1.2e-8 at FD_CREEP = 1e-10; rounding adds eps-relative."""
    law = ex.contact()

    class NoSlope:
        def forces(self, *a):
            return law.forces(*a)

    Vx = ex.speed_unit()
    assert creep_slope(NoSlope(), Vx) == pytest.approx(law.creep_slope, rel=1e-6)
    tau = relaxation_time(law, Body(M=ex.M, Rx=ex.Rx, Iy=IY), Vx)
    assert tau == pytest.approx(ex.M * 0.25 * Vx / law.creep_slope, rel=1e-15)
    assert relaxation_time(law, Body(M=ex.M, Rx=ex.Rx, Iy=IY), 0.0) == 0.0
    assert math.isfinite(tau)


def test_system_command(tmp_path, capsys):
    scene = str(ROOT / "scenarios" / "fig13.toml")
    args = ["system", scene, "--case", "eta = 3", "--set", f"My_ex={MY!r}",
            "--out", str(tmp_path), "--fmu-out", str(OUT)]  # fmt: skip
    assert cli.main(args) == 0
    out = capsys.readouterr().out
    for name in ("fig13_contact.fmu", "fig13_body.fmu", "fig13.ssp", "OspSystemStructure.xml"):
        assert f"wrote {tmp_path / 'fig13' / name}" in out
        assert (tmp_path / "fig13" / name).is_file()
    # fmpy takes no step from the file: the command says which to pass
    assert "step_size=1e-06" in out and "stop_time=" in out
    # My_ex of Fig. 13 is a sine: a system file cannot carry it
    assert cli.main(["system", scene, "--out", str(tmp_path)]) == 1
    err = capsys.readouterr().err
    assert "My_ex" in err and "--set My_ex=VALUE" in err
    # a scene with lateral parts has no planar coupling
    assert cli.main(["system", str(ROOT / "scenarios" / "cornering.toml")]) == 1
    assert "planar body-mode scene" in capsys.readouterr().err


def test_the_ssp_carries_the_step_for_osp_tools(made):
    """SSP 1.0 has no step of its own: OSP's annotation of the DefaultExperiment holds
    it (libcosim reads baseStepSize), beside the scene's stop time."""
    with zipfile.ZipFile(made.ssp) as z:
        root = ET.fromstring(z.read("SystemStructure.ssd"))
    ns = {"ssd": system.SSD, "ssc": system.SSC, "osp": system.OSP_SSP}
    exp = root.find("ssd:DefaultExperiment", ns)
    assert float(exp.get("stopTime")) == made.stop_time
    (note,) = exp.findall("ssd:Annotations/ssc:Annotation", ns)
    assert note.get("type") == "com.opensimulationplatform"
    (fixed,) = note.findall("osp:Algorithm/osp:FixedStepAlgorithm", ns)
    assert float(fixed.get("baseStepSize")) == made.step == 1e-6


@pytest.mark.parametrize("which", ["pythonfmu", "native"])
def test_libcosim_runs_the_ssp_as_written(which, made, made_native, body_mode):
    """libcosim's SSP reader with the step from the file: the coupling's expectations
    (check_coupling) and, exchanging once per step as fmpy does, fmpy's numbers."""
    m = made if which == "pythonfmu" else made_native
    run = libcosim_ssp_run(m.ssp)
    assert run["time"].size == round(T_END / m.step)
    assert run["time"][1] - run["time"][0] == pytest.approx(m.step, rel=1e-9)
    check_coupling(errors(run["time"], run, body_mode))
    res = simulate_ssp(str(m.ssp), stop_time=T_END, step_size=m.step)
    assert np.max(np.abs(run["Tx"] - res["contact.Tx"])) <= 1e-9 * ex.mu * ex.P


def test_fmpy_runs_the_native_ssp(made_native, body_mode):
    """The native pair in fmpy, at the step the command prints: the same coupling."""
    assert made_native.step == 1e-6
    assert all(p.name.endswith("_native.fmu") for p in made_native.fmus.values())
    for fmu in made_native.fmus.values():
        md = fmpy.read_model_description(str(fmu))
        assert md.coSimulation.modelIdentifier.endswith("_native")
    res = simulate_ssp(str(made_native.ssp), stop_time=T_END, step_size=made_native.step)
    t = res["time"] + made_native.step
    run = {"Tx": res["contact.Tx"], "Vx": res["body.Vx"], "Omega_y": res["body.Omega_y"]}
    check_coupling(errors(t, run, body_mode))
