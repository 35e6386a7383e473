"""The native contact FMU with a spin input (``--native --full contact``): the strip march
of the thin-layer law on its spin grid, built in C for each load (model.c, cf_model_grid), and
the forward-mode derivative of that march behind its directional derivatives
(stepper.c, cf_march_jacobian), against the pythonfmu FMU and central differences."""

from __future__ import annotations

import math
import shutil
from pathlib import Path

import numpy as np
import pytest
from test_native_fmu import central_differences

import fmu_build
from contact_fmu import examples as ex
from contact_fmu.fmu.config import ModelConfig
from contact_fmu.fmu.variables import RATE_MAX, SPEED_MAX
from contact_fmu.scenario.instance import DISCARD, ERROR, OK, Instance
from fmu_build import native_fmu

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "out" / "fmu"
MU_P = ex.mu * ex.P
LAW = ex.contact()

pytestmark = pytest.mark.skipif(shutil.which("cc") is None, reason="no C compiler")


@pytest.fixture(scope="module")
def fmus() -> dict[str, Path]:
    cfg = ModelConfig.full("contact")
    return {"native": native_fmu.build(cfg, OUT).path, "pythonfmu": fmu_build.build(cfg, OUT).path}


def _inputs(rng: np.random.Generator, k: int) -> dict[str, float]:
    """A random input of the force element: both rolling directions and standstill (every
    tenth), creepages from adhesion to beyond full slip, spin creepage phi a1/|Vx| of
    the same size (or no spin, every fourth), loads about the examples'."""
    Vx = 0.0 if k % 10 == 0 else float(rng.choice([-1.0, 1.0]) * 10 ** rng.uniform(-1, 1.3))
    V = max(abs(Vx), 1.0)
    size = 10 ** rng.uniform(-1.5, 0.7) * LAW.creep_full_slip
    xi = rng.uniform(-1.0, 1.0, 3) * size
    return {
        "P": float(rng.uniform(0.5, 1.5) * ex.P),
        "Vx": Vx,
        "Vy": float(xi[1] * V),
        "Omega_y": float((Vx - xi[0] * V) / ex.Rx),
        "Omega_z": 0.0 if k % 4 == 3 else float(xi[2] * V / LAW.a1),
    }


def test_full_contact_fmu_with_spin_gives_the_pythonfmu_outputs(fmus):
    """60 random inputs (spin, lateral slip, standstill, a new load each time, mu tuned
    half way): the native FMU's outputs are the pythonfmu FMU's within 1e-12 of each
    output's scale (the march's sums run in another order than numpy's; C's hypot and
    sqrt against numpy's complex abs), the same doubles without spin and lateral slip
    (the same closed form), and every force within the Coulomb bound |T| <= mu P
    (Eq. 35 integrated over the contact)."""
    runs = {}
    for target, path in fmus.items():
        rng = np.random.default_rng(18)
        rows = []
        with Instance(path, target) as c:
            for k in range(60):
                if k == 30:
                    c.set("mu", 0.2)  # tunable: the law and its spin grid follow it
                u = _inputs(rng, k)
                for name, value in u.items():
                    c.set(name, value)
                rows.append((u | {"mu": c.get("mu")}, c.outputs()))
        runs[target] = rows
    native, python = runs["native"], runs["pythonfmu"]
    names = [n for n in python[0][1] if n != "regime"]
    spinning = sum(u["Omega_z"] != 0.0 for u, _ in python)
    assert spinning >= 40 and any(u["Vx"] == 0.0 and u["Omega_z"] for u, _ in python)
    for name in names:
        x = np.array([o[name] for _, o in native])
        y = np.array([o[name] for _, o in python])
        assert np.max(np.abs(x - y)) <= 1e-12 * np.max(np.abs(y)), name
    for (u, a), (_, b) in zip(native, python, strict=True):
        assert a["regime"] == b["regime"]
        if u["Omega_z"] == 0.0 and u["Vy"] == 0.0:
            assert a == b
        assert math.hypot(a["Tx"], a["Ty"]) <= u["mu"] * u["P"] * (1 + 1e-12)


