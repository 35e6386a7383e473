"""Every FMU variable, declared once: name, causality per mode, unit, description, start, range.

Both the pythonfmu registration (``slave``) and the post-processing of
modelDescription.xml (units, min/max, ModelStructure; ``fmu_build``) read this table,
so the two can never disagree. Names follow Spector & Batra (1995); units are SI.

Modes: ``body`` (the FMU owns the rigid-body dynamics, Eqs. 8-11), ``contact`` (a
force element: kinematics in, contact forces out) and ``rigid_body`` (Eqs. 8-9 alone,
driven by Tx from a contact-mode FMU; used to couple two FMUs in a master).

Default start values are the parameter set of ``contact_fmu.examples`` (the paper's
figures) with eta = 3; tests check that they agree.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Protocol

MODES = ("body", "contact", "rigid_body")
PARAMETER, INPUT, OUTPUT = "parameter", "input", "output"

# SI base-unit exponents of every unit used (FMI 2.0 UnitDefinitions/BaseUnit).
UNITS: dict[str, dict[str, int]] = {
    "1": {},
    "1/m": {"m": -1},
    "m": {"m": 1},
    "m/s": {"m": 1, "s": -1},
    "rad/s": {"rad": 1, "s": -1},
    "s": {"s": 1},
    "kg": {"kg": 1},
    "kg.m2": {"kg": 1, "m": 2},
    "N": {"kg": 1, "m": 1, "s": -2},
    "N.m": {"kg": 1, "m": 2, "s": -2},
    "Pa": {"kg": 1, "m": -1, "s": -2},
    "m/Pa": {"kg": -1, "m": 2, "s": 2},
}

# Physical ranges of the speeds and rates (the initial values, the body's state, the
# force element's kinematic inputs): beyond them the body's state (Vx and the slip vx,
# Eq. 20) no longer resolves Omega_y = (Vx - vx)/Rx to the changes one step makes
# (eps |Vx| / Rx against h Rx mu P / Iy; docs/reliability.md), and the strip march of
# the law with spin overflows (its increments grow as Omega_z a1 dx/(|Vx| k)). Far
# beyond any wheel, bearing or vehicle. The C code's CF_SPEED_MAX, CF_RATE_MAX are these
# (cf_abi.h, generated from contact_fmu/native/abi.py).
SPEED_MAX = 1e4  # m/s
RATE_MAX = 1e7  # rad/s
# Smallest coefficient of friction. Measured friction coefficients reach 1e-3 with
# lubricated rolling and 1e-4 to 1e-5 only in superlubric laboratory contacts; 1e-9 lies
# four decades below any of them. Below it the model stops being computable: mu = 5e-324
# underflows the onset of full slip 2 mu p0 (kb + ks)/a1 to 0 (beta per creepage, its
# inverse, divides by it), and mu P, the unit of every force and of the load limit
# (1e9 mu P), would be smaller than the load P itself.
MU_MIN = 1e-9

# Contact-mode inputs that the contact forces depend on directly (direct feedthrough).
_KIN = ("P", "Vx", "Vy", "Omega_y", "Omega_z")


class Structure(Protocol):
    """What decides which variables a model has (``config.ModelConfig`` provides it)."""

    mode: str
    vy: str  # "zero" | "ratio" | "eq10"
    spin: str  # "zero" | "ratio" | "eq11"
    methods: tuple[str, ...]
    schemes: tuple[str, ...]
    contact_law: str  # "layer" | "halfspace"
    phase: str  # "steady" | "transient"


# Conditions on the structure, by name (only the body mode has optional parts).
CONDITIONS = {
    "vy": lambda s: s.vy != "zero",
    "vy_eq10": lambda s: s.vy == "eq10",
    "vy_ratio": lambda s: s.vy == "ratio",
    "spin": lambda s: s.spin != "zero",
    "spin_eq11": lambda s: s.spin == "eq11",
    "spin_ratio": lambda s: s.spin == "ratio",
    "lateral": lambda s: s.vy != "zero" or s.spin != "zero",
    "methods": lambda s: len(s.methods) > 1,
    "schemes": lambda s: len(s.schemes) > 1,
    "transient": lambda s: s.phase == "transient",
}


@dataclass(frozen=True)
class Var:
    """One FMU variable.

    ``causality`` maps each mode that has the variable to "parameter", "input" or
    "output". ``min``/``max`` are inclusive bounds written to the model description;
    ``open_min`` excludes the lower bound itself (FMI has no exclusive bound, so the
    FMU checks it and the description says so); ``below`` adds to the requirement a
    value below min violates what min means (P: lift-off is P = 0). ``needs`` names a
    CONDITIONS entry that must hold in body mode. ``feedthrough``: the contact-mode inputs an output
    depends on directly (ModelStructure/Outputs dependencies). ``laws``: the contact
    laws whose models have the variable (None: every law); the half-space law's
    geometry and materials are structural, so the layer law's Ry, k1, k2, kb, ks are
    parameters of the layer law only. ``tunable``: a parameter the FMU takes between
    steps too (variability "tunable"; else "fixed").
    """

    name: str
    unit: str | None
    description: str
    causality: Mapping[str, str]
    start: float | str = 0.0
    min: float | None = None
    max: float | None = None
    open_min: bool = False
    below: str | None = None
    type: str = "Real"
    needs: str | None = None
    feedthrough: tuple[str, ...] = field(default=())
    laws: tuple[str, ...] | None = None
    tunable: bool = False

    def bounds(self, mode: str) -> tuple[float | None, float | None]:
        """(min, max) of the model description in ``mode``: the declared range where the
        importer sets the variable (a parameter or an input), none where the model
        computes it (an output: a range there would be a promise on the model's results;
        the rigid_body mode's Vx, for one, has no bound of its own)."""
        if self.causality[mode] == OUTPUT:
            return None, None
        return self.min, self.max

    def lower_requirement(self) -> str:
        """The requirement of the lower bound, as the checks word it: "> 0", ">= 0 (...)"."""
        req = f"{'>' if self.open_min else '>='} {self.min:g}"
        return req if self.below is None else f"{req} ({self.below})"

    def check(self, value: object) -> str | None:
        """None if ``value`` is admissible, else the requirement it violates."""
        if self.type == "String":
            return None if isinstance(value, str) else "a string"
        try:
            v = float(value)  # type: ignore[arg-type]
        except (TypeError, ValueError):
            return "a number"
        if not math.isfinite(v):
            return "finite"
        if self.type == "Integer" and v != int(v):
            return "an integer"
        if self.min is not None and (v < self.min or (self.open_min and v == self.min)):
            return self.lower_requirement()
        if self.max is not None and v > self.max:
            return f"<= {self.max:g}"
        return None


def _p(name, unit, desc, start, modes=("body", "contact"), **kw) -> Var:
    return Var(name, unit, desc, {m: PARAMETER for m in modes}, start, **kw)


_BODY = ("body",)
_LAYER = ("layer",)
_BODY_RB = ("body", "rigid_body")
_ALL = ("body", "contact", "rigid_body")

VARIABLES: tuple[Var, ...] = (
    # ---- parameters ------------------------------------------------------------------
    _p(
        "mu",
        "1",
        f"Coefficient of friction (>= {MU_MIN:g}); tunable: a new value between steps (a wet "
        "or contaminated patch) applies from the next step, the bound becomes mu P",
        0.3,
        min=MU_MIN,
        tunable=True,
    ),
    _p(
        "Rx",
        "m",
        "Radius of the body in the rolling plane: rolling radius and curvature radius (> 0)",
        0.05,
        modes=_ALL,
        min=0.0,
        open_min=True,
    ),
    _p(
        "Ry",
        "m",
        "Lateral radius of curvature of the body (> 0)",
        0.10,
        min=0.0,
        open_min=True,
        laws=_LAYER,
    ),
    _p(
        "k1",
        "m/Pa",
        "Normal compliance of the body's layer, Eq. (32) (>= 0, with k1 + k2 > 0)",
        5.0e-13,
        min=0.0,
        laws=_LAYER,
    ),
    _p(
        "k2",
        "m/Pa",
        "Normal compliance of the substrate's layer, Eq. (32) (>= 0, with k1 + k2 > 0)",
        5.0e-13,
        min=0.0,
        laws=_LAYER,
    ),
    _p(
        "kb",
        "m/Pa",
        "Tangential compliance of the body's layer, Eq. (31) (>= 0, with kb + ks > 0)",
        3.2e-13,
        min=0.0,
        laws=_LAYER,
    ),
    _p(
        "ks",
        "m/Pa",
        "Tangential compliance of the substrate's layer, Eq. (31) (>= 0, with kb + ks > 0)",
        3.2e-13,
        min=0.0,
        laws=_LAYER,
    ),
    _p("M", "kg", "Mass of the body (> 0)", 1.0, modes=_BODY_RB, min=0.0, open_min=True),
    _p(
        "Iy",
        "kg.m2",
        "Moment of inertia about the axle (>= 0); eta = M Rx^2/Iy, Iy = 0 is eta = inf",
        0.05**2 / 3.0,
        modes=_BODY_RB,
        min=0.0,
    ),
    _p(
        "Iz",
        "kg.m2",
        "Moment of inertia about the vertical axis, Eq. (11) (> 0)",
        1.0e-3,
        modes=_BODY,
        min=0.0,
        open_min=True,
        needs="spin_eq11",
    ),
    _p(
        "vy_ratio",
        "1",
        "Held lateral slip ratio Vy/Vx (instead of Eq. 10)",
        0.0,
        modes=_BODY,
        needs="vy_ratio",
    ),
    _p(
        "spin_ratio",
        "1/m",
        "Held spin ratio Omega_z/Vx (instead of Eq. 11)",
        0.0,
        modes=_BODY,
        needs="spin_ratio",
    ),
    _p(
        "Vx0",
        "m/s",
        "Initial speed of the centre of mass (abs <= 1e4 m/s)",
        5.6418958354775635,
        modes=_BODY_RB,
        min=-SPEED_MAX,
        max=SPEED_MAX,
    ),
    _p(
        "vx0",
        "m/s",
        "Initial rigid slip at the contact centre, Vx0 - Omega_y0 Rx (Eq. 3): the body "
        "starts with Omega_y0 = (Vx0 - vx0)/Rx; 0 is pure rolling at any Vx0 (initial "
        "creepage xi_x0 = vx0/abs(Vx0); abs <= 1e4 m/s)",
        0.0,
        modes=_BODY_RB,
        min=-SPEED_MAX,
        max=SPEED_MAX,
    ),
    _p(
        "Vy0",
        "m/s",
        "Initial lateral speed, Eq. (10) (abs <= 1e4 m/s)",
        0.0,
        modes=_BODY,
        needs="vy_eq10",
        min=-SPEED_MAX,
        max=SPEED_MAX,
    ),
    _p(
        "Omega_z0",
        "rad/s",
        "Initial angular velocity about the vertical, Eq. (11) (abs <= 1e7 rad/s)",
        0.0,
        modes=_BODY,
        needs="spin_eq11",
        min=-RATE_MAX,
        max=RATE_MAX,
    ),
    _p(
        "h_max",
        "s",
        "Largest internal step of the stiff integrator: a communication step h "
        "is split into ceil(h/h_max) steps (> 0)",
        1.0e-4,
        modes=_BODY,
        min=0.0,
        open_min=True,
    ),
    Var(
        "max_work",
        "1",
        "Most work of one communication step, in work units (1 to 1e9): an internal step "
        "costs 1 (vx the only unknown), 200 (Vy and/or Omega_z as unknowns, Eqs. 10-11, or "
        "a held spin on the thin-layer law's spin grid) or "
        '2 nx ny (phase "transient"); a step that needs more is taken in fewer, longer '
        "internal steps (fmi2Warning), at least one (the transient field: fmi2Discard if "
        "one exceeds it). Where Python solves the stages, each evaluation of the law counts "
        "too (3, 25 with Eqs. 10-11 or the spin grid, nx ny / 8 on the field): a step "
        "beyond the budget is discarded",
        {"body": PARAMETER},
        10_000.0,
        min=1.0,
        max=1e9,
    ),
    Var(
        "nx",
        None,
        'Phase "transient": cells of the traction field along the contact length 2 a1 (4 to '
        "1024: the field's memory and time grow with nx ny)",
        {"body": PARAMETER},
        64,
        min=4,
        max=1024,
        type="Integer",
        needs="transient",
    ),
    Var(
        "ny",
        None,
        'Phase "transient": strips of the traction field across the contact width 2 a2 (2 to 512)',
        {"body": PARAMETER},
        32,
        min=2,
        max=512,
        type="Integer",
        needs="transient",
    ),
    _p(
        "cells_per_step",
        "1",
        'Phase "transient": largest distance rolled per internal step, in cells of the field '
        "(> 0); the internal steps also respect h_max",
        0.5,
        modes=_BODY,
        min=0.0,
        open_min=True,
        needs="transient",
    ),
    Var(
        "field_file",
        None,
        'Phase "transient": CSV file the traction field is written to at field_times '
        '(columns requested, time, i, j, x, y, tau_x, tau_y, p, slip, inside, weight; "": '
        "none)",
        {"body": PARAMETER},
        "",
        type="String",
        needs="transient",
    ),
    Var(
        "field_times",
        None,
        'Phase "transient": times (s), separated by spaces or commas, at which the field is '
        "written: at the end of the communication step that reaches each",
        {"body": PARAMETER},
        "",
        type="String",
        needs="transient",
    ),
    Var(
        "method",
        None,
        'Stepper: "full" (stiff slip equation, Eq. 20) or "quasistationary" (Eqs. 26, 28-30)',
        {"body": PARAMETER},
        "full",
        type="String",
        needs="methods",
    ),
    Var(
        "scheme",
        None,
        'Integrator: "lobatto3c" (Lobatto IIIC, no overshoot after load steps) or "sdirk2" '
        "(SDIRK2, smaller error constant, rings after steps of a few relaxation times)",
        {"body": PARAMETER},
        "lobatto3c",
        type="String",
        needs="schemes",
    ),
    # ---- inputs ----------------------------------------------------------------------
    Var(
        "P",
        "N",
        "Normal load (>= 0, <= 1e9 N); P = 0 is lift-off: no contact, zero tangential "
        "forces and moment, the body moves under the external loads alone",
        {"body": INPUT, "contact": INPUT},
        1000.0,
        min=0.0,
        max=1e9,
        below="lift-off, no contact, is P = 0",
    ),
    Var(
        "Fx_ex",
        "N",
        "External force on the body along the rolling direction",
        {"body": INPUT, "rigid_body": INPUT},
    ),
    Var(
        "Fy_ex",
        "N",
        "External lateral force on the body, Eq. (10)",
        {"body": INPUT},
        needs="vy_eq10",
    ),
    Var(
        "My_ex",
        "N.m",
        "External moment about the axle (driving > 0, braking < 0)",
        {"body": INPUT, "rigid_body": INPUT},
    ),
    Var(
        "Mz_ex",
        "N.m",
        "External moment about the vertical axis, Eq. (11)",
        {"body": INPUT},
        needs="spin_eq11",
    ),
    # ---- kinematics: outputs of the body, inputs of the force element ---------------------
    Var(
        "Vx",
        "m/s",
        "Speed of the centre of mass along the rolling direction (as an input: abs <= 1e4 m/s)",
        {"body": OUTPUT, "contact": INPUT, "rigid_body": OUTPUT},
        5.6418958354775635,
        min=-SPEED_MAX,
        max=SPEED_MAX,
    ),
    Var(
        "Vy",
        "m/s",
        "Lateral speed of the centre of mass (as an input: abs <= 1e4 m/s)",
        {"body": OUTPUT, "contact": INPUT},
        needs="vy",
        min=-SPEED_MAX,
        max=SPEED_MAX,
    ),
    Var(
        "Omega_y",
        "rad/s",
        "Angular velocity about the axle (as an input: abs <= 1e7 rad/s)",
        {"body": OUTPUT, "contact": INPUT, "rigid_body": OUTPUT},
        112.83791670955127,
        min=-RATE_MAX,
        max=RATE_MAX,
    ),
    Var(
        "Omega_z",
        "rad/s",
        "Angular velocity about the vertical axis (spin; as an input: abs <= 1e7 rad/s)",
        {"body": OUTPUT, "contact": INPUT},
        needs="spin",
        min=-RATE_MAX,
        max=RATE_MAX,
    ),
    # ---- contact outputs (the force is an input of the rigid body) -------------------------
    Var(
        "Tx",
        "N",
        "Resultant frictional force along x that the body exerts on the substrate "
        "(the body receives -Tx)",
        {"body": OUTPUT, "contact": OUTPUT, "rigid_body": INPUT},
        feedthrough=_KIN,
    ),
    Var(
        "Ty",
        "N",
        "Lateral resultant frictional force on the substrate",
        {"body": OUTPUT, "contact": OUTPUT},
        needs="lateral",
        feedthrough=_KIN,
    ),
    Var(
        "Mz",
        "N.m",
        "Frictional moment about the vertical axis on the substrate",
        {"body": OUTPUT, "contact": OUTPUT},
        needs="lateral",
        feedthrough=_KIN,
    ),
    Var(
        "vx",
        "m/s",
        "Longitudinal rigid slip at the contact centre, Vx - Omega_y Rx (Eq. 3)",
        {"body": OUTPUT, "contact": OUTPUT},
        feedthrough=("Vx", "Omega_y"),
    ),
    Var(
        "vy",
        "m/s",
        "Lateral rigid slip at the contact centre, Vy (Eq. 3)",
        {"body": OUTPUT, "contact": OUTPUT},
        needs="vy",
        feedthrough=("Vy",),
    ),
    Var(
        "xi_x",
        "1",
        "Longitudinal creepage vx / abs(Vx)",
        {"body": OUTPUT, "contact": OUTPUT},
        feedthrough=("Vx", "Omega_y"),
    ),
    Var(
        "xi_y",
        "1",
        "Lateral creepage vy / abs(Vx)",
        {"body": OUTPUT, "contact": OUTPUT},
        needs="vy",
        feedthrough=("Vx", "Vy"),
    ),
    Var(
        "xi_sp",
        "1/m",
        "Spin creepage Omega_z / abs(Vx)",
        {"body": OUTPUT, "contact": OUTPUT},
        needs="spin",
        feedthrough=("Vx", "Omega_z"),
    ),
    Var(
        "a1",
        "m",
        "Semi-axis of the contact ellipse along x, Eq. (34)",
        {"body": OUTPUT, "contact": OUTPUT},
        feedthrough=("P",),
    ),
    Var(
        "a2",
        "m",
        "Lateral semi-axis of the contact ellipse, Eq. (34)",
        {"body": OUTPUT, "contact": OUTPUT},
        feedthrough=("P",),
    ),
    Var(
        "p0",
        "Pa",
        "Peak contact pressure, Eq. (34)",
        {"body": OUTPUT, "contact": OUTPUT},
        feedthrough=("P",),
    ),
    Var(
        "adhesion",
        "1",
        "Adhesion area over contact area",
        {"body": OUTPUT, "contact": OUTPUT},
        feedthrough=_KIN,  # spin too: Omega_z shrinks the adhesion area (strip march)
    ),
    Var(
        "regime",
        None,
        "0: rolling with partial slip (an adhesion area exists), 1: gross sliding",
        {"body": OUTPUT, "contact": OUTPUT},
        0,
        type="Integer",
        feedthrough=_KIN,  # with spin: whether the adhesion area is left
    ),
    Var(
        "slip_centroid_x",
        "m",
        'Phase "transient": x of the centroid of the slip area (0 without slip)',
        {"body": OUTPUT},
        needs="transient",
    ),
    Var(
        "slip_centroid_y",
        "m",
        'Phase "transient": y of the centroid of the slip area (0 without slip)',
        {"body": OUTPUT},
        needs="transient",
    ),
    Var(
        "tau_peak",
        "Pa",
        'Phase "transient": largest traction magnitude of the field',
        {"body": OUTPUT},
        needs="transient",
    ),
)

BY_NAME: dict[str, Var] = {v.name: v for v in VARIABLES}


def variability(var: Var, mode: str) -> str:
    """FMI variability of ``var`` in ``mode``: parameters fixed (or tunable), Real inputs
    and outputs continuous, others discrete."""
    c = var.causality[mode]
    if c == PARAMETER:
        return "tunable" if var.tunable else "fixed"
    return "continuous" if var.type == "Real" else "discrete"


def applicable(var: Var, s: Structure) -> bool:
    """Whether the model ``s`` can have ``var`` at all."""
    if s.mode not in var.causality:
        return False
    if var.laws is not None and s.contact_law not in var.laws:
        return False
    return s.mode != "body" or var.needs is None or CONDITIONS[var.needs](s)


def available(s: Structure, causality: str) -> list[str]:
    """Names of every variable of the given causality that the model ``s`` can have."""
    return [v.name for v in VARIABLES if applicable(v, s) and v.causality[s.mode] == causality]


def select(s: Structure, inputs: tuple[str, ...], outputs: tuple[str, ...]) -> list[Var]:
    """The variables of a built FMU, in value-reference order.

    Every applicable parameter (the model reads them all), then the requested inputs
    and outputs in declaration order.
    """
    wanted = set(inputs) | set(outputs)
    chosen = []
    for v in VARIABLES:
        if not applicable(v, s):
            continue
        c = v.causality[s.mode]
        if c == PARAMETER or v.name in wanted:
            chosen.append(v)
    return chosen


def markdown_table() -> str:
    """Every variable as a Markdown table (docs/variables.md): causality per mode, unit,
    start."""
    rows = [
        "| name | body | contact | rigid_body | unit | start | description |",
        "|---|---|---|---|---|---|---|",
    ]
    for v in VARIABLES:
        modes = [v.causality.get(m, "") for m in MODES]
        if v.needs:
            modes[0] += f" ({v.needs})" if modes[0] else ""
        start = "" if all(c == OUTPUT for c in v.causality.values()) else f"{v.start!r}"
        unit = v.unit if v.unit is not None else ("" if v.type == "Real" else v.type)
        rows.append(f"| {v.name} | {' | '.join(modes)} | {unit} | {start} | {v.description} |")
    return "\n".join(rows)


DOCS_MARKS = ("<!-- variables.py: table -->", "<!-- variables.py: end -->")


def write_docs(page: str) -> str:
    """``page`` (the text of docs/variables.md) with the table between DOCS_MARKS
    regenerated."""
    begin, end = DOCS_MARKS
    head, sep, rest = page.partition(begin)
    _, sep2, tail = rest.partition(end)
    if not (sep and sep2):
        raise ValueError(f"the page lacks the markers {begin} ... {end}")
    return head + begin + "\n" + markdown_table() + "\n" + end + tail


if __name__ == "__main__":
    # python -m contact_fmu.fmu.variables               the table on stdout
    # python -m contact_fmu.fmu.variables --write-docs  regenerate it in docs/variables.md
    import sys
    from pathlib import Path

    if sys.argv[1:] == ["--write-docs"]:
        doc = Path(__file__).resolve().parents[2] / "docs" / "variables.md"
        doc.write_text(write_docs(doc.read_text()))
    else:
        print(markdown_table())
