"""Plausibility of a scene's numbers: values that look like unit slips, as warnings.

A scene is SI throughout. A value typed in another unit (a radius in mm, a load in kN,
a modulus in MPa) is legal for the FMU and runs without a word, to a wrong answer. These
checks compare each value with what a wheel, a roller or a rail can be and warn
(``PlausibilityWarning``), naming the file, the key, the value and the likely slip. A
scene that means such a value as written says so in its [checks] table:

    [checks]
    accept = ["Rx"]            # these keys' warnings are meant as written
    plausibility = false       # or: no plausibility checks at all

The thresholds, each an order of magnitude beyond the real range:

- Rx, Ry (and the half-space solids' radii) above RADIUS_MAX = 10 m: the largest wheels
  (mining tyres, r = 2 m) are a fifth of that; 300 mm typed as m is 300.
- the load P: its largest value over the run below LOAD_MIN = 1 N; in body mode, below
  WEIGHT_RATIO[0] = 1/100 of the body's weight M g (a vehicle's wheel carries about its
  share of the weight, the paper's test body 100 times its own), or above
  WEIGHT_RATIO[1] = 1e4 times it (4 kN typed as N on a 400 kg quarter car is 1e-3 M g).
- the layer compliances k1, k2, kb, ks above COMPLIANCE_MAX = 1e-8 m/Pa: a 10 mm layer
  of 1 MPa rubber; a steel layer's 5e-13 m/Pa typed in m/MPa is 5e-7.
- the contact semi-axes of the layer law (Eq. 34, at the largest load) above
  SEMI_AXIS_RATIO = 0.2 of their radius: the contact is then not small against the body,
  as the theory assumes (compliances or the load in the wrong unit).
- the half-space solids' Young's moduli E below MODULUS_MIN = 1 MPa (softer than any
  rubber): steel's 210 GPa typed in MPa is 2.1e5, in GPa 210.
"""

from __future__ import annotations

import math
import warnings
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from .schema import Scene

RADIUS_MAX = 10.0  # m
LOAD_MIN = 1.0  # N
WEIGHT_RATIO = (1e-2, 1e4)  # P / (M g)
COMPLIANCE_MAX = 1e-8  # m/Pa
SEMI_AXIS_RATIO = 0.2  # a1/Rx, a2/Ry
MODULUS_MIN = 1e6  # Pa
G = 9.80665  # m/s^2, standard gravity

SOLIDS = ("body", "substrate")
# The keys a scene's [checks] accept may name: those the checks below question.
KEYS = (
    "Rx",
    "Ry",
    "P",
    "k1",
    "k2",
    "kb",
    "ks",
    "semi_axes",
    *(f"halfspace.{s}.{k}" for s in SOLIDS for k in ("Rx", "Ry", "E")),
)


class PlausibilityWarning(UserWarning):
    """A scene value that is legal but looks like a unit slip (``plausibility.py``)."""


