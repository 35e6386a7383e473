"""The integrator scheme as an FMU string parameter: declared only where offered, honoured."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import pytest

import fmu_build
from contact_fmu import examples as ex
from contact_fmu._validate import InputError
from contact_fmu.dynamics import integrator
from contact_fmu.dynamics.body import Loads
from contact_fmu.dynamics.integrator import RollingBody
from contact_fmu.fmu import config as fc
from contact_fmu.scenario import load
from contact_fmu.scenario.instance import OK, Instance

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "out" / "fmu"


def test_config_offers_the_integrators_schemes():
    """config.SCHEMES duplicates integrator.SCHEMES (config must not import the integrator)."""
    assert fc.SCHEMES == integrator.SCHEMES


def test_scheme_parameter_exists_only_with_two_schemes():
    cfg = load(ROOT / "scenarios" / "fig13.toml").config
    assert "scheme" not in {v.name for v in cfg.variables}
    both = dataclasses.replace(cfg, schemes=fc.SCHEMES)
    assert "scheme" in {v.name for v in both.variables}
    assert "scheme" in {v.name for v in fc.ModelConfig.full("body").variables}


def test_unknown_scheme_is_refused_naming_it():
    cfg = load(ROOT / "scenarios" / "fig13.toml").config
    with pytest.raises(InputError) as e:
        dataclasses.replace(cfg, schemes=("euler",))
    assert e.value.name == "scheme" and "one of" in str(e.value)
    with pytest.raises(InputError) as e:
        dataclasses.replace(cfg, schemes=fc.SCHEMES, starts={**cfg.starts, "scheme": "rk4"})
    assert e.value.name == "scheme"


@pytest.fixture(scope="module")
def fmu() -> Path:
    cfg = load(ROOT / "scenarios" / "fig13.toml").config
    return fmu_build.build(dataclasses.replace(cfg, schemes=fc.SCHEMES), OUT).path


@pytest.mark.parametrize("scheme", fc.SCHEMES)
def test_fmu_runs_the_chosen_scheme_as_the_core_does(fmu, scheme):
    """Ten communication steps of 1.75e-4 s (4 internal steps each) after the loads are
    applied to a freely rolling body: at every step the FMU's Tx and vx equal the core
    stepper's with the same scheme to 1e-12 relative (the same floating-point operations;
    rounding only). The two schemes differ by more than 1e-6 during the slip transient
    (their stability functions differ at h/tau_r ~ 3), so the parameter is not ignored."""
    F = ex.force_unit()
    loads = Loads(F, 0.0, -0.1 * F * ex.Rx, 0.0)
    h, n, steps = 1.75e-4, 4, 10
    cores: dict[str, list[dict[str, float]]] = {}
    for s in fc.SCHEMES:
        rb = RollingBody(
            ex.contact(), ex.body(3.0), Vx0=ex.speed_unit(), Omega_y0=ex.speed_unit() / ex.Rx,
            scheme=s,
        )  # fmt: skip
        cores[s] = []
        for _ in range(steps):
            rb.advance(h, loads, n)
            cores[s].append(rb.outputs())
    got = []
    with Instance(fmu, "scheme", {"scheme": scheme, "h_max": h / n}) as inst:
        inst.set("Fx_ex", loads.Fx_ex)
        inst.set("My_ex", loads.My_ex)
        for _ in range(steps):
            assert inst.step(h) == OK
            got.append({k: inst.get(k) for k in ("Tx", "vx")})
        assert inst.get("scheme") == scheme
    other = next(s for s in fc.SCHEMES if s != scheme)
    for k, scale in (("Tx", ex.mu * ex.P), ("vx", ex.speed_unit() * 0.01)):
        own = [abs(g[k] - c[k]) for g, c in zip(got, cores[scheme], strict=True)]
        apart = [abs(a[k] - b[k]) for a, b in zip(cores[other], cores[scheme], strict=True)]
        assert max(own) <= 1e-12 * scale
        assert max(apart) > 1e-6 * scale
