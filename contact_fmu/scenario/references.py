"""Reference results of the scenes, produced without the FMU.

Each ``[[reference]]`` of a scene names its ``source``; this module reproduces it from
the scene's data on a path that does not go through the FMU, its adapter or fmpy:

- ``quasistationary``: the closed form Tx = A2 Fx_ex - A1 My_ex / Rx of Eq. (26)
  (dimensional; ``dynamics.body.Body.tx_quasistationary``), valid in rolling after the slip
  transient, with regime = 0; where Vy follows Eq. (10), also Ty = Fy_ex (Eq. 29);
- ``full_slip``: Coulomb's law in gross sliding, Tx = sign mu P and regime = 1, over a
  window the scene asserts to be sliding;
- ``sliding_motion``: Eqs. (8)-(9) with that force (Tx = 0 at P = 0, lift-off) over
  the held inputs: Vx and Omega_y summed step by step, over a run the scene asserts to
  slide throughout;
- ``simulate``: the pure-numerics stepper of ``dynamics.simulate`` (RollingBody) with
  ``refine`` times more internal steps than the FMU takes (h_max / refine);
- ``traction``: contact mode; the resultant of the traction field marched strip by
  strip (``LayerContact.traction``) on an ``nx`` x ``ny`` grid, integrated numerically:
  independent of the closed form H(beta) of Eqs. (40)-(43) the FMU evaluates (0 at
  P = 0: no contact, no field);
- ``halfspace``: contact mode, half-space law; direct solves of the steady-rolling
  problem (``HalfSpaceContact`` of the scene's [halfspace] declaration, on the solver
  grid of the table) at the sampled points: independent of the creep-force table the
  FMU interpolates;
- ``halfspace_creepage``: body mode, half-space law; the quasistationary state of
  Eq. (26): Tx = A2 Fx_ex - A1 My_ex/Rx, and the creepage xi_x and adhesion fraction at
  which direct solves give that Tx (bracketed root finding on the solver, no table).
- ``transient``: body mode, phase "transient"; the numerics' transient stepper
  (``dynamics.thin_layer_field.TransientRollingBody``) on a finer field grid
  ``grid = [nx, ny]`` with internal steps of at most ``cells`` cells, driven step by step
  with the held loads.

Samples: every ``every``-th grid point within ``t_from`` <= t <= ``t_to``, or within
each ``[from, to]`` of ``windows``, or the grid points nearest to the listed ``times``.

The law, the body, its lateral motion and its initial state come from the FMU's own
factory (``fmu.factory``: make_law, make_body, make_lateral, initial_state), so a
reference runs the model the FMU runs, on another path.

All of them see the inputs as the FMU does: sampled on the communication grid and held
over each step (``signals.held``), so that the value at t_k uses the inputs of the step
ending at t_k.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from ..dynamics.body import Loads
from ..dynamics.integrator import RollingBody
from ..dynamics.kinematics import rigid_slip
from ..fmu.factory import initial_state, make_body, make_lateral, make_law, thin_layer_law
from .runner import write_reference
from .schema import Case, Reference, Scene
from .signals import held

FloatArray = NDArray[np.float64]


def _samples(scene: Scene, ref: Reference) -> NDArray[np.int_]:
    """Grid indices of the reference points: t_from <= t <= t_to (or each window of
    ``windows``), every n-th; or the points nearest to ``times``."""
    o = ref.options
    t = scene.grid
    if "times" in o:
        idx = np.rint(np.asarray(o["times"], float) / scene.step).astype(int)
        if np.any(idx < 0) or np.any(idx >= t.size):
            raise ValueError(f"{scene.path}: reference times {o['times']} outside the run")
        return idx
    every = max(int(o.get("every", 1)), 1)
    windows = o.get("windows", [[o.get("t_from", 0.0), o.get("t_to", scene.stop_time)]])
    parts = []
    for t_from, t_to in windows:
        idx = np.flatnonzero((t >= float(t_from) - 1e-12) & (t <= float(t_to) + 1e-12))
        parts.append(idx[::every])
    return np.concatenate(parts)


def _held_inputs(scene: Scene, case: Case) -> dict[str, FloatArray]:
    t = scene.grid
    return {
        n: held(case.inputs[n](t)) if n in case.inputs else np.zeros(t.size)
        for n in ("P", "Fx_ex", "Fy_ex", "My_ex", "Mz_ex", "Vx", "Vy", "Omega_y", "Omega_z")
    }


def quasistationary(scene: Scene, ref: Reference, case: Case) -> dict[str, FloatArray]:
    k = _samples(scene, ref)
    u = _held_inputs(scene, case)
    Tx = make_body(case.parameters).tx_quasistationary(u["Fx_ex"][k], u["My_ex"][k])
    out = {"time": scene.grid[k], "Tx": Tx, "regime": np.zeros(k.size)}
    if scene.config.vy == "eq10":  # Eq. (29): the lateral force balances the load
        out["Ty"] = u["Fy_ex"][k]
    return out


def full_slip(scene: Scene, ref: Reference, case: Case) -> dict[str, FloatArray]:
    k = _samples(scene, ref)
    u = _held_inputs(scene, case)
    sign = float(ref.options["sign"])
    Tx = sign * case.parameters["mu"] * u["P"][k]
    return {"time": scene.grid[k], "Tx": Tx, "regime": np.ones(k.size)}


def by_simulation(
    scene: Scene, ref: Reference, case: Case, refine: int | None = None
) -> dict[str, FloatArray]:
    """The stepper of ``simulate`` driven step by step with the held loads.

    ``simulate()`` samples a load function at stage times, and a stage on a
    communication point (Lobatto IIIC's first stage, c = 0) cannot tell which step's
    held value applies; so the same loop as ``simulate()`` is written out here, with
    the loads of each communication step passed as constants.
    """
    cfg, p = scene.config, case.parameters
    t = scene.grid
    P = case.inputs["P"](t)
    if np.ptp(P) != 0.0:
        raise ValueError(f"{scene.name}: source 'simulate' needs a constant P")
    refine = int(ref.options["refine"]) if refine is None else refine
    substeps = refine * max(1, math.ceil(scene.step / p["h_max"] - 1e-9))
    rb = RollingBody(
        make_law(cfg, p, float(P[0])), make_body(p), make_lateral(cfg, p), case.method,
        **initial_state(p), scheme=case.scheme,
    )  # fmt: skip
    loads = np.array([case.inputs[n](t) if n in case.inputs else np.zeros(t.size)
                      for n in Loads._fields])  # fmt: skip
    names = [v for v in ref.tolerance if v != "regime"]
    rec = {v: np.empty(t.size) for v in [*names, "regime"]}

    def record(i: int) -> None:
        o = rb.outputs()
        for v in names:
            rec[v][i] = o[v]
        rec["regime"][i] = float(rb.out.sliding)

    record(0)
    for i in range(t.size - 1):
        rb.advance(scene.step, Loads(*(float(x) for x in loads[:, i])), substeps)
        record(i + 1)
    k = _samples(scene, ref)
    return {"time": t[k], **{v: rec[v][k] for v in ref.tolerance}}


def by_transient(scene: Scene, ref: Reference, case: Case) -> dict[str, FloatArray]:
    """The transient thin-layer stepper outside the FMU, at the reference's resolution:
    field grid ``grid`` = [nx, ny] and internal steps of at most ``cells`` cells rolled
    (and at most the scene's h_max), the loads of each communication step held."""
    from ..dynamics.thin_layer_field import TransientRollingBody

    cfg, p, o = scene.config, case.parameters, ref.options
    t = scene.grid
    P = held(case.inputs["P"](t))
    nx, ny = (int(n) for n in o["grid"])
    cells = float(o["cells"])
    tb = TransientRollingBody(
        make_law(cfg, p, float(P[0])), make_body(p), make_lateral(cfg, p),
        **initial_state(p), nx=nx, ny=ny,
    )  # fmt: skip
    loads = np.array([case.inputs[n](t) if n in case.inputs else np.zeros(t.size)
                      for n in Loads._fields])  # fmt: skip
    names = list(ref.tolerance)
    rec = {v: np.empty(t.size) for v in names}

    def record(i: int) -> None:
        out = tb.outputs()
        for v in names:
            rec[v][i] = out[v]

    record(0)
    for i in range(t.size - 1):
        if P[i + 1] != tb.law.P:
            tb.set_load(float(P[i + 1]))
        n = max(math.ceil(scene.step / p["h_max"] - 1e-9), tb.substeps_for(scene.step, cells))
        tb.advance(scene.step, Loads(*(float(x) for x in loads[:, i])), n)
        record(i + 1)
    k = _samples(scene, ref)
    return {"time": t[k], **{v: rec[v][k] for v in names}}


def by_traction(scene: Scene, ref: Reference, case: Case, refine: int = 1) -> dict[str, FloatArray]:
    nx, ny = (refine * int(n) - (refine - 1) for n in ref.options["grid"])
    p = case.parameters
    u = _held_inputs(scene, case)
    k = _samples(scene, ref)
    rows: dict[str, list[float]] = {"Tx": [], "Ty": [], "Mz": [], "xi_x": []}
    for i in k:
        if u["Omega_z"][i] != 0.0:
            raise ValueError(f"{scene.name}: source 'traction' is without spin")
        vx, vy = rigid_slip(u["Vx"][i], u["Omega_y"][i], u["Vy"][i], p["Rx"])
        if u["P"][i] == 0.0:  # lift-off: no contact, no field
            resultant = (0.0, 0.0, 0.0)
        else:
            field = thin_layer_law(p, u["P"][i]).traction(vx, vy, u["Vx"][i], nx, ny)
            resultant = field.resultant()
        for name, value in zip(("Tx", "Ty", "Mz"), resultant, strict=True):
            rows[name].append(value)
        rows["xi_x"].append(vx / abs(u["Vx"][i]))  # for plots; not compared
    out = {"time": scene.grid[k], "xi_x": np.asarray(rows["xi_x"])}
    out.update({n: np.asarray(rows[n]) for n in ref.tolerance if n in rows})
    return out


def _contacts(scene: Scene, case: Case):
    """HalfSpaceContact of the scene's declaration at a load P (N) with the case's mu,
    one per load (its patch and calibration are cached on it)."""
    spec = scene.config.table_spec
    mu = case.parameters.get("mu", spec.mu)
    cache: dict[float, object] = {}

    def at(P: float):
        if P not in cache:
            cache[P] = spec.contact(P=P, mu=mu)
        return cache[P]

    return at


def by_halfspace(scene: Scene, ref: Reference, case: Case) -> dict[str, FloatArray]:
    spec = scene.config.table_spec
    Rx = case.parameters.get("Rx", spec.Rx)
    u = _held_inputs(scene, case)
    k = _samples(scene, ref)
    contact = _contacts(scene, case)
    rows: dict[str, list[float]] = {n: [] for n in ("Tx", "Ty", "Mz", "adhesion", "xi_x")}
    for i in k:
        vx, vy = rigid_slip(u["Vx"][i], u["Omega_y"][i], u["Vy"][i], Rx)
        s = contact(float(u["P"][i])).traction(vx, vy, u["Omega_z"][i], u["Vx"][i])
        for name, value in zip(rows, (s.Tx, s.Ty, s.Mz, s.adhesion_fraction), strict=False):
            rows[name].append(value)
        rows["xi_x"].append(vx / abs(u["Vx"][i]))  # for plots; not compared
    out = {"time": scene.grid[k], "xi_x": np.asarray(rows["xi_x"])}
    out.update({n: np.asarray(rows[n]) for n in ref.tolerance if n in rows})
    return out


# Bracket of the creepage root, in units of xi_ref = mu P/(G c^2): full slip sets in
# near 0.5 for Hertzian contacts (docs/halfspace.md), so the force there is mu P up to
# the elastic part of the slip (1e-4 of mu P and less).
CREEPAGE_BRACKET = 3.0
# Tolerance of that root in units of xi_ref: far below the table's interpolation error
# it is compared with (1e-3 of xi_ref and more).
CREEPAGE_XTOL = 1e-6


def by_halfspace_creepage(scene: Scene, ref: Reference, case: Case) -> dict[str, FloatArray]:
    k = _samples(scene, ref)
    u = _held_inputs(scene, case)
    if np.any(u["Fy_ex"] != 0.0) or np.any(u["Mz_ex"] != 0.0):
        raise ValueError(f"{scene.name}: source 'halfspace_creepage' is longitudinal only")
    Tx = make_body(case.parameters).tx_quasistationary(u["Fx_ex"][k], u["My_ex"][k])
    contact = _contacts(scene, case)
    spec = scene.config.table_spec
    mu = case.parameters.get("mu", spec.mu)
    xi, adhesion = np.empty(k.size), np.empty(k.size)
    for j, i in enumerate(k):
        key = (spec.key, mu, float(u["P"][i]), float(Tx[j]))
        if key not in _CREEPAGES:  # cases with the same demand share the root
            _CREEPAGES[key] = _creepage(contact(key[2]), key[3])
        xi[j], adhesion[j] = _CREEPAGES[key]
    return {"time": scene.grid[k], "Tx": Tx, "xi_x": xi, "adhesion": adhesion,
            "regime": np.zeros(k.size)}  # fmt: skip


# Roots found in this process: (declaration key, mu, P, Tx) -> (xi, adhesion fraction).
_CREEPAGES: dict[tuple[str, float, float, float], tuple[float, float]] = {}


def _creepage(contact, Tx: float) -> tuple[float, float]:
    """(xi, adhesion fraction) of the steady rolling state with longitudinal force Tx (N),
    |Tx| < mu P: Tx is odd and increasing in xi = vx/|Vx| (for either sign of Vx: the
    mirror of the contact), so the root lies in [0, CREEPAGE_BRACKET xi_ref]."""
    from scipy.optimize import brentq

    if Tx == 0.0:
        return 0.0, contact.solve(0.0).adhesion_fraction
    xi_ref = contact.mu * contact.P / (contact.elastic.G * contact.c**2)
    hi = CREEPAGE_BRACKET * xi_ref
    if contact.solve(hi).Tx <= abs(Tx):
        raise ValueError(f"Tx = {Tx!r} N is not reached below full slip (mu P)")
    xi = brentq(lambda x: contact.solve(x).Tx - abs(Tx), 0.0, hi, xtol=CREEPAGE_XTOL * xi_ref)
    return math.copysign(xi, Tx), contact.solve(xi).adhesion_fraction


def sliding_motion(scene: Scene, ref: Reference, case: Case) -> dict[str, FloatArray]:
    """Eqs. (8)-(9) in gross sliding, Tx = sign mu P (P = 0, lift-off: Tx = 0), with the
    held inputs constant over each step: Vx and Omega_y change by h (Fx_ex - Tx)/M and
    h (My_ex + Rx Tx)/Iy per step, summed from the initial state (no law, no stepper)."""
    p, u = case.parameters, _held_inputs(scene, case)
    sign = float(ref.options["sign"])
    Tx = sign * p["mu"] * u["P"]
    h = np.diff(scene.grid)
    Vx = p["Vx0"] + np.concatenate([[0.0], np.cumsum(h * (u["Fx_ex"] - Tx)[1:] / p["M"])])
    dO = h * (u["My_ex"] + p["Rx"] * Tx)[1:] / p["Iy"]
    Omega_y = initial_state(p)["Omega_y0"] + np.concatenate([[0.0], np.cumsum(dO)])
    k = _samples(scene, ref)
    return {"time": scene.grid[k], "Tx": Tx[k], "Vx": Vx[k], "Omega_y": Omega_y[k],
            "regime": np.ones(k.size)}  # fmt: skip


SOURCES: dict[str, Callable[[Scene, Reference, Case], dict[str, FloatArray]]] = {
    "quasistationary": quasistationary,
    "full_slip": full_slip,
    "sliding_motion": sliding_motion,
    "simulate": by_simulation,
    "traction": by_traction,
    "halfspace": by_halfspace,
    "halfspace_creepage": by_halfspace_creepage,
    "transient": by_transient,
}


def generate(scene: Scene, ref: Reference) -> dict[str, dict[str, FloatArray]]:
    """{case: {time, variables}} of one reference, from its source."""
    if ref.source not in SOURCES:
        raise ValueError(f"{scene.path}: unknown reference source {ref.source!r}")
    return {c: SOURCES[ref.source](scene, ref, scene.case(c)) for c in ref.cases}


def discretisation_error(scene: Scene, ref: Reference) -> dict[str, float]:
    """Richardson estimate of a discretisation error that a tolerance must cover.

    ``simulate``: the FMU's time-stepping error; SDIRK2 is second order, so at the
    FMU's internal step h_max it is about (4/3) |y(h_max) - y(h_max/2)|.
    ``traction``: the quadrature error of the reference itself on its grid, second
    order in the spacing: (4/3) |T(grid) - T(grid refined twice)|.
    The maximum over the reference's cases and points is returned per variable. It
    justifies the stored tolerances (see the scene files).
    """
    paths = {"simulate": (by_simulation, 1, 2), "traction": (by_traction, 1, 2)}
    if ref.source not in paths:
        raise ValueError(f"no discretisation error for source {ref.source!r}")
    path, a, b = paths[ref.source]
    est: dict[str, float] = {}
    for c in ref.cases:
        case = scene.case(c)
        coarse = path(scene, ref, case, refine=a)
        fine = path(scene, ref, case, refine=b)
        for var in ref.tolerance:
            e = float(np.max(np.abs(coarse[var] - fine[var]))) * 4.0 / 3.0
            est[var] = max(est.get(var, 0.0), e)
    return est


def regenerate(scene: Scene, out_dir: Path | None = None) -> list[Path]:
    """Write every reference of the scene (to its own file, or under ``out_dir``)."""
    written = []
    for ref in scene.references:
        path = ref.file if out_dir is None else Path(out_dir) / ref.file.name
        write_reference(path, generate(scene, ref))
        written.append(path)
    return written
