"""The interface the C code of contact_fmu/native shares with Python, declared once.

Two users see the same bytes: the C files (stepper.c and the native FMU's model.c and
instance.c, through stepper.h) and the ctypes binding of ``contact_fmu.native``, which
fills and reads the structs in place. From the declarations here come

- ``cf_abi.h``, committed next to this file and included by stepper.h: the structs, the
  order of a body step's outputs (``cf_body.out``) and the constants of the Python
  numerics the C code reads, each as the literal that reads back to its Python double
  (``repr``); written by ``python -m contact_fmu.native.abi_header --write``;
- ``fields(name)``: a struct's ctypes ``_fields_`` (``native.Params``, ``State``, ...,
  and field.py's ``Field``, ``StageIn``, ``StageOut``, ``Body``, ``BodyState``).

A field is (name, C type, comment) or (name, C type, length, comment) for an array; the
C types are those of ``CTYPES``. A constant is (C name, C type, Python home, comment):
its value is read from the home module (``module.ATTRIBUTE``, relative to contact_fmu)
when the header is written, never copied here. tests/test_native_abi.py checks that the
committed header is this module's, that the compiler's sizes and offsets are ctypes',
and that the compiled constants are the Python doubles.

Only the standard library is imported here (the homes are imported by ``constants``,
when the header is written): the binding imports this module, and the FMU's vendored
copy of the package carries it without the homes' closure.
"""

from __future__ import annotations

import ctypes
import importlib
import textwrap
from pathlib import Path
from typing import Any

HEADER = Path(__file__).with_name("cf_abi.h")
COMMAND = "python -m contact_fmu.native.abi_header --write"  # abi_header.py
WIDTH = 100  # the project's line length
TEXT = 88  # a comment block's text

# C type -> ctypes type (pointers are passed as addresses: c_void_p)
CTYPES: dict[str, Any] = {
    "double": ctypes.c_double,
    "int": ctypes.c_int,
    "const double *": ctypes.c_void_p,
    "const void *": ctypes.c_void_p,
    "long long": ctypes.c_longlong,
    "double *": ctypes.c_void_p,
    "unsigned char *": ctypes.c_void_p,
    "const unsigned char *": ctypes.c_void_p,
}

# ---- a body step's outputs: RollingBody.outputs() keys, in the order of cf_body.out -----
# (Python key, C index, comment)
OUTPUTS: tuple[tuple[str, str, str], ...] = (
    ("Vx", "O_VX", "the body's speed (m/s)"),
    ("Vy", "O_VY", "its lateral speed (m/s)"),
    ("Omega_y", "O_OMEGA_Y", "its rolling rate (rad/s)"),
    ("Omega_z", "O_OMEGA_Z", "its spin rate (rad/s)"),
    ("Tx", "O_TX", "the contact's longitudinal force (N)"),
    ("Ty", "O_TY", "its lateral force (N)"),
    ("Mz", "O_MZ", "its spin moment (N m)"),
    ("vx", "O_VX_SLIP", "the longitudinal slip velocity (m/s)"),
    ("vy", "O_VY_SLIP", "the lateral one (m/s)"),
    ("xi_x", "O_XI_X", "the creepages vx/|Vx| ..."),
    ("xi_y", "O_XI_Y", "... vy/|Vx| ..."),
    ("xi_sp", "O_XI_SP", "... and the spin creepage (1/m)"),
    ("a1", "O_A1", "the contact's half-length (m)"),
    ("a2", "O_A2", "its half-width (m)"),
    ("p0", "O_P0", "its peak pressure (Pa)"),
    ("adhesion", "O_ADHESION", "the adhesion area's fraction"),
    ("regime", "O_REGIME", "the regime's code"),
)
# the array lengths a field may name, with their values
LENGTHS = {"N_OUT": len(OUTPUTS)}

