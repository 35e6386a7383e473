"""Regression tests of the FMUs under hostile input, broken hosts and damaged states.

Each test is one failure seen when the built FMUs were driven call by call through
fmpy's low-level API, as an importer's test bench would: a crash, fmi2Fatal where the
standard wants fmi2Error, a silent fmi2OK, stale or wrong outputs served as fmi2OK. What
may crash the process runs in a subprocess, so that a crash fails the test instead of
ending the run.
"""

from __future__ import annotations

import math
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import fmpy
import pytest
from fmpy.fmi1 import FMICallException

import fmu_build
from contact_fmu import examples as ex
from contact_fmu.fmu.config import ModelConfig
from contact_fmu.scenario import load
from contact_fmu.scenario.instance import DISCARD, ERROR, OK, Instance

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "out" / "fmu"
MU_P = ex.mu * ex.P
WARNING = 1


def scene_fmu(name: str) -> Path:
    return fmu_build.build(load(ROOT / "scenarios" / f"{name}.toml").config, OUT).path


def full_fmu(mode: str) -> Path:
    return fmu_build.build(ModelConfig.full(mode), OUT).path


def run_isolated(code: str) -> subprocess.CompletedProcess:
    """``code`` in a fresh interpreter (a crash is its exit status, not ours)."""
    return subprocess.run(
        [sys.executable, "-c", textwrap.dedent(code)],
        capture_output=True,
        text=True,
        timeout=120,
        cwd=ROOT,
    )


@pytest.mark.parametrize(
    ("scene", "name", "value"),
    [("fig13", "My_ex", 6e306), ("fig13", "Fx_ex", 1.2e308), ("brake", "My_ex", 6e306)],
)
def test_huge_finite_load_is_discarded_not_a_segfault(scene, name, value):
    """The compiled thin-layer march segfaulted on a huge finite load; loads beyond
    integrator.LOAD_LIMIT mu P are now refused at the step, naming the input."""
    proc = run_isolated(
        f"""
        from contact_fmu.scenario.instance import Instance
        with Instance({str(scene_fmu(scene))!r}, "huge") as b:
            b.set({name!r}, {value!r})
            print(b.step(1e-4), b.messages[-1][1])
            b.set({name!r}, 0.0)
            print(b.step(1e-4))
        """
    )
    assert proc.returncode == 0, proc.stderr[-2000:]
    first, second = proc.stdout.splitlines()[-2:]
    assert first.startswith(f"{DISCARD} ") and f"{name} = {value!r} is invalid" in first
    assert second == str(OK)


def test_momentum_balance_holds_or_the_moment_is_refused():
    """fig13 with My_ex = 1e20 answered OK with Vx from 5.6 to 8.0 m/s in 1e-4 s (the
    balance allows mu P h/M = 0.03 m/s)."""
    h = 1e-4
    with Instance(scene_fmu("fig13"), "balance") as b:
        V0, Fx = b.get("Vx"), b.get("Fx_ex")
        b.set("My_ex", 1e20)
        assert b.step(h) == DISCARD
        assert b.get("Vx") == V0
        b.set("My_ex", 1e3)  # 67 mu P Rx: gross sliding, balance kept
        assert b.step(h) == OK
        # Eq. (8): M dVx = (Fx_ex - Tx) h with abs(Tx) <= mu P; LOAD_LIMIT's rounding
        assert abs(ex.M * (b.get("Vx") - V0) - Fx * h) <= MU_P * h * (1 + 1e-5)


@pytest.mark.parametrize("scene", ["fig13", "rail_traction"])
def test_a_step_that_spins_the_body_beyond_its_range_is_discarded(scene):
    """A moment within LOAD_LIMIT held for a long step spun a wheel up to 2.5e10 rad/s;
    there the (Vx, vx) state resolves Vx only to 2e-6 m/s, and the balance failed by
    that much. Speeds and rates beyond their declared ranges are refused."""
    with Instance(scene_fmu(scene), "spin") as b:
        before = b.outputs()
        b.set("My_ex", 1e10)  # within LOAD_LIMIT mu P Rx for both
        assert b.step(1.0) == DISCARD
        assert "Omega_y = " in b.messages[-1][1] and "within abs <= 1e+07" in b.messages[-1][1]
        assert b.outputs() == before


