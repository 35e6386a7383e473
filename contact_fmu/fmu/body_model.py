"""Body mode: the FMU owns the rigid-body dynamics (Eqs. 8-11) and the contact law.

The stepper (``integrator.RollingBody`` for the steady phase) is driven through its
small interface: ``set_load(P)``, ``advance(h, loads, substeps)``, ``outputs()``,
``snapshot()``/``restore()``. A communication step h is split into
ceil(h / h_max) stepper steps with the loads held constant (zero-order hold); the stiff
slip equation is handled by the stepper's L-stable scheme, so any h is stable and
h_max only sets the accuracy of the slow dynamics.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from .. import native
from .._validate import InputError
from ..dynamics.body import Loads
from ..dynamics.integrator import RollingBody, WorkBudgetError
from ..dynamics.kinematics import V_CREEP_FLOOR
from . import messages as words
from .config import ModelConfig
from .factory import initial_state, make_body, make_lateral, make_law
from .ranges import within_range

# The work of one doStep is bounded by the parameter max_work (variables.py), counted in
# work units: an internal step costs WORK_SCALAR (vx the only unknown: compiled, 1 to 3
# us here) or WORK_VECTOR (Vy and/or Omega_z as unknowns, Eqs. 10-11, or a held spin on
# the thin-layer law: each stage solve evaluates the law on its spin grid, 0.3 ms
# compiled, up to 7 ms where a hostile step takes many Newton iterations; 30 ms where
# Python solves it), the transient field's
# one nx ny WORK_PER_CELL (0.6 us per cell compiled here, 15 us in Python). Beyond the
# budget h_max is enlarged for that step (the scheme stays stable; only the accuracy of
# the slow dynamics drops), so that one doStep cannot take unbounded time: at the
# default, well under a second on every path (docs/reliability.md, "Worst-case time").
MAX_WORK = 10_000
WORK_SCALAR = 1
WORK_VECTOR = 200
WORK_PER_CELL = 2
# Where Python solves the stages (where the compiled path declines a step, or is not
# there; the transient field), each evaluation of the law counts too: WORK_SCALAR_EVAL
# (20 to 80 us here), WORK_VECTOR_EVAL (0.6 to 1.3 ms on the spin grid), or nx ny
# WORK_PER_CELL_EVAL for the field. A step takes about 3 (scalar), 4 to 8 (vector) or 6
# (field) evaluations; a hostile one up to hundreds (the Newton iterations of its
# stages), and the evaluations beyond the budget discard the step (WorkBudgetError).
WORK_SCALAR_EVAL = 3
WORK_VECTOR_EVAL = 25
WORK_PER_CELL_EVAL = 0.125
# Most internal steps of the scalar path at the default budget (its cap before any
# parameter sets another: stepper.c's CF_MAX_SUBSTEPS).
MAX_SUBSTEPS = MAX_WORK // WORK_SCALAR
# h / h_max within this relative margin of an integer does not add a step.
SUBSTEP_SLACK = 1e-9


def substeps(h: float, h_max: float, cap: int = MAX_SUBSTEPS) -> int:
    """ceil(h / h_max), at least 1, at most ``cap``."""
    n = math.ceil(h / h_max * (1.0 - SUBSTEP_SLACK))
    return min(max(n, 1), cap)


def marches_spin(stepper: Any) -> bool:
    """Whether the stepper's law marches its spin grid in every evaluation: a held spin
    ratio on the thin-layer law (the law with ``native_strips``)."""
    lateral = getattr(stepper, "lateral", None)
    spin = lateral is not None and bool(lateral.spin_ratio)
    return spin and hasattr(getattr(stepper, "law", None), "native_strips")


def step_cap(max_work: float, work: float) -> int:
    """Most internal steps of ``work`` units each within ``max_work`` (at least 1:
    stepper.c's max_substeps, the native FMU's the same from the same parameter)."""
    return max(1, int(max_work // work))


def make_stepper(
    cfg: ModelConfig, p: Mapping[str, Any], P: float, t0: float, data_dir: Path | None = None
) -> Any:
    """The stepper of the configured phase, law and method at the initial state; the
    law's generated data (a creep-force table) is read under ``data_dir`` (factory.py)."""
    if cfg.phase != "steady":  # ModelConfig admits only implemented phases
        raise InputError("phase", cfg.phase, '"steady"')
    return RollingBody(
        make_law(cfg, p, P, data_dir),
        make_body(p),
        make_lateral(cfg, p),
        method=p.get("method", cfg.methods[0]),
        **initial_state(p),
        t0=t0,
        scheme=p.get("scheme", cfg.schemes[0]),
    )