# ---- the structs: name -> (what it is, fields) -----------------------------------------
STRUCTS: dict[str, tuple[str, list[tuple]]] = {
    "cf_params": (
        "The parameters of a step (stepper.c): the body, the law at its load, the path and "
        "the constants of the Python numerics (dynamics/integrator.py, dynamics/solvers.py, "
        "laws/thin_layer.py), passed so that they live once (the ctypes Kernel from the "
        "Python values, the native FMU from the CF_* above: model.c's cf_model_constants). "
        "native.Params.",
        [
            ("M", "double", "kg: the body's mass"),
            ("Rx", "double", "m: its rolling radius"),
            ("A1", "double", "Eq. (23)"),
            ("A2", "double", "Eq. (23)"),
            ("m_slip", "double", "kg: M A2, the slip's mass"),
            ("mu", "double", "the law: coefficient of friction"),
            ("P", "double", "N: the normal load"),
            ("a1", "double", "m: the contact's half-length"),
            ("creep_full_slip", "double", "the creepage of full slip (laws/thin_layer.py)"),
            ("beta_per_creep", "double", "beta per unit creepage (laws/thin_layer.py)"),
            ("ry", "double", "held ratio vy/Vx (Lateral.vy_ratio; the spin ratio: rz)"),
            ("v_standstill", "double", "dynamics.integrator.V_STANDSTILL (m/s)"),
            ("v_scale_floor", "double", "dynamics.integrator.V_SCALE_FLOOR (m/s)"),
            ("z_algebraic", "double", "dynamics.integrator.Z_ALGEBRAIC"),
            ("capacity_margin", "double", "dynamics.integrator.CAPACITY_MARGIN"),
            ("solve_rtol", "double", "dynamics.solvers.SOLVE_RTOL"),
            ("expand", "double", "dynamics.solvers.EXPAND"),
            ("beta_full_slip", "double", "laws.thin_layer.BETA_FULL_SLIP"),
            ("beta_series", "double", "laws.thin_layer.BETA_SERIES"),
            ("max_newton", "int", "dynamics.solvers.MAX_NEWTON"),
            ("quasistationary", "int", 'method: 1 "quasistationary", 0 "full"'),
            ("law", "int", "LAW_LAYER or LAW_TABLE (stepper.h)"),
            (
                "coef",
                "const double *",
                "LAW_TABLE (halfspace/table.py CreepTable at P): "
                "its Hermite patches (n1-1, n2-1, n3-1, 64, 4)",
            ),  # fmt: skip
            ("ax1", "const double *", "its axes (n1), (n2), (n3)"),
            ("ax2", "const double *", ""),
            ("ax3", "const double *", ""),
            ("n1", "int", "the axes' lengths"),
            ("n2", "int", ""),
            ("n3", "int", ""),
            ("ext1", "double", "the box: the axes' last nodes"),
            ("ext2", "double", ""),
            ("ext3", "double", ""),
            ("xi_ref", "double", "the table's units: creepage ..."),
            ("phi_ref", "double", "... spin (1/m) ..."),
            ("c", "double", "... and force"),
            ("saturation_width", "double", "halfspace.table.SATURATION_WIDTH"),
            ("Iz", "double", "kg m^2: the vector path (cf_advance_vector)"),
            ("rz", "double", "1/m: the held spin ratio"),
            ("dyn_vy", "int", "1: Vy (Eq. 10) is a stage unknown"),
            ("dyn_spin", "int", "1: Omega_z (Eq. 11) is a stage unknown"),
            (
                "strips",
                "const void *",
                "the thin-layer law's spin grid (a cf_strips; NULL for the table)",
            ),  # fmt: skip
            ("fd_step", "double", "dynamics.solvers.FD_STEP: the forward-difference step"),
            ("line_search_min", "double", "dynamics.solvers.LINE_SEARCH_MIN"),
            ("contraction_max", "double", "dynamics.solvers.CONTRACTION_MAX: keep a Jacobian ..."),
            ("contraction_fast", "double", "dynamics.solvers.CONTRACTION_FAST: ... or renew it"),
            ("newton_iterations", "int", "dynamics.solvers.NEWTON_ITERATIONS"),
            (
                "algebraic_key",
                "double",
                "dynamics.integrator.ALGEBRAIC: the key of a kept Newton matrix of the "
                "algebraic stage",
            ),  # fmt: skip
            (
                "bracket",
                "int",
                "1: a scalar stage whose Newton iteration does not converge "
                "is solved here by solvers.increasing_root (its bracket search, then brentq), "
                "as the Python path does; 0: CF_FALLBACK, the Python path solves it",
            ),  # fmt: skip
            ("max_expansions", "int", "dynamics.solvers.MAX_EXPANSIONS"),
            ("gamma", "double", "dynamics.integrator.GAMMA: SDIRK2's 1 - 1/sqrt(2)"),
            ("sdirk", "int", "the scheme: 0 Lobatto IIIC, 1 SDIRK2 (integrator.SCHEMES)"),
            ("Iy", "double", "kg m^2: the body's inertia, for the free step at P = 0"),
            # ---- a creep-force table of several load nodes (the native FMU's) ----
            (
                "n_loads",
                "int",
                "LAW_TABLE: its load nodes; 0 or 1: coef is the table at P (one node, or "
                "blended by Python: CreepTable._coefficients_at), else coef holds each "
                "node's patches in turn, blended at P by the weights of the spline below",
            ),  # fmt: skip
            ("spline_k", "int", "the spline's degree (CreepTable._weights: min(3, n - 1))"),
            (
                "spline",
                "const double *",
                "log P of the first and last node, the knots (n + k + 1), the coefficients "
                "(n x n, row major) of make_interp_spline(log P_j, eye(n), k), the onsets "
                "of full slip (n)",
            ),  # fmt: skip
        ],
    ),
    "cf_state": (
        "The state of the scalar path (cf_advance): RollingBody's y, t and _dv, its last "
        "ContactOutputs and regime. native.State.",
        [
            ("Vx", "double", "m/s: y[0]"),
            ("vx", "double", "m/s: y[1]"),
            ("t", "double", "s"),
            ("dv", "double", "RollingBody._dv"),
            ("Tx", "double", "N: out, ContactOutputs"),
            ("Ty", "double", "N"),
            ("Mz", "double", "N m"),
            ("out_sliding", "int", "out.sliding"),
            ("sliding", "int", "RollingBody.sliding (quasistationary gross sliding)"),
        ],
    ),
    "cf_body": (
        "A communication step of the body (fmu/body_model.py, cf_body_step): the inputs "
        "held over it, the parameters, the outputs of RollingBody.outputs(). "
        "native.BodyIO.",
        [
            ("P", "double", "N: inputs held over the step ..."),
            ("Fx_ex", "double", "N"),
            ("My_ex", "double", "N m (Fy_ex, Mz_ex: no effect on this path)"),
            ("h_max", "double", "s: parameter, the largest internal step"),
            ("a2", "double", "m: the law's, reported"),
            ("p0", "double", "Pa: the law's, reported"),
            ("v_creep_floor", "double", "dynamics.kinematics.V_CREEP_FLOOR (m/s)"),
            ("substep_slack", "double", "body_model.SUBSTEP_SLACK"),
            ("max_substeps", "int", "body_model.MAX_SUBSTEPS"),
            ("out", "double", "N_OUT", "the outputs, indexed by O_*"),
        ],
    ),
    "cf_strips": (
        "laws.thin_layer._Grid.march: the strip march of the spin law on its grid. native.Strips.",
        [
            ("ny", "int", "nodes across ..."),
            ("nx", "int", "... and along"),
            ("x", "const double *", "m: node coordinates (nx) ..."),
            ("y", "const double *", "... and (ny)"),
            ("dist", "const double *", "(ny x nx): distance marched ..."),
            ("mid", "const double *", "... midpoint ..."),
            ("cap", "const double *", "... and mu p"),
            ("w", "const double *", "(ny x nx): resultant weights"),
            ("k", "double", "m/Pa: kb + ks"),
            ("tiny", "double", "laws.thin_layer.TINY"),
        ],
    ),
    "cf_vstate": (
        "The state of the vector path (cf_advance_vector: Vy and/or Omega_z as stage "
        "unknowns). native.VState.",
        [
            ("Vx", "double", "m/s: y of RollingBody ..."),
            ("vx", "double", "m/s"),
            ("Vy", "double", "m/s"),
            ("Oz", "double", "rad/s: Omega_z"),
            ("t", "double", "s"),
            ("dv", "double", "RollingBody._dv"),
            ("Tx", "double", "N: out, ContactOutputs"),
            ("Ty", "double", "N"),
            ("Mz", "double", "N m"),
            ("out_sliding", "int", "out.sliding"),
            ("jac_valid", "int", "RollingBody._jac: (jac_h, J) kept, or none"),
            ("jac_h", "double", "its key"),
            ("J", "double", 36, "2n x 2n (n x n for the algebraic stage), row major"),
            ("sliding", "int", "RollingBody.sliding (quasistationary gross sliding)"),
        ],
    ),
    "cf_field": (
        "The thin-layer transient field's grid and law (field.c; "
        "dynamics.thin_layer_field.LayerField: nx cells of dx over the lattice's half-extent "
        "X, ny strips at y; law a1, p0, mu, k = kb + ks). "
        "Per strip: ell = l(y) (Eq. 37), p_strip = p0 (1 - y^2/a2^2) (p at x = 0), dy_w the "
        "scaled strip width (LayerField._update_contact). c0 = mu p0/a1^2 (mu p = c0 (l^2 - "
        "x^2), Eq. 33). field.Field.",
        [
            ("ny", "int", "strips across 2 a2 ..."),
            ("nx", "int", "... and cells along the lattice"),
            ("dx", "double", "m: the cell"),
            ("X", "double", "m: the lattice's half-extent"),
            ("a1", "double", "m: the law's half-length"),
            ("p0", "double", "Pa: its peak pressure"),
            ("mu", "double", "its coefficient of friction"),
            ("k", "double", "m/Pa: kb + ks"),
            ("c0", "double", "Pa/m^2: mu p0/a1^2"),
            ("min_speed_fraction", "double", "dynamics.thin_layer_field.MIN_SPEED_FRACTION"),
            ("y", "const double *", "(ny): the strips' y (m) ..."),
            ("ell", "const double *", "... l(y) (m) ..."),
            ("p_strip", "const double *", "... p at x = 0 (Pa) ..."),
            ("dy_w", "const double *", "... and scaled widths (m)"),
        ],
    ),
    "cf_field_stage_in": (
        "A stage's inputs (LayerField.stage's arguments): the base of the step (theta, the "
        "inside mask, ny x nx row major, bytes 0/1), tau_hat in base indexing, the distance "
        "rolled ds (m), elapsed and h_own (s), the rigid slip (vx, vy) (m/s), phi = Omega_z "
        "(rad/s), Vx (m/s); midpath and jacobian as in LayerField.stage (0 or 1). "
        "field.StageIn.",
        [
            ("theta", "double", "the base's column offset (cells)"),
            ("inside", "const unsigned char *", "(ny x nx) the base's inside mask"),
            ("hat_x", "const double *", "(ny x nx) tau_hat (Pa) ..."),
            ("hat_y", "const double *", ""),
            ("ds", "double", "m: distance rolled"),
            ("elapsed", "double", "s"),
            ("h_own", "double", "s"),
            ("vx", "double", "m/s: the rigid slip ..."),
            ("vy", "double", ""),
            ("phi", "double", "rad/s: Omega_z"),
            ("Vx", "double", "m/s"),
            ("midpath", "int", "0 or 1"),
            ("jacobian", "int", "0 or 1: J wanted"),
        ],
    ),
    "cf_field_stage_out": (
        "A stage's results (StageField): theta and shift, column positions x (nx), traction, "
        "weights (ny x nx), the slip (slip & inside) and inside masks (bytes 0/1), the "
        "resultant T = (Tx, Ty, Mz), dTx/dvx and (with jacobian) J = d(Tx, Ty, Mz)/d(vx, vy, "
        "Omega_z), 3 x 3 row major. work: scratch of 5 ny nx + 3 nx doubles. field.StageOut.",
        [
            ("theta", "double", "the stage's column offset"),
            ("shift", "long long", "columns moved"),
            ("x", "double *", "(nx) m"),
            ("tau_x", "double *", "(ny x nx) Pa ..."),
            ("tau_y", "double *", ""),
            ("w", "double *", "(ny x nx) m^2: weights"),
            ("slip", "unsigned char *", "(ny x nx) 0/1 ..."),
            ("inside", "unsigned char *", ""),
            ("work", "double *", "scratch"),
            ("T", "double", 3, "N, N, N m: the resultant"),
            ("dTx_dvx", "double", "N s/m"),
            ("J", "double", 9, "with jacobian: 3 x 3, row major"),
        ],
    ),
    "cf_field_body": (
        "The body (Eqs. 8-11) of a TransientRollingBody: vx a stage unknown, Vy and Omega_z "
        "held at the ratios ry, rz to Vx (Lateral) or unknowns too; the law's "
        "creep_full_slip; SDIRK2's gamma and a21 = 1 - gamma; solvers.SOLVE_RTOL, "
        "integrator.V_SCALE_FLOOR (m/s), MAX_STAGE_ITERATIONS. field.Body.",
        [
            ("M", "double", "kg"),
            ("Rx", "double", "m"),
            ("A1", "double", "Eq. (23)"),
            ("A2", "double", "Eq. (23)"),
            ("m_slip", "double", "kg: M A2"),
            ("ry", "double", "held Vy/Vx"),
            ("rz", "double", "held Omega_z/Vx (1/m)"),
            ("creep_full_slip", "double", "the law's"),
            ("gamma", "double", "SDIRK2's"),
            ("a21", "double", "1 - gamma"),
            ("solve_rtol", "double", ""),
            ("v_scale_floor", "double", "m/s"),
            ("max_iterations", "int", "of a stage solve"),
            # ---- Vy and/or Omega_z as stage unknowns too (the native FMU's) ----
            ("dyn_vy", "int", "1: Vy is a stage unknown (Eq. 10; ry unused), 0: held"),
            ("dyn_spin", "int", "1: Omega_z is one (Eq. 11; rz unused), 0: held"),
            ("Iz", "double", "kg m^2: with dyn_spin"),
            ("a1", "double", "m: the law's half-length (the spin's scale)"),
            (
                "eval_limit",
                "int",
                "with a stage unknown besides vx: the field's evaluations one advance may "
                "take (EvalBudget.eval_limit; beyond: CF_FIELD_BUDGET), 0: none",
            ),  # fmt: skip
        ],
    ),
    "cf_field_body_state": (
        "The state of cf_field_advance: y = (Vx, vx, Vy, Omega_z), t (s), the contact impulse "
        "(N s, N s, N m s), the field (theta, direction, tau_x, tau_y, slip: ny x nx, advanced "
        "in place), the contact at the end of the last step (T = (Tx, Ty, Mz), sliding: no "
        "adhesion), scratch (work: CF_FIELD_ADVANCE_WORK doubles, bytes: "
        "CF_FIELD_ADVANCE_BYTES). field.BodyState.",
        [
            ("y", "double", 4, "m/s, m/s, m/s, rad/s"),
            ("t", "double", "s"),
            ("impulse", "double", 3, "N s, N s, N m s"),
            ("theta", "double", "the lattice's column offset"),
            ("direction", "double", "sign of the last distance rolled"),
            ("tau_x", "double *", "(ny x nx) Pa ..."),
            ("tau_y", "double *", ""),
            ("slip", "unsigned char *", "(ny x nx) 0/1"),
            ("T", "double", 3, "N, N, N m"),
            ("sliding", "int", "no adhesion"),
            ("work", "double *", "scratch"),
            ("bytes", "unsigned char *", "scratch"),
        ],
    ),
}