@pytest.mark.parametrize("target", ["native", "pythonfmu"])
def test_spin_forces_are_the_compiled_laws_doubles(fmus, target, monkeypatch):
    """Where the same C runs: LayerContact.forces in this process marches its spin grid
    (numpy's thin_layer._Grid) with the compiled library (cf_layer_forces). The native FMU
    marches the grid it built in C (cf_grid_build) for each load; the pythonfmu FMU
    carries the library (fmu_build.compiles) and its law calls it, loaded from the FMU's
    own resources. Rolling inputs with spin, a new load each time: the same doubles (so
    the native FMU's grids are numpy's bit for bit), and numpy's march (what the
    pythonfmu FMU ran without the library) within the bounds of
    test_strip_march_of_the_spin_law_agrees_to_rounding (7e-13 of mu P, of mu P
    max(a1, a2) for Mz). The native FMU is fmpy-valid and declares its directional
    derivatives."""
    import sys

    import fmpy
    from fmpy.validation import validate_fmu

    from contact_fmu import native
    from contact_fmu.laws.thin_layer import LayerContact

    if native.library() is None:
        pytest.skip("no compiled library")
    if target == "native":
        assert validate_fmu(str(fmus["native"])) == []
        md = fmpy.read_model_description(str(fmus["native"]))
        assert md.coSimulation.providesDirectionalDerivative
    rng = np.random.default_rng(4)
    rows = []
    with Instance(fmus[target], "c") as c:
        par = {n: c.get(n) for n in ("P", "Rx", "Ry", "k1", "k2", "kb", "ks", "mu")}
        for k in range(40):
            u = _inputs(rng, k)
            if u["Vx"] == 0.0 or u["Omega_z"] == 0.0:
                continue
            for name, value in u.items():
                c.set(name, value)
            law = LayerContact(**(par | {"P": u["P"]}))
            vx, vy = u["Vx"] - u["Omega_y"] * par["Rx"], u["Vy"]
            got = (c.get("Tx"), c.get("Ty"), c.get("Mz"))
            assert got == law.forces(vx, vy, u["Omega_z"], u["Vx"])
            rows.append((law, (vx, vy, u["Omega_z"], u["Vx"]), got))
        if target == "pythonfmu":  # the library the FMU's law called: its own copy
            package = fmu_build.build(ModelConfig.full("contact"), OUT).package
            lib = sys.modules[f"{package}.native"]._LOADED["stepper"]
            lib = None if lib is None else Path(lib._name)  # not the user's cache's
            assert lib is not None and lib.parts[-3:-1] == (package, "native"), lib
    assert len(rows) >= 20
    monkeypatch.setattr(native, "_LOADED", {"stepper": None})  # numpy's march
    for law, v, got in rows:
        F = law.mu * law.P
        scale = (F, F, F * max(law.a1, law.a2))
        for a, b, s in zip(got, law.forces(*v), scale, strict=True):
            assert abs(a - b) <= 7e-13 * s


