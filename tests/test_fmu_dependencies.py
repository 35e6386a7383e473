"""Declared dependencies checked by perturbation.

FMI 2.0 ModelStructure/Outputs lists, for each output, the inputs it depends on
directly: a master that couples FMUs orders its calls (and finds algebraic loops) from
these lists, so an output that follows an input it does not declare is read stale, with
no error. For every kind of FMU (pythonfmu and native; body, contact and rigid_body,
each full variant: every variable, Eqs. 10-11) this sets each input away from an
operating point and reads every output again without a step: whatever moves must be
declared as depending on that input.

An output that depends on no input is a function of the state and the parameters only,
so reading it twice with nothing but an undeclared input changed is the same
computation twice: exact equality is the test (any difference is a dependency).

The operating point is partial slip with spin (Omega_z a1 / Vx = 0.0046, creepage 1e-3:
adhesion 0.87, regime 0), where every contact output responds to its kinematics; the
perturbation is 10 % of each value, enough to move any output that depends on it.
"""

from __future__ import annotations

from pathlib import Path

import pytest

import fmu_build
from contact_fmu import examples as ex
from contact_fmu.fmu.config import ModelConfig
from contact_fmu.scenario.instance import OK, Instance
from fmu_build import native_fmu

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "out" / "fmu"
V = ex.speed_unit()  # m/s
# the operating point of every input (SI): a load, forces and moments of the body, the
# kinematics of partial slip with spin
POINT = {
    "P": ex.P,
    "Fx_ex": 0.1 * ex.mu * ex.P,
    "Fy_ex": 0.05 * ex.mu * ex.P,
    "My_ex": -0.01 * ex.mu * ex.P * ex.Rx,
    "Mz_ex": 0.01 * ex.mu * ex.P * ex.Rx,
    "Tx": 0.1 * ex.mu * ex.P,
    "Vx": V,
    "Vy": 1e-4 * V,
    "Omega_y": (1.0 - 1e-3) * V / ex.Rx,
    "Omega_z": 1.0,
}
BUILD = {"pythonfmu": fmu_build.build, "native": native_fmu.build}
MODES = ("body", "contact", "rigid_body")


@pytest.fixture(scope="module", params=[(k, m) for k in BUILD for m in MODES],
                ids=lambda p: f"{p[0]}-{p[1]}")  # fmt: skip
def fmu(request) -> Path:
    kind, mode = request.param
    return BUILD[kind](ModelConfig.full(mode), OUT).path


def declared(inst: Instance) -> dict[str, set[str]]:
    """ModelStructure/Outputs: each output's direct dependencies, by name."""
    return {u.variable.name: {d.name for d in u.dependencies or []}
            for u in inst.md.outputs}  # fmt: skip


def test_every_output_that_moves_is_declared(fmu):
    with Instance(fmu, "deps") as inst:
        inputs = [n for n, v in inst.vars.items() if v.causality == "input"]
        assert inputs and set(inputs) <= set(POINT)
        for name in inputs:
            inst.set(name, POINT[name])
        assert inst.step(1e-6) == OK  # a state that the inputs have reached
        deps = declared(inst)
        base = inst.outputs()
        undeclared = []
        for name in inputs:
            inst.set(name, 1.1 * POINT[name])
            moved = {k for k, v in inst.outputs().items() if v != base[k]}
            undeclared += [(k, name) for k in sorted(moved) if name not in deps[k]]
            inst.set(name, POINT[name])
            assert inst.outputs() == base  # back at the point: the same outputs
        assert undeclared == [], f"(output, input) moved but not declared: {undeclared}"


@pytest.mark.parametrize("kind", BUILD)
def test_regime_says_whether_an_adhesion_area_exists(kind):
    """regime is 0 exactly when an adhesion area exists (adhesion > 0), also under
    spin, where the translational creepage alone does not decide: at creepage 1e-3
    (partial slip without spin: adhesion 0.87) a spin Omega_z = 1e4 rad/s (Omega_z a1 /
    Vx = 4.6) leaves no node of the strip march in adhesion (adhesion 0): gross sliding,
    regime 1; at Omega_z = 100 rad/s adhesion is 0.0277 (to the 4 decimals compared),
    regime 0."""
    fmu = BUILD[kind](ModelConfig.full("contact"), OUT).path
    with Instance(fmu, "regime") as inst:
        for name in ("P", "Vx", "Vy", "Omega_y"):
            inst.set(name, POINT[name])
        seen = {}
        for Oz in (0.0, 1.0, 100.0, 1e3, 1e4, -1e4):
            inst.set("Omega_z", Oz)
            a, r = inst.get("adhesion"), inst.get("regime")
            seen[Oz] = (round(a, 4), r)
            assert r == (0 if a > 0.0 else 1), seen
        assert seen[1e4] == (0.0, 1) and seen[100.0] == (0.0277, 0), seen