# ---- the constants: (C name, C type, Python home, comment) ------------------------------
CONSTANTS: tuple[tuple[str, str, str, str], ...] = (
    ("CF_LOAD_LIMIT", "double", "dynamics.integrator.LOAD_LIMIT",
     "|Fx_ex|, |My_ex|/Rx <= this mu P"),
    ("CF_SPEED_MAX", "double", "fmu.variables.SPEED_MAX", "(m/s; ranges.within_range)"),
    ("CF_RATE_MAX", "double", "fmu.variables.RATE_MAX", "(rad/s)"),
    ("CF_TIME_RTOL", "double", "fmu.call_state.TIME_RTOL", "(doStep's time check, cf_time_ok)"),
    ("CF_V_STANDSTILL", "double", "dynamics.integrator.V_STANDSTILL", "(m/s)"),
    ("CF_V_SCALE_FLOOR", "double", "dynamics.integrator.V_SCALE_FLOOR", "(m/s)"),
    ("CF_Z_ALGEBRAIC", "double", "dynamics.integrator.Z_ALGEBRAIC", ""),
    ("CF_CAPACITY_MARGIN", "double", "dynamics.integrator.CAPACITY_MARGIN", ""),
    ("CF_ALGEBRAIC_KEY", "double", "dynamics.integrator.ALGEBRAIC", ""),
    ("CF_GAMMA", "double", "dynamics.integrator.GAMMA", "(SDIRK2's 1 - 1/sqrt(2))"),
    ("CF_SOLVE_RTOL", "double", "dynamics.solvers.SOLVE_RTOL", ""),
    ("CF_EXPAND", "double", "dynamics.solvers.EXPAND", ""),
    ("CF_MAX_EXPANSIONS", "int", "dynamics.solvers.MAX_EXPANSIONS", ""),
    ("CF_MAX_NEWTON", "int", "dynamics.solvers.MAX_NEWTON", ""),
    ("CF_FD_STEP", "double", "dynamics.solvers.FD_STEP", ""),
    ("CF_LINE_SEARCH_MIN", "double", "dynamics.solvers.LINE_SEARCH_MIN", ""),
    ("CF_CONTRACTION_MAX", "double", "dynamics.solvers.CONTRACTION_MAX", ""),
    ("CF_CONTRACTION_FAST", "double", "dynamics.solvers.CONTRACTION_FAST", ""),
    ("CF_NEWTON_ITERATIONS", "int", "dynamics.solvers.NEWTON_ITERATIONS", ""),
    ("CF_BETA_FULL_SLIP", "double", "laws.thin_layer.BETA_FULL_SLIP", ""),
    ("CF_BETA_SERIES", "double", "laws.thin_layer.BETA_SERIES", ""),
    ("CF_V_CREEP_FLOOR", "double", "dynamics.kinematics.V_CREEP_FLOOR", "(m/s)"),
    ("CF_SUBSTEP_SLACK", "double", "fmu.body_model.SUBSTEP_SLACK", ""),
    ("CF_MAX_SUBSTEPS", "int", "fmu.body_model.MAX_SUBSTEPS", ""),
    ("CF_WORK_SCALAR", "int", "fmu.body_model.WORK_SCALAR", "(work units per internal step)"),
    ("CF_WORK_VECTOR", "int", "fmu.body_model.WORK_VECTOR", "(Eqs. 10-11: per internal step)"),
    ("CF_WORK_PER_CELL", "int", "fmu.body_model.WORK_PER_CELL", "(the field's step, per cell)"),
    ("CF_FIELD_A21", "double", "dynamics.thin_layer_field.A21", ""),
    ("CF_FIELD_MIN_SPEED_FRACTION", "double", "dynamics.thin_layer_field.MIN_SPEED_FRACTION", ""),
    ("CF_FIELD_MAX_ITERATIONS", "int", "dynamics.thin_layer_field.MAX_STAGE_ITERATIONS", ""),
    ("CF_FIELD_SHIFT_MAX", "double", "dynamics.thin_layer_field.SHIFT_MAX",
     "(columns a stage may roll the lattice by)"),
)  # fmt: skip


