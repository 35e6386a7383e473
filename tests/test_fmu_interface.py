"""The interface as a tool user expects it.

- Initial kinematics: the body starts from Vx0 and the initial rigid slip vx0 (Eq. 3),
  Omega_y0 = (Vx0 - vx0)/Rx; with vx0 = 0 (the default) a new Vx0 alone starts in pure
  rolling: no creepage, no force.
- mu is a tunable parameter: set between steps (a wet or contaminated patch), it gives
  the new Coulomb bound |T| = mu P in gross sliding, in contact mode at once (the force
  element's outputs follow) and in body mode from the next step; through fmpy's input
  table as a user drives it; FMU states carry it.
- Strict bounds: FMI's min is inclusive, so every variable whose lower bound is
  excluded says so in its description, and the FMU refuses the bound itself.
"""

from __future__ import annotations

from pathlib import Path

import fmpy
import numpy as np
import pytest

import fmu_build
from contact_fmu import examples as ex
from contact_fmu.fmu import variables as fv
from contact_fmu.fmu.config import ModelConfig
from contact_fmu.scenario import load
from contact_fmu.scenario.instance import DISCARD, ERROR, OK, Instance

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "out" / "fmu"
MU_P = ex.mu * ex.P


def _models(build) -> dict[str, Path]:
    """fig13, sweep and the full rigid_body model built by ``build`` (a target's build)."""
    return {
        "fig13": build(load(ROOT / "scenarios" / "fig13.toml").config, OUT).path,
        "sweep": build(load(ROOT / "scenarios" / "sweep.toml").config, OUT).path,
        "rigid": build(ModelConfig.full("rigid_body"), OUT).path,
    }


@pytest.fixture(scope="module")
def fmus() -> dict[str, Path]:
    return _models(fmu_build.build)


@pytest.fixture(scope="module")
def native_fmus() -> dict[str, Path]:
    """The same models as native C FMUs (fmu_build.native_fmu), from the same declarations."""
    from fmu_build import native_fmu

    return _models(native_fmu.build)


@pytest.fixture(params=["pythonfmu", "native"])
def both(request, fmus, native_fmus) -> dict[str, Path]:
    return fmus if request.param == "pythonfmu" else native_fmus


def test_strict_lower_bounds_are_stated_in_the_descriptions(fmus):
    for v in fv.VARIABLES:
        if v.open_min:
            assert f"(> {v.min:g}" in v.description, v.name
        else:
            assert "(> " not in v.description, v.name
    md = fmpy.read_model_description(str(fmus["fig13"]))
    for var in md.modelVariables:
        decl = fv.BY_NAME[var.name]
        if decl.open_min:  # min="0.0" in the file, "(> 0)" in the text; the FMU refuses 0
            assert float(var.min) == decl.min and "(> 0" in var.description
    with Instance(fmus["fig13"], "bound", initialise=False) as b:  # Rx: open at 0
        with pytest.raises(fmpy.fmi1.FMICallException) as e:
            b.set("Rx", 0.0)
        assert e.value.status == ERROR
        assert any("Rx = 0.0 is invalid: must be > 0" in m for _, m in b.messages)


@pytest.mark.parametrize("V0", [20.0, -3.0, 0.0])
def test_vx0_alone_starts_in_pure_rolling(both, V0):
    """Only Vx0 set: Omega_y = Vx0/Rx, no slip and no force, in the body FMU and in the
    rigid-body FMU; after 20 steps without loads the body still rolls (Tx = 0)."""
    with Instance(both["fig13"], "body", {"Vx0": V0, "Fx_ex": 0.0, "My_ex": 0.0}) as b:
        assert b.get("Omega_y") == V0 / ex.Rx and b.get("vx") == 0.0 and b.get("Tx") == 0.0
        for _ in range(20):
            assert b.step(1.75e-4) == OK
        assert b.get("Tx") == 0.0 and b.get("Vx") == V0 and b.get("xi_x") == 0.0
    with Instance(both["rigid"], "rigid", {"Vx0": V0}) as r:
        assert r.get("Omega_y") == V0 / ex.Rx


def test_vx0_sets_the_initial_creepage(both):
    """vx0 = 0.01 Vx0: xi_x = 0.01 at the start, Omega_y0 = (Vx0 - vx0)/Rx (Eq. 3)."""
    V0 = ex.speed_unit()
    with Instance(both["fig13"], "slip", {"vx0": 0.01 * V0}) as b:
        assert b.get("xi_x") == pytest.approx(0.01, rel=1e-14)
        assert b.get("Omega_y") == (V0 - 0.01 * V0) / ex.Rx


def test_mu_step_in_contact_mode_gives_the_new_coulomb_bound(both):
    """Gross sliding (Omega_y = 0, xi = 1): |Tx| = mu P; mu from 0.3 to 0.1 between steps
    changes the outputs at once (direct feedthrough), then back."""
    md = fmpy.read_model_description(str(both["sweep"]))
    mu = next(v for v in md.modelVariables if v.name == "mu")
    assert (mu.causality, mu.variability) == ("parameter", "tunable")
    locked = {"P": ex.P, "Vx": ex.speed_unit(), "Omega_y": 0.0}
    with Instance(both["sweep"], "c", locked) as c:
        assert c.step(1e-3) == OK
        assert abs(c.get("Tx")) == pytest.approx(MU_P, rel=1e-12)
        c.set("mu", 0.1)
        assert abs(c.get("Tx")) == pytest.approx(0.1 * ex.P, rel=1e-12)
        assert c.step(1e-3) == OK and abs(c.get("Tx")) == pytest.approx(0.1 * ex.P, rel=1e-12)
        try:  # refused: held, the steps discarded until corrected (the pythonfmu FMU
            c.set("mu", -0.1)  # also answers fmi2Error at the setter, the native one OK)
        except fmpy.fmi1.FMICallException as e:
            assert e.status == ERROR
        assert c.step(1e-3) == DISCARD
        c.set("mu", 0.3)
        assert c.step(1e-3) == OK and abs(c.get("Tx")) == pytest.approx(MU_P, rel=1e-12)