def findings(scene: Scene) -> list[tuple[str, str]]:
    """(key, message) of every questionable value of ``scene``, one per key and value;
    ``key`` is what [checks] accept names to silence it."""
    out: dict[tuple[str, str], str] = {}

    def add(key: str, where: str, value: Any, why: str) -> None:
        out.setdefault((key, f"{where}={value!r}"), f"{where} = {value!r}: {why}")

    for case in scene.cases:
        p = case.parameters
        at = _where(scene, case.name, "parameters")
        for k in ("Rx", "Ry"):
            if k in p and p[k] > RADIUS_MAX:
                add(
                    k,
                    at(k),
                    p[k],
                    f"a radius over {RADIUS_MAX:g} m, larger than any wheel; typed in mm?",
                )
        for k in ("k1", "k2", "kb", "ks"):
            if k in p and p[k] > COMPLIANCE_MAX:
                add(
                    k,
                    at(k),
                    p[k],
                    f"a layer compliance over {COMPLIANCE_MAX:g} m/Pa, softer "
                    "than 10 mm of rubber; typed in m/MPa?",
                )
        if "P" not in case.inputs:
            continue
        P = float(np.max(case.inputs["P"](scene.grid)))
        where = _where(scene, case.name, "inputs")("P")
        if P < LOAD_MIN:
            add("P", where, P, f"the largest load of the run is below {LOAD_MIN:g} N; typed in kN?")
        elif "M" in p:
            ratio = P / (p["M"] * G)
            if not WEIGHT_RATIO[0] <= ratio <= WEIGHT_RATIO[1]:
                add(
                    "P",
                    where,
                    P,
                    f"the largest load is {ratio:.3g} times the weight M g of the "
                    f"body (M = {p['M']!r} kg); P typed in kN, or M in the wrong unit?",
                )
        if scene.config.contact_law == "layer" and P > 0.0:
            names = ("Rx", "Ry", "k1", "k2")
            if all(k in p for k in names):
                for axis, R, a in zip(
                    ("a1", "a2"), (p["Rx"], p["Ry"]), _semi_axes(P, p), strict=True
                ):
                    if a > SEMI_AXIS_RATIO * R:
                        radius = "Rx" if axis == "a1" else "Ry"
                        add(
                            "semi_axes",
                            f"the contact semi-axis {axis} (m)",
                            float(f"{a:.3g}"),
                            f"{a / R:.2g} {radius} by Eq. (34) from {at('k1')}, {at('k2')}, "
                            f"{at(radius)} and {where} = {P:.6g} N, not small against the body; "
                            "compliances typed in m/MPa, or P in the wrong unit?",
                        )
    spec = scene.config.law_spec
    for s in SOLIDS:
        solid = spec.get(s)
        if not isinstance(solid, dict):
            continue
        for k in ("Rx", "Ry"):
            R = solid.get(k)
            if isinstance(R, float | int) and math.isfinite(R) and R > RADIUS_MAX:
                add(
                    f"halfspace.{s}.{k}",
                    f"halfspace.{s}.{k}",
                    R,
                    f"a radius over "
                    f"{RADIUS_MAX:g} m, larger than any wheel or rail head; typed in mm?",
                )
        E = solid.get("E")
        if isinstance(E, float | int) and E < MODULUS_MIN:
            add(
                f"halfspace.{s}.E",
                f"halfspace.{s}.E",
                E,
                f"a Young's modulus below "
                f"{MODULUS_MIN:g} Pa, softer than any rubber; typed in MPa or GPa?",
            )
    return [(key, msg) for (key, _), msg in out.items()]


def _semi_axes(P: float, p: dict[str, Any]) -> tuple[float, float]:
    """a1, a2 (m) of the layer law, Eq. (34): delta = sqrt(P (k1 + k2)/pi) (Rx Ry)^(-1/4),
    a1 = sqrt(2 Rx delta), a2 = sqrt(2 Ry delta) (thin_layer.LayerContact)."""
    delta = math.sqrt(P * (p["k1"] + p["k2"]) / math.pi) * (p["Rx"] * p["Ry"]) ** -0.25
    return math.sqrt(2.0 * p["Rx"] * delta), math.sqrt(2.0 * p["Ry"] * delta)


def _where(scene: Scene, case: str, table: str):
    """The key of a value in a case: the scene's own table when the case takes it from
    there, else the case's."""
    for c in scene.source.get("cases", []):
        if c.get("name") == case:
            mine = c.get(table, {})
            return lambda k: f"cases[{case!r}].{table}.{k}" if k in mine else f"{table}.{k}"
    return lambda k: f"{table}.{k}"


def warn(scene: Scene) -> list[str]:
    """Warn (PlausibilityWarning) about every questionable value of ``scene`` that its
    [checks] does not accept; the messages, one line each, naming the file."""
    if not scene.checks.plausibility:
        return []
    msgs = []
    for key, msg in findings(scene):
        if key in scene.checks.accept:
            continue
        text = f'{scene.path}: {msg} (if meant: [checks] accept = ["{key}"])'
        warnings.warn(text, PlausibilityWarning, stacklevel=3)
        msgs.append(text)
    return msgs