def fields(struct: str) -> list[tuple[str, Any]]:
    """The ctypes ``_fields_`` of the C struct ``struct`` (its fields, in order)."""
    out = []
    for f in STRUCTS[struct][1]:
        name, ctype, *length, _ = f
        t = CTYPES[ctype]
        if length:
            n = length[0]
            t = t * (LENGTHS[n] if isinstance(n, str) else n)
        out.append((name, t))
    return out


def _home(path: str) -> Any:
    """The value ``module.ATTRIBUTE`` of a constant's Python home (relative to the package
    this one is in: contact_fmu)."""
    module, _, attribute = path.rpartition(".")
    root = __package__.rpartition(".")[0]
    return getattr(importlib.import_module(f"{root}.{module}"), attribute)


def constants() -> dict[str, int | float]:
    """Each constant's value, read from its Python home: an int for C int, a float for C
    double (TypeError where the home holds another type)."""
    out: dict[str, int | float] = {}
    for name, ctype, home, _ in CONSTANTS:
        value = _home(home)
        if ctype == "int" and not (isinstance(value, int) and not isinstance(value, bool)):
            raise TypeError(f"{home} = {value!r} is declared int for {name}")
        if ctype == "double" and not isinstance(value, float):
            raise TypeError(f"{home} = {value!r} is declared double for {name}")
        out[name] = value
    return out


