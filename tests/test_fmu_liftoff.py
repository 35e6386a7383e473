"""Lift-off (P = 0) and two hostile legal calls, on both targets (pythonfmu and native).

- P = 0 is lift-off: no contact, zero tangential forces and moment, the body moves under
  the external loads alone (Eqs. 8-9 with T = 0: M dVx = Fx_ex h, Iy dOmega_y = My_ex h),
  and contact resumes with |T| <= mu P when P returns (docs/model.md, "Lift-off").
- mu below MU_MIN is refused at the setter on both targets (mu = 5e-324 was fmi2Fatal,
  ZeroDivisionError, on the pythonfmu FMU).
- fig13 with M = 1e-300: an OK step keeps the momentum balance (Omega_y jumped by 1.9e7
  times what mu P Rx h allows: the stiff stage dropped Vx's share of the slip's change).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from fmpy.fmi1 import FMICallException

import fmu_build
from contact_fmu.fmu import variables as fv
from contact_fmu.fmu.config import ModelConfig
from contact_fmu.scenario import load
from contact_fmu.scenario.instance import DISCARD, ERROR, OK, Instance

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "out" / "fmu"
TARGETS = ("pythonfmu", "native")


def build(target: str, model: str) -> Path:
    """The FMU of a scene (or "full-MODE": ModelConfig.full) for a target."""
    if model.startswith("full-"):
        cfg = ModelConfig.full(model[5:])
    else:
        cfg = load(ROOT / "scenarios" / f"{model}.toml").config
    if target == "native":
        from fmu_build import native_fmu

        return native_fmu.build(cfg, OUT).path
    return fmu_build.build(cfg, OUT).path


# body scenes: scalar layer (fig13, brake), table (rail_traction), vector path (full-body)
BODY = ("fig13", "brake", "rail_traction", "full-body")


@pytest.mark.parametrize("scene", BODY)
@pytest.mark.parametrize("target", TARGETS)
def test_lifted_body_moves_under_external_loads_and_returns_to_contact(target, scene):
    """P set to 0, stepped, set back: every step OK; at P = 0 no force and the free
    motion of Eqs. (8)-(9) with T = 0, M dVx = Fx_ex h and Iy dOmega_y = My_ex h to
    rounding (eps of the speeds: 1e-12 of the change); after, abs(T) <= mu P."""
    with Instance(build(target, scene), "lift") as b:
        M, Iy, mu = b.get("M"), b.get("Iy"), b.get("mu")
        # the loads the scene takes (a brake scene only its moment)
        Fx = 30.0 if "Fx_ex" in b.vars else 0.0
        My = -2.0 if "My_ex" in b.vars else 0.0
        h = 1e-3
        for name, value in (("Fx_ex", Fx), ("My_ex", My)):
            if name in b.vars:
                b.set(name, value)
        P0 = b.get("P")
        assert b.step(h) == OK
        b.set("P", 0.0)
        for _ in range(3):
            V0, O0 = b.get("Vx"), b.get("Omega_y")
            assert b.step(h) == OK, b.messages[-3:]
            out = b.outputs()
            assert out["Tx"] == 0.0 and out.get("Ty", 0.0) == 0.0 and out.get("Mz", 0.0) == 0.0
            assert out.get("a1", 0.0) == 0.0 and out.get("adhesion", 0.0) == 0.0
            dV, dO = out["Vx"] - V0, out["Omega_y"] - O0
            assert abs(M * dV - Fx * h) <= 1e-12 * abs(Fx * h) + 4e-16 * M * abs(V0)
            assert abs(Iy * dO - My * h) <= 1e-9 * abs(My * h) + 4e-16 * Iy * abs(O0) * 100
        for P in (1e-3, 1.0, P0):  # back into contact, gross sliding first
            b.set("P", P)
            for _ in range(3):
                assert b.step(h) == OK, b.messages[-3:]
                out = b.outputs()
                T = math.hypot(out["Tx"], out.get("Ty", 0.0))
                assert T <= mu * P * (1 + 1e-12), (P, out)
        assert all(s == OK for s, _ in b.messages), b.messages


@pytest.mark.parametrize("scene", ("full-contact", "rail_creep"))
@pytest.mark.parametrize("target", TARGETS)
def test_lifted_contact_element_gives_no_force(target, scene):
    """Contact mode at P = 0: Tx = Ty = Mz = 0 at any kinematics, the ellipse 0; P back:
    the law at the new load, abs(T) <= mu P."""
    with Instance(build(target, scene), "lift") as c:
        mu = c.get("mu")
        c.set("Omega_y", c.get("Vx") / c.get("Rx") * 0.9)  # 10 % creepage: full slip
        c.set("P", 0.0)
        assert c.step(1e-3) == OK
        out = c.outputs()
        served = [n for n in ("Tx", "Ty", "Mz", "a1", "a2", "p0", "adhesion") if n in out]
        assert "Tx" in served and all(out[n] == 0.0 for n in served), out
        c.set("P", 500.0)
        assert c.step(1e-3) == OK
        T = math.hypot(c.get("Tx"), c.get("Ty") if "Ty" in c.vars else 0.0)
        assert 0.99 * mu * 500.0 <= T <= mu * 500.0 * (1 + 1e-12)  # full slip: mu P


@pytest.mark.parametrize("target", TARGETS)
def test_scene_may_start_lifted(target):
    """A body that starts in the air (P = 0 at initialisation) initialises and steps."""
    with Instance(build(target, "fig13"), "air", start_values={"P": 0.0}) as b:
        assert b.get("Tx") == 0.0
        assert b.step(1e-3) == OK
        b.set("P", 1000.0)
        assert b.step(1e-3) == OK
        assert abs(b.get("Tx")) <= 300.0 * (1 + 1e-12)


@pytest.mark.parametrize("target", TARGETS)
def test_negative_load_is_refused_saying_lift_off_is_zero(target):
    """P < 0 is no load: the setter answers fmi2Error naming P and saying that lift-off
    is P = 0; the instance stays usable."""
    with Instance(build(target, "fig13"), "neg") as b:
        with pytest.raises(FMICallException) as e:
            b.set("P", -1.0)
        assert e.value.status == ERROR
        assert (
            "P = -1.0 is invalid: must be >= 0 (lift-off, no contact, is P = 0)"
            in (b.messages[-1][1])
        )
        b.set("P", 1000.0)
        assert b.step(1e-4) == OK


@pytest.mark.parametrize("scene", ("fig13", "brake"))
@pytest.mark.parametrize("target", TARGETS)
def test_friction_coefficient_below_its_minimum_is_an_error_not_fatal(target, scene):
    """mu = 5e-324 after a normal start was fmi2Fatal (ZeroDivisionError) on the
    pythonfmu FMU and OK on the native one: both refuse it at the setter (Error, named),
    and go on with the last good mu; MU_MIN itself is taken."""
    with Instance(build(target, scene), "mu") as b:
        assert b.step(1e-4) == OK
        with pytest.raises(FMICallException) as e:
            b.set("mu", 5e-324)
        assert e.value.status == ERROR
        assert f"mu = 5e-324 is invalid: must be >= {fv.MU_MIN:g}" in b.messages[-1][1]
        b.set("mu", 0.3)
        assert b.step(1e-4) == OK
        b.set("mu", fv.MU_MIN)
        assert b.step(1e-4) == OK
        assert abs(b.get("Tx")) <= fv.MU_MIN * b.get("P") * (1 + 1e-12)


@pytest.mark.parametrize("target", TARGETS)
def test_tiny_mass_keeps_the_momentum_balance(target):
    """fig13 with M = 1e-300 and the reported sequence of steps: Omega_y jumped from
    114.950 to 115.289 rad/s in a step of 1e-12 s after Fx_ex changed (the stiff stage
    took the slip's jump into Omega_y). The angular momentum balance of Eq. (9) over the
    step: Iy dOmega_y = (My_ex + Rx Tx) h with abs(Tx) <= mu P, to rounding of Omega_y
    (eps Vx/Rx)."""
    with Instance(build(target, "fig13"), "m", start_values={"M": 1e-300}) as b:
        t = 0.0
        for h in (1.75e-4, 4.03e-9, 1.75e-5, 1.75e-5):
            assert b.step(h, t) == OK
            t += h
        b.set("Fx_ex", -38.2284)
        O0, Iy, Rx, mu, P = (b.get(n) for n in ("Omega_y", "Iy", "Rx", "mu", "P"))
        My = b.get("My_ex")
        h = 1e-12
        assert b.step(h, 0.00021000403) == OK
        dO = b.get("Omega_y") - O0
        assert abs(Iy * dO - My * h) <= mu * P * Rx * h + Iy * 4e-16 * abs(O0) * 4
        assert abs(b.get("Tx")) <= mu * P


def test_transient_phase_refuses_lift_off_naming_it():
    """The transient phase's traction field lives on the contact ellipse: at P = 0 its
    step answers fmi2Discard (state unchanged, the steady phase takes lift-off), and the
    next step in contact is OK."""
    with Instance(build("pythonfmu", "fig12_transient"), "t") as b:
        assert b.step(1e-4) == OK
        before = b.outputs()
        b.set("P", 0.0)
        assert b.step(1e-4) == DISCARD
        assert "P = 0.0 is invalid: must be > 0 in the transient phase" in b.messages[-1][1]
        assert b.outputs() == before
        b.set("P", 1000.0)
        assert b.step(1e-4) == OK


def test_native_force_element_slopes_vanish_at_lift_off():
    """The native contact FMU's directional derivatives in the kinematics at P = 0: the
    forces are 0 at every Vx, Vy, Omega_y, so is every slope (the analytic form had
    mu P times an infinite beta per creepage: NaN, answered fmi2Error)."""
    with Instance(build("native", "full-contact"), "dd") as c:
        vr = {n: v.valueReference for n, v in c.vars.items()}
        c.set("Omega_y", 0.9 * c.get("Vx") / c.get("Rx"))
        c.set("P", 0.0)
        for name in ("Vx", "Vy", "Omega_y"):
            got = c.fmu.getDirectionalDerivative([vr["Tx"], vr["Ty"], vr["Mz"]], [vr[name]], [1.0])
            assert list(got) == [0.0, 0.0, 0.0]


def test_scene_may_ramp_its_load_from_zero(tmp_path):
    """A scene whose P ramps from 0 (the wheel set down) loads, builds and runs: at P = 0
    Tx = 0, then abs(Tx) <= mu P of the load held over each step."""
    from contact_fmu.scenario import runner

    text = (ROOT / "scenarios" / "liftoff.toml").read_text()
    start = text.index("P = [")
    end = text.index("]\n", start) + 2
    text = text[:start] + "P = { ramp = { start = 0.0, duration = 1.0e-3, height = 1000.0 } }\n"
    text += (ROOT / "scenarios" / "liftoff.toml").read_text()[end:]
    text = text.replace("stop_time = 5.0e-3", "stop_time = 2.0e-3")
    path = tmp_path / "setdown.toml"
    path.write_text(text.replace("references/", str(ROOT / "scenarios" / "references") + "/"))
    scene = load(path)
    (res,) = runner.simulate(fmu_build.build(scene.config, OUT).path, scene)
    assert res.error is None
    P = np.asarray(res.columns["P"], float)
    Tx = np.asarray(res.columns["Tx"], float)
    assert P[0] == 0.0 and Tx[0] == 0.0
    held = np.maximum(P, np.r_[P[:1], P[:-1]])  # the load of the step ending at t_k
    assert np.all(np.abs(Tx) <= 0.3 * held * (1 + 1e-12))
    assert np.max(np.abs(Tx)) == pytest.approx(300.0, rel=1e-12)  # sliding at full load