def test_every_declared_input_of_every_full_fmu_works_with_non_zero_values():
    """The full contact FMU logged FileNotFoundError (native/stepper.c, not carried by
    a contact FMU) for Omega_z != 0 and kept old outputs: every input, non-zero."""
    values = {"P": 900.0, "Fx_ex": 0.1 * MU_P, "Fy_ex": 0.1 * MU_P, "My_ex": -0.01,
              "Mz_ex": 1e-4, "Vx": 5.0, "Vy": 0.002, "Omega_y": 99.9, "Omega_z": 0.5,
              "Tx": 10.0}  # fmt: skip
    for mode in ("body", "contact", "rigid_body"):
        with Instance(full_fmu(mode), mode) as b:
            inputs = [n for n, v in b.vars.items() if v.causality == "input"]
            assert inputs
            for n in inputs:
                b.set(n, values[n])
            assert b.step(1e-4) == OK, b.messages
            out = b.outputs()
            assert all(math.isfinite(v) for v in out.values()), out
            assert all(s == OK for s, _ in b.messages), b.messages
            if "Tx" in out:
                assert math.hypot(out["Tx"], out.get("Ty", 0.0)) <= 0.3 * 900.0 * (1 + 1e-12)


@pytest.mark.parametrize(("name", "value"), [("Vx", 1.797e308), ("P", 5e-324)])
def test_contact_outputs_that_cannot_be_computed_are_an_error_not_stale(name, value):
    """rail_creep served the previous outputs with OK after FloatingPointError (Vx =
    1.797e308) or ZeroDivisionError (P = 5e-324); they break abs(T) <= mu P for the
    new load. Now getReal answers fmi2Error until the inputs admit outputs again."""
    with Instance(scene_fmu("rail_creep"), "stale") as c:
        good = c.get(name)
        c.get("Tx")
        try:
            c.set(name, value)
        except FMICallException as e:  # a value outside the declared range
            assert e.status == ERROR
        with pytest.raises(FMICallException) as e:
            c.get("Tx")
        assert e.value.status == ERROR
        assert "no outputs for the current inputs" in c.messages[-1][1]
        c.set(name, good)
        assert math.isfinite(c.get("Tx"))


def test_transient_field_keeps_coulomb_bound_after_the_load_falls():
    """fig12_transient answered abs(T) = 1.008 mu P with OK in gross sliding after P fell
    from 1000 to 10 N: the strips' rule no longer integrated the new pressure."""
    with Instance(scene_fmu("fig12_transient"), "bound", {"nx": 16, "ny": 8}) as b:
        b.set("Fx_ex", 2000.0)  # beyond mu P: gross sliding
        for P in (1000.0, 500.0, 100.0, 10.0):
            b.set("P", P)
            for _ in range(5):
                assert b.step(2e-5) == OK
                T = math.hypot(b.get("Tx"), b.get("Ty"))
                assert T <= ex.mu * P * (1 + 1e-12), (P, T / (ex.mu * P))


def test_communication_point_is_checked_in_ulps_of_t_not_in_h():
    """After a step of 1e6 s, a point 5e-4 s off was accepted (tolerance 1e-9 h)."""
    with Instance(scene_fmu("fig13"), "time") as b:
        b.set("Fx_ex", 0.0)  # free rolling: the body stays in its range for 1e6 s
        b.set("My_ex", 0.0)
        assert b.step(1e6) in (OK, WARNING)
        assert b.step(1e-4, time=1e6 + 5e-4) == DISCARD
        assert "currentCommunicationPoint" in b.messages[-1][1]
        t = 1e6 + math.ulp(1e6)  # a master's rounding of the same time
        assert b.step(1e-4, time=t) == OK