def literal(value: int | float) -> str:
    """A C literal of ``value`` that reads back to the same int or double (repr: the
    shortest decimal that rounds to it); ValueError for inf or NaN."""
    if isinstance(value, int):
        return f"({value})" if value < 0 else str(value)
    r = repr(float(value))
    if r in ("inf", "-inf", "nan"):
        raise ValueError(f"{r} has no C literal")
    r = r if "." in r or "e" in r else r + ".0"
    return f"({r})" if r[0] == "-" else r


def _comment(text: str, indent: str = "") -> list[str]:
    """``text`` as a C block comment of lines of at most WIDTH characters."""
    lines = textwrap.wrap(text, TEXT - len(indent))
    out = [f"{indent}/* {lines[0]}"] + [f"{indent} * {line}" for line in lines[1:]]
    out[-1] += " */"
    if len(out[-1]) > WIDTH:
        out[-1] = out[-1][:-3]
        out.append(f"{indent} */")
    return out


def _aligned(pairs: list[tuple[str, str]], indent: str = "") -> list[str]:
    """Declarations with their comments in one column (a comment that would not fit
    goes on the line above its declaration)."""
    column = max(len(indent + d) for d, _ in pairs) + 1
    out = []
    for decl, comment in pairs:
        line = indent + decl
        if not comment:
            out.append(line)
        elif len(line.ljust(column)) + len(comment) + 7 <= WIDTH:
            out.append(f"{line.ljust(column)} /* {comment} */")
        elif len(line) + len(comment) + 7 <= WIDTH:
            out.append(f"{line} /* {comment} */")
        else:
            out += [*_comment(comment, indent), line]
    return out