@pytest.mark.parametrize("target", ["native", "pythonfmu"])
def test_bad_spin_input_is_refused_naming_it_and_the_instance_recovers(fmus, target):
    """Omega_z = NaN, inf or a huge finite 1e308 (beyond its physical range RATE_MAX =
    1e7 rad/s; there the march's increments Omega_z a1 dx/(|Vx| k) overflow into an
    output NaN): fmi2Error at setReal and at getReal of the outputs, fmi2Discard at
    doStep, each naming Omega_z and the value. At the bound itself, the saturated
    sliding field of a pure spin (|T| <= mu P, every node slides). Corrected, the
    instance gives a fresh instance's doubles."""
    from fmpy.fmi1 import FMICallException

    u = {"Vx": 5.0, "Vy": 0.002, "Omega_y": (5.0 - 0.003) / ex.Rx, "Omega_z": 0.8}
    with Instance(fmus[target], "fresh") as fresh:
        for name, value in u.items():
            fresh.set(name, value)
        want = fresh.outputs()
    with Instance(fmus[target], "bad") as c:
        for name, value in u.items():
            c.set(name, value)
        for value, text, must in (
            (math.nan, "nan", "finite"),
            (-math.inf, "-inf", "finite"),
            (1e308, "1e+308", "<= 1e+07"),
            (-1e308, "-1e+308", ">= -1e+07"),
        ):
            with pytest.raises(FMICallException) as e:
                c.set("Omega_z", value)
            said = f"Omega_z = {text} is invalid: must be {must}"
            assert e.value.status == ERROR and said in c.messages[-1][1]
            with pytest.raises(FMICallException) as e:
                c.get("Tx")
            assert e.value.status == ERROR and said in c.messages[-1][1]
            assert c.step(1e-3) == DISCARD and said in c.messages[-1][1]
        c.set("Omega_z", RATE_MAX)
        out = c.outputs()
        assert all(math.isfinite(v) for v in out.values())
        assert math.hypot(out["Tx"], out["Ty"]) <= MU_P * (1 + 1e-12)
        assert out["adhesion"] == 0.0  # every node slides
        c.set("Omega_z", u["Omega_z"])
        assert c.outputs() == want
        assert c.step(1e-3) == OK and c.outputs() == want


@pytest.mark.parametrize("target", ["native", "pythonfmu"])
def test_kinematic_inputs_are_refused_beyond_their_physical_range(fmus, target):
    """Vx, Vy (|.| <= SPEED_MAX = 1e4 m/s), Omega_y, Omega_z (|.| <= RATE_MAX = 1e7 rad/s:
    the body mode's bounds, ranges.within_range): the model description declares the
    range, a value one ulp beyond answers fmi2Error naming the input and the value and
    doStep fmi2Discard, the bound itself is taken. Every corner of that box (each input
    at +- its bound, Vx also at 1 m/s and at standstill) gives finite forces within
    Coulomb's bound |T| <= mu P (Eq. 35 over the contact) and |Mz| <= mu P max(a1, a2)
    (|x tau_y - y tau_x| <= |r| |tau| within the ellipse)."""
    import fmpy
    from fmpy.fmi1 import FMICallException

    bound = {"Vx": SPEED_MAX, "Vy": SPEED_MAX, "Omega_y": RATE_MAX, "Omega_z": RATE_MAX}
    nominal = {"Vx": 5.0, "Vy": 0.0, "Omega_y": 5.0 / ex.Rx, "Omega_z": 0.0}
    md = {v.name: v for v in fmpy.read_model_description(str(fmus[target])).modelVariables}
    with Instance(fmus[target], "range") as c:
        for name, b in bound.items():
            assert (float(md[name].min), float(md[name].max)) == (-b, b), name
            for sign in (1.0, -1.0):
                beyond = sign * math.nextafter(b, math.inf)
                with pytest.raises(FMICallException) as e:
                    c.set(name, beyond)
                said = f"{name} = {beyond!r} is invalid: must be "
                assert e.value.status == ERROR and said in c.messages[-1][1], c.messages[-1]
                assert c.step(1e-3) == DISCARD and said in c.messages[-1][1]
                c.set(name, sign * b)
                assert c.step(1e-3) == OK
            c.set(name, nominal[name])
        corners = 0
        for Vx in (SPEED_MAX, -SPEED_MAX, 1.0, 0.0):
            for sy, so, sz in np.ndindex(2, 2, 2):
                u = {"Vx": Vx, "Vy": (-1) ** sy * SPEED_MAX, "Omega_y": (-1) ** so * RATE_MAX,
                     "Omega_z": (-1) ** sz * RATE_MAX}  # fmt: skip
                for name, value in u.items():
                    c.set(name, value)
                out = c.outputs()
                assert all(math.isfinite(v) for v in out.values()), (u, out)
                assert math.hypot(out["Tx"], out["Ty"]) <= MU_P * (1 + 1e-12), (u, out)
                assert abs(out["Mz"]) <= MU_P * max(out["a1"], out["a2"]), (u, out)
                corners += 1
        assert corners == 32