def test_infinite_communication_point_is_discarded_on_the_compiled_path():
    """t = inf passed the compiled path's check (inf <= rtol inf) and stepped with OK."""
    with Instance(scene_fmu("fig13"), "inf") as b:
        assert b.step(1e-4) == OK  # the compiled step is in place
        assert b.step(1e-4, time=math.inf) == DISCARD
        assert b.step(1e-4) == OK


def test_a_refused_value_is_not_returned_with_ok():
    """getReal of an input whose NaN was refused returned the NaN with fmi2OK."""
    with Instance(scene_fmu("fig13"), "held") as b:
        with pytest.raises(FMICallException):
            b.set("P", math.nan)
        with pytest.raises(FMICallException) as e:
            b.get("P")
        assert e.value.status == ERROR and "P = nan is invalid" in b.messages[-1][1]
        b.set("P", ex.P)
        assert b.get("P") == ex.P and b.step(1e-4) == OK


def test_transient_grid_has_a_declared_maximum():
    """ny = 2147483647 (a legal Integer >= 2) allocated until the kernel killed the
    process; nx and ny are declared with a maximum and refused beyond it."""
    with Instance(scene_fmu("fig12_transient"), "grid", initialise=False) as b:
        for name, value in (("ny", 2147483647), ("nx", 1025)):
            with pytest.raises(FMICallException) as e:
                b.set(name, value)
            assert e.value.status == ERROR and f"{name} = {value}" in b.messages[-1][1]


def test_internal_step_cap_answers_warning():
    """One doStep capped at MAX_SUBSTEPS internal steps answered fmi2OK with only a
    logged note while the accuracy it promised (h_max) was not kept."""
    with Instance(scene_fmu("fig13"), "cap", {"h_max": 1e-6}) as b:
        status = b.fmu.fmi2DoStep(b.fmu.component, 0.0, 0.1, 1)
        assert status == WARNING
        assert b.messages[-1][0] == WARNING and "internal steps" in b.messages[-1][1]


def test_doStep_before_initialisation_is_an_error():
    with Instance(scene_fmu("fig13"), "early", initialise=False) as b:
        assert b.step(1e-4) == ERROR
        assert "fmi2ExitInitializationMode not called" in b.messages[-1][1]


# (FMU, inputs set before one doStep, output compared): the body FMU's compiled step;
# the contact FMU's law with spin, whose strip march runs in the library
FALLBACK = {
    "fig13": ({"Fx_ex": 100.0}, "Tx"),
    "full_contact": ({"Vy": 0.01, "Omega_y": 112.0, "Omega_z": 0.7}, "Tx"),
}


@pytest.mark.parametrize("kind", FALLBACK)
def test_compiled_library_that_cannot_load_falls_back_to_python_with_a_warning(tmp_path, kind):
    """A damaged compiled stepper and C core (or ones needing a newer C library) killed
    the FMU; now the Python path takes over, with a warning at initialisation. The Python path
    gives the compiled one's doubles for the body step (module docstring of
    contact_fmu.native), and for the spin law's strip march the same to the bounds of
    tests/test_native.py (7e-13 of mu P: the march's sums in another order)."""
    path = scene_fmu("fig13") if kind == "fig13" else full_fmu("contact")
    inputs, out = FALLBACK[kind]
    fmpy.extract(str(path), str(tmp_path))
    libs = list(tmp_path.glob("resources/cfmu_*/native/_stepper_*.so"))
    cores = list(tmp_path.glob("resources/cfmu_*/native/_core.so"))  # fmu/slave_core.py
    assert libs and cores
    for lib in (libs[0], cores[0]):
        lib.write_bytes(b"not an ELF file")
    runs = []
    for unzip in (tmp_path, None):  # one process each: the two share the FMU's modules
        proc = run_isolated(
            f"""
            from contact_fmu.scenario.instance import Instance
            with Instance({str(path)!r}, "b", unzip_dir={str(unzip) if unzip else None!r}) as b:
                for k, v in {inputs!r}.items():
                    b.set(k, v)
                print(b.step(1.75e-4), repr(b.get({out!r})))
                print([m for m in b.messages if m[0] == 1])
            """
        )
        assert proc.returncode == 0, proc.stderr[-2000:]
        runs.append(proc.stdout.splitlines()[-2:])
    (broken, warnings), (good, none) = runs
    assert "cannot be loaded" in warnings and "runs in Python" in warnings
    assert none == "[]"
    (s1, t1), (s2, t2) = (line.split() for line in (broken, good))
    assert s1 == s2 == "0"
    if kind == "fig13":
        assert t1 == t2
    else:
        assert float(t1) != 0.0 and abs(float(t1) - float(t2)) <= 7e-13 * MU_P