def _joined(home: str, comment: str) -> str:
    """A constant's comment: its home, then its note (a parenthesis, or after a colon)."""
    if not comment:
        return home
    return f"{home} {comment}" if comment[0] == "(" else f"{home}: {comment}"


def _declaration(field: tuple) -> str:
    name, ctype, *length, _ = field
    sep = "" if ctype.endswith("*") else " "
    return f"{ctype}{sep}{name}" + (f"[{length[0]}]" if length else "") + ";"


def header() -> str:
    """cf_abi.h: the constants, the outputs' order and the structs, from this module's
    declarations and the constants' Python homes."""
    lines = [
        f"/* Generated by `{COMMAND}` (from abi.py): do not edit. */",
        *_comment(
            "The types and constants the C code shares with Python (stepper.h includes this "
            "file; the ctypes structs of contact_fmu/native/__init__.py and field.py have the "
            "same fields from the same declarations). tests/test_native_abi.py compares this "
            "file with the generator's output, the compiler's sizes and offsets with ctypes', "
            "and the constants with their Python homes."
        ),
        "#ifndef CF_ABI_H",
        "#define CF_ABI_H",
        "",
        *_comment(
            "The constants of the Python numerics, each its home's double (or int) written "
            "as the literal that reads back to it."
        ),
    ]
    values = constants()
    lines += _aligned(
        [
            (f"#define {name} {literal(values[name])}", _joined(home, c))
            for name, _, home, c in CONSTANTS
        ]
    )
    lines += ["", "/* The outputs of RollingBody.outputs() in the order of cf_body.out. */"]
    lines += ["enum {"]
    lines += _aligned([(f"{c},", f"{key}: {text}") for key, c, text in OUTPUTS], "    ")
    lines += [f"    N_OUT = {len(OUTPUTS)}", "};"]
    for struct, (doc, declared) in STRUCTS.items():
        lines += ["", *_comment(doc), "typedef struct {"]
        lines += _aligned([(_declaration(f), f[-1]) for f in declared], "    ")
        lines += [f"}} {struct};"]
    lines += ["", "#endif"]
    return "\n".join(lines) + "\n"