def test_directional_derivatives_with_spin_are_central_differences_of_the_outputs(fmus):
    """d(Tx, Ty, Mz)/d(Vx, Vy, Omega_y, Omega_z) of the native FMU (the closed form's
    partials plus the strip march differentiated in forward mode) against central
    differences of its own outputs at 24 random points, 8 each in adhesion, partial slip
    and full slip (creepages 0.05, 0.6 and 3 of the onset of full slip, spin creepage of
    the same size; a quarter without spin, where d/dOmega_z is the march's slope at 0).
    Step d = 1e-9 of the input's scale u (|Vx|, |Vx|/Rx, |Vx|/a1): truncation d^2 f'''
    is below 1e-17 of mu P/u; the outputs' rounding, about sqrt(3072) eps mu P (the
    march's nodes), divided by 2 d is 6e-6 mu P/u (bound 2e-5); the rounding of the slip
    vx = Vx - Omega_y Rx, 2 ulp of Vx against a step of 1e-9 |Vx|, changes the step by
    up to 4.4e-7 (bound 1e-6 of the difference). A kink of the march (a node at its
    adhesion limit within d) would add up to a strip's share of the slope: at these
    points none lies within the step (120 points measured: worst 0.1 of the bound). A
    combined direction is the sum of the single ones; vx and vy are exact."""
    rng = np.random.default_rng(7)
    outs = ("Tx", "Ty", "Mz")
    scale = {"Tx": MU_P, "Ty": MU_P, "Mz": MU_P * LAW.a1}
    with Instance(fmus["native"], "dd") as c:
        vr = {n: v.valueReference for n, v in c.vars.items()}
        zr = [vr[o] for o in outs]
        for k in range(24):
            Vx = float(rng.choice([-1.0, 1.0]) * 10 ** rng.uniform(-0.5, 1.3))
            size = (0.05, 0.6, 3.0)[k % 3] * LAW.creep_full_slip
            xi = rng.uniform(-1.0, 1.0, 3) * size
            u = {
                "Vx": Vx,
                "Vy": float(xi[1] * abs(Vx)),
                "Omega_y": float((Vx - xi[0] * abs(Vx)) / ex.Rx),
                "Omega_z": 0.0 if k % 4 == 3 else float(xi[2] * abs(Vx) / LAW.a1),
            }
            for name, value in u.items():
                c.set(name, value)
            unit = {"Vx": abs(Vx), "Vy": abs(Vx), "Omega_y": abs(Vx) / ex.Rx,
                    "Omega_z": abs(Vx) / LAW.a1}  # fmt: skip
            grads = {}
            for name in u:
                got = c.fmu.getDirectionalDerivative(zr, [vr[name]], [1.0])
                grads[name] = got
                diff = central_differences(c, name, u[name], 1e-9 * unit[name])
                for o, g in zip(outs, got, strict=True):
                    fd = diff[o]
                    tol = 2e-5 * scale[o] / unit[name] + 1e-6 * abs(fd)
                    assert abs(g - fd) <= tol, (k, o, name, g, fd, u)
            both = c.fmu.getDirectionalDerivative(zr, [vr["Vx"], vr["Omega_z"]], [2.0, -3.0])
            for i, o in enumerate(outs):
                want = 2.0 * grads["Vx"][i] - 3.0 * grads["Omega_z"][i]
                assert abs(both[i] - want) <= 1e-12 * (abs(want) + scale[o] / unit["Vx"])
            slip = c.fmu.getDirectionalDerivative(
                [vr["vx"], vr["vy"]], [vr["Omega_y"], vr["Vy"], vr["Omega_z"]], [1.0, 1.0, 1.0]
            )
            assert slip == [-ex.Rx, 1.0]