class BodyModel:
    """The body of the body-mode FMU: outputs are states, no direct feedthrough."""

    feedthrough = False

    def __init__(self, stepper: Any, h_max: float, P: float, max_work: float = MAX_WORK) -> None:
        self.stepper = stepper
        self.h_max = h_max
        self.P = P
        self.max_work = max_work
        # Vy and/or Omega_z as stage unknowns (native CF_DYN_VY, CF_DYN_SPIN), or a held
        # spin on the thin-layer law: each evaluation marches the spin grid (CF_HELD_SPIN
        # without CF_TABLE; the table's spin is a lookup)
        vector = len(getattr(stepper, "_idx", ())) > 1 or marches_spin(stepper)
        self.work = WORK_VECTOR if vector else WORK_SCALAR
        self.cap = step_cap(max_work, self.work)
        # the work of one evaluation of the law where Python solves the stages
        self.eval_work: float = WORK_VECTOR_EVAL if vector else WORK_SCALAR_EVAL

    def step(self, h: float, inputs: Mapping[str, float]) -> str | None:
        P = inputs["P"]
        if P != self.P:
            self.stepper.set_load(P)
            self.P = P
        loads = Loads(*[inputs.get(k, 0.0) for k in Loads._fields])
        n = self.internal_steps(h)
        self.stepper.eval_limit = max(1, int(self.max_work // self.eval_work))
        try:
            self.stepper.advance(h, loads, n)
        except WorkBudgetError as e:
            why = words.BEYOND_MAX_WORK(max_work=self.max_work, work=self.eval_work)
            raise WorkBudgetError(e.limit, why) from None
        within_range(self.stepper.outputs())
        if n == self.cap and self.beyond_cap(h):
            return self.cap_note(h, n, words.CAP_LIMITS(h_max=self.h_max))
        return None

    def beyond_cap(self, h: float) -> bool:
        """Whether h needs more internal steps than the budget allows (stepper.c's test,
        instance.c's note)."""
        return h / self.h_max > self.cap

    def cap_note(self, h: float, n: int, limits: str) -> str:
        """The warning of a step taken in the budget's n steps (the native FMU's words)."""
        return words.CAP_NOTE(h=h, limits=limits, max_work=self.max_work, work=self.work, n=n,
                          step=h / n)  # fmt: skip

    def fast(self) -> native.FastBody | None:
        """The whole step in compiled code (contact_fmu/native) where the stepper's path
        is covered, else None. Same results as ``step`` + ``outputs``."""
        kernel = getattr(self.stepper, "_kernel", None)
        if kernel is None or isinstance(kernel, native.VectorKernel):  # cf_body_step: scalar
            return None
        if self.stepper.lateral.spin_ratio:  # cf_body_outputs' adhesion has no spin march
            return None
        constants = {
            "v_creep_floor": V_CREEP_FLOOR,
            "substep_slack": SUBSTEP_SLACK,
            "max_substeps": self.cap,
        }
        return native.FastBody(kernel, self.stepper, self.h_max, constants)

    def internal_steps(self, h: float) -> int:
        """Stepper steps for a communication step h (s): ceil(h / h_max), at most the
        budget's."""
        return substeps(h, self.h_max, self.cap)

    def evaluate(self, inputs: Mapping[str, float]) -> None:  # no feedthrough
        return None

    def tune(self, params: Mapping[str, Any]) -> None:
        """mu from the next step on (a wet or contaminated patch)."""
        if "mu" in params:
            self.stepper.set_mu(params["mu"])

    def outputs(self) -> dict[str, float]:
        return self.stepper.outputs()

    def snapshot(self) -> Any:
        return (self.stepper.snapshot(), self.P)

    def restore(self, snap: Any) -> None:
        stepper_snap, self.P = snap
        self.stepper.restore(stepper_snap)


def build(
    cfg: ModelConfig,
    params: Mapping[str, Any],
    inputs: Mapping[str, float],
    t0: float,
    data_dir: Path | None = None,
) -> BodyModel:
    """The body model from the FMU's parameters and inputs at the start time t0 (s)."""
    P = inputs["P"]
    stepper = make_stepper(cfg, params, P, t0, data_dir)
    within_range(stepper.outputs(), start=True)
    return BodyModel(stepper, params["h_max"], P, params.get("max_work", MAX_WORK))