def test_mu_step_in_body_mode_through_fmpy_input(both):
    """fig13's body braked beyond its capacity (My_ex = -2 mu P Rx: the demanded Tx,
    A1 2 mu P = 1.5 mu P, exceeds mu P) slides with Tx = -mu P; mu stepped from 0.3 to
    0.15 at 2 ms in fmpy's input table (as a user drives a wet patch) gives Tx =
    -0.15 P from the next step on, and back to -0.3 P after 4 ms."""
    t_in = [0.0, 2e-3, 2e-3, 4e-3, 4e-3]
    mu = [0.3, 0.3, 0.15, 0.15, 0.3]
    table = np.array(
        [(t, ex.P, 0.0, -2.0 * MU_P * ex.Rx, m) for t, m in zip(t_in, mu, strict=True)],
        dtype=[(n, float) for n in ("time", "P", "Fx_ex", "My_ex", "mu")],
    )
    h = 1.75e-4
    res = fmpy.simulate_fmu(str(both["fig13"]), input=table, output=["Tx", "regime"],
                            stop_time=40 * h, output_interval=h)  # fmt: skip
    t, Tx = res["time"], res["Tx"]
    sliding = res["regime"] == 1
    assert sliding[(t > 1e-3)].all()
    before, wet, after = (t > 1e-3) & (t < 2e-3), (t > 2.2e-3) & (t < 4e-3), t > 4.2e-3
    assert np.allclose(Tx[before], MU_P, rtol=1e-12)
    assert np.allclose(Tx[wet], 0.15 * ex.P, rtol=1e-12)
    assert np.allclose(Tx[after], MU_P, rtol=1e-12)
    assert wet.sum() >= 9 and after.sum() >= 5


def test_fmu_state_carries_mu(both):
    """A state taken at mu = 0.3, mu then tuned to 0.15 and stepped: setting the state
    brings mu = 0.3 back, and the next step repeats the untuned one bit for bit."""
    brake = {"Fx_ex": 0.0, "My_ex": -2.0 * MU_P * ex.Rx}
    with Instance(both["fig13"], "s", brake) as b:
        for _ in range(10):
            assert b.step(1.75e-4) == OK
        state = b.get_state()
        assert b.step(1.75e-4) == OK
        expected = b.outputs()
        b.set_state(state)
        b.set("mu", 0.15)
        assert b.step(1.75e-4) == OK and b.outputs() != expected
        b.set_state(state)
        assert b.get("mu") == 0.3
        assert b.step(1.75e-4) == OK and b.outputs() == expected
        b.free_state(state)


def test_state_taken_after_mu_is_lowered_is_restored(both):
    """A master's rollback across a wet patch: mu lowered while the body slides at
    Tx = -0.3 P, the state taken before the next step (its outputs still at the old
    bound), a step, the state set again: accepted (the bound of the outputs' own mu),
    and the step repeats bit for bit with Tx = -0.15 P."""
    brake = {"Fx_ex": 0.0, "My_ex": -2.0 * MU_P * ex.Rx}
    with Instance(both["fig13"], "rollback", brake) as b:
        for _ in range(10):
            assert b.step(1.75e-4) == OK
        b.set("mu", 0.15)
        state = b.get_state()
        assert abs(b.get("Tx")) == pytest.approx(MU_P, rel=1e-12)  # computed at mu = 0.3
        assert b.step(1.75e-4) == OK
        first = b.outputs()
        b.set_state(state)
        assert b.step(1.75e-4) == OK and b.outputs() == first
        assert abs(first["Tx"]) == pytest.approx(0.15 * ex.P, rel=1e-12)
        b.free_state(state)


def test_mu_is_fixed_where_the_model_does_not_take_it(fmus):
    """A fixed parameter (M) set after initialisation is refused with fmi2Error; mu is
    the only tunable one."""
    assert [v.name for v in fv.VARIABLES if v.tunable] == ["mu"]
    with Instance(fmus["fig13"], "fixed") as b:
        with pytest.raises(fmpy.fmi1.FMICallException) as e:
            b.set("M", 2.0)
        assert e.value.status == ERROR
        assert b.step(1e-4) == OK


def test_mu_step_in_the_half_space_contact_fmu():
    """The half-space table is normalised by mu P (Kalker's similarity in mu): at gross
    sliding (xi = 1) a step of mu from 0.3 to 0.15 halves Tx exactly (the table's value
    at xi = 1, 0.9999992 mu P, scaled) and keeps abs(Tx) <= mu P."""
    path = fmu_build.build(load(ROOT / "scenarios" / "rail_creep.toml").config, OUT).path
    sliding = {"P": 100e3, "Vx": 30.0, "Vy": 0.0, "Omega_y": 0.0}
    with Instance(path, "rail", sliding) as c:
        assert c.step(1e-3) == OK
        dry = c.get("Tx")
        c.set("mu", 0.15)
        wet = c.get("Tx")
        assert wet == pytest.approx(0.5 * dry, rel=1e-12)
        assert 0.999 * 0.15 * 100e3 <= abs(wet) <= 0.15 * 100e3