def test_a_tuned_mu_rebuilds_the_spin_grid_of_the_body_path():
    """mu is tunable and the spin grid's capacities are mu p (Eq. 35): the grid is
    keyed on the law it is for (a1, a2, p0, mu, kb + ks), not on the load alone. The
    cornering scene (Eqs. 10-11) with mu tuned from 0.3 to 0.15 half way: the native
    FMU's outputs are the pythonfmu FMU's doubles (the adhesion to 1e-12: numpy sums
    its grid in another order), as they are without the tuning (a grid kept for the
    old mu gave an adhesion 0.85 against 0.70)."""
    from contact_fmu.scenario import load, runner

    scene = load(ROOT / "scenarios" / "cornering.toml")
    case = scene.cases[0]
    table = runner.input_table(scene, case)
    starts = runner.start_values(scene, case)
    got = []
    for path in (native_fmu.build(scene.config, OUT).path, fmu_build.build(scene.config, OUT).path):
        with Instance(path, "mu", starts) as inst:
            for k in range(60):
                if k == 30:
                    inst.set("mu", 0.5 * inst.get("mu"))
                for name in scene.inputs:
                    inst.set(name, float(table[name][k]))
                assert inst.step(scene.step) == OK, inst.messages[-1:]
            got.append(inst.outputs())
    a, b = got
    assert abs(a.pop("adhesion") - b.pop("adhesion")) <= 1e-12
    assert a == b and a["Ty"] != 0.0


def test_a_vanishing_rolling_speed_with_spin_gives_finite_forces_on_both_fmus(fmus):
    """Vx = +-1e-300, +-5e-324 (subnormal), 1e-200 with spin and lateral slip (the strip
    march's gain 1/(|Vx| k) bounded, docs/model.md; it overflowed into "Tx = nan is not
    finite"): both FMUs answer OK with finite outputs, |T| <= mu P (Eq. 35 over the
    contact), the native FMU's outputs the pythonfmu FMU's within 1e-12 of each output's
    scale (as the random inputs above), and the native FMU's directional derivatives of
    (Tx, Ty, Mz) finite with a rigid slip (cf_march_jacobian with the bounded gain: not
    Vx's, the slip's; at v = 0 the closed form's creep slope mu P h'(0) c/|Vx| itself
    passes DBL_MAX for a subnormal Vx, and the FMU says so, fmi2Error)."""
    outs = ("Tx", "Ty", "Mz")
    runs = {}
    for target, path in fmus.items():
        rows = []
        with Instance(path, target) as c:
            vr = {n: v.valueReference for n, v in c.vars.items()}
            for Vx in (1e-300, -1e-300, 5e-324, -5e-324, 1e-200):
                for Vy, Oz, slip in ((0.0, 1.0, 0.0), (2e-3, 1.0, 1e-3), (-1e-3, -3.0, 0.0)):
                    u = {"Vx": Vx, "Vy": Vy, "Omega_y": (Vx - slip) / ex.Rx, "Omega_z": Oz}
                    for name, value in u.items():
                        c.set(name, value)
                    out = c.outputs()
                    assert all(math.isfinite(v) for v in out.values()), (u, out)
                    assert math.hypot(out["Tx"], out["Ty"]) <= MU_P * (1 + 1e-12), (u, out)
                    assert c.step(1e-3) == OK, c.messages[-1:]
                    if target == "native" and (Vy, slip) != (0.0, 0.0):
                        zr = [vr[o] for o in outs]
                        for name in u:
                            d = c.fmu.getDirectionalDerivative(zr, [vr[name]], [1.0])
                            assert all(math.isfinite(x) for x in d), (u, name, d)
                    rows.append(out)
        runs[target] = rows
    for name in runs["pythonfmu"][0]:
        if name == "regime":
            continue
        x = np.array([o[name] for o in runs["native"]])
        y = np.array([o[name] for o in runs["pythonfmu"]])
        assert np.max(np.abs(x - y)) <= 1e-12 * np.max(np.abs(y)), name