@pytest.mark.parametrize("core", ["1", "0"])
def test_host_without_scipy_fails_loudly(core):
    """A host Python without scipy answered OK at initialisation and Discard at the
    first doStep (fmpy simulate then exited 0 with two rows). The FMU's C core needs no
    scipy: with it the FMU simulates; on its Python path (CONTACT_FMU_CORE=0) it fails
    loudly."""
    proc = run_isolated(
        f"""
        import os, sys
        os.environ["CONTACT_FMU_CORE"] = {core!r}
        sys.modules["scipy"] = None  # a host environment without scipy
        import fmpy
        try:
            fmpy.simulate_fmu({str(scene_fmu("fig13"))!r}, stop_time=1e-3,
                              output_interval=1e-4)
            print("simulated")
        except Exception as e:
            print("raised", type(e).__name__, e)
        """
    )
    assert proc.returncode == 0, proc.stderr[-2000:]
    expected = "simulated" if core == "1" else "raised"
    assert proc.stdout.splitlines()[-1].startswith(expected), proc.stdout


def test_own_state_with_a_bad_input_into_an_instance_of_other_parameters():
    """A state holding an invalid input (P = -1) set into an instance whose parameters
    differ answered fmi2Fatal; a state with spin likewise. Now they restore."""
    path = full_fmu("contact")
    with Instance(path, "a") as a, Instance(path, "b", {"mu": 0.5}) as b:
        a.set("Omega_z", 0.5)
        assert a.step(1e-4) == OK
        spin = a.serialize_state(a.get_state())
        with pytest.raises(FMICallException):
            a.set("P", -1.0)
        bad = a.serialize_state(a.get_state())
        for data in (spin, bad):
            b.set_state(b.deserialize_state(data, a.time))
            assert b.get("mu") == ex.mu
        with pytest.raises(FMICallException):  # P = -1 is held: no outputs
            b.get("Tx")
        b.set("P", ex.P)
        b.set_state(b.deserialize_state(spin, a.time))
        assert b.step(1e-4, time=a.time) == OK and math.isfinite(b.get("Tx"))


@pytest.mark.skipif(shutil.which("objdump") is None, reason="no objdump")
def test_fmu_binary_needs_no_c_library_newer_than_pythonfmus():
    """The FMU's Linux binary (the status shim) needs glibc 2.17 at most (dlopen and
    dlsym bound to their oldest versions); pythonfmu's own binary, which it loads,
    sets the FMU's floor at 2.32 (RHEL/Rocky 9 has 2.34)."""
    from test_native import GLIBC_FLOOR, glibc_needed

    with Instance(scene_fmu("fig13"), "glibc") as b:
        shim = next((b.dir / "binaries" / "linux64").glob("*.so"))
        inner = b.dir / "resources" / fmu_build.INNER
        assert (2, 2) <= glibc_needed(shim) <= GLIBC_FLOOR
        assert glibc_needed(inner) <= (2, 34)
