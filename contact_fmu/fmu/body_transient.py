"""Body mode, phase "transient": the body on the thin-layer traction field.

The stepper is ``thin_layer_field.TransientRollingBody``: the traction field of Eq. (15) with
its time-derivative term on a material grid of nx cells along the contact and ny
strips across it, advanced together with Eqs. (8)-(11) by an L-stable SDIRK2 step
(docs/transient.md). The field is part of the state (FMU get/set state restores it).
A communication step h is split into the larger of ceil(h/h_max) and the number of
steps that keeps each within ``cells_per_step`` cells at the present speed, loads held
(zero-order hold); any step is stable, these two only set the accuracy. An internal
step costs nx ny WORK_PER_CELL work units: at most max_work // that many are taken
(fewer, longer steps beyond: fmi2Warning), and a grid whose one step exceeds max_work
is refused at the step (fmi2Discard naming max_work); each evaluation of the field in
the stage solves costs nx ny WORK_PER_CELL_EVAL, and a step whose evaluations exceed
max_work is discarded (WorkBudgetError).

The field can be written to a CSV file (``field_file``) at chosen times
(``field_times``): at the end of the communication step that reaches each requested
time, one row per node of the field's grid,

    requested, time, i, j, x, y, tau_x, tau_y, p, slip, inside, weight

(s, s, strip index i (y), column index j (x), m, m, Pa, Pa, Pa, 0/1, 0/1, m^2): tau is
the traction the body exerts on the substrate (Eq. 8 convention), ``weight`` the
quadrature weight of the node in the resultant (sum weight tau = (Tx, Ty)). The file
is rewritten whole at each capture and after a restore of the FMU state, so it always
holds the captures of the trajectory the FMU is on.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from .._validate import InputError
from ..dynamics.thin_layer_field import TransientRollingBody
from . import messages as words
from .body_model import MAX_WORK, WORK_PER_CELL, WORK_PER_CELL_EVAL, BodyModel, substeps
from .config import ModelConfig
from .factory import initial_state, make_body, make_lateral, make_law
from .ranges import within_range

# CSV columns of the field file, in order.
FIELD_COLUMNS = (
    "requested",
    "time",
    "i",
    "j",
    "x",
    "y",
    "tau_x",
    "tau_y",
    "p",
    "slip",
    "inside",
    "weight",
)
# A requested time counts as reached by a step ending within this relative margin of
# it (the step's end is a sum of communication steps: rounding only).
TIME_RTOL = 1e-9


def parse_times(text: str) -> tuple[float, ...]:
    """The field times (s) of ``field_times``: numbers separated by spaces or commas,
    finite, sorted; InputError naming field_times otherwise."""
    parts = [p for p in re.split(r"[\s,;]+", str(text).strip()) if p]
    try:
        times = [float(p) for p in parts]
    except ValueError:
        raise InputError("field_times", text, words.FIELD_TIMES_SYNTAX()) from None
    if not all(math.isfinite(t) for t in times):
        raise InputError("field_times", text, words.FIELD_TIMES_FINITE())
    return tuple(sorted(times))


class FieldRecorder:
    """Captures of the traction field at requested times, written to a CSV file."""

    def __init__(self, path: str, times: tuple[float, ...]) -> None:
        self.path = Path(path) if path else None
        self.times = times if self.path is not None else ()
        self.captures: list[tuple[float, float, dict[str, np.ndarray]]] = []

    def capture_due(self, t: float, arrays: Any) -> bool:
        """Capture the field ``arrays()`` at time t (s) for every requested time reached
        and not yet captured; write the file if anything was captured."""
        before = len(self.captures)
        while len(self.captures) < len(self.times):
            wanted = self.times[len(self.captures)]
            if wanted > t + TIME_RTOL * max(1.0, abs(t)):
                break
            self.captures.append((wanted, t, arrays()))
        if len(self.captures) == before:
            return False
        try:
            self.write()
        except InputError:
            del self.captures[before:]  # the recorder's state is as before the call
            raise
        return True

    def write(self) -> None:
        """Write every capture (OSError names the file)."""
        if self.path is None:
            return
        rows = []
        for wanted, t, a in self.captures:
            ny, nx = a["tau_x"].shape
            j, i = np.meshgrid(np.arange(nx), np.arange(ny))
            X, Y = np.meshgrid(a["x"], a["y"])
            cols = (np.full(i.size, wanted), np.full(i.size, t), i.ravel(), j.ravel(),
                    X.ravel(), Y.ravel(), a["tau_x"].ravel(), a["tau_y"].ravel(),
                    a["p"].ravel(), a["slip"].ravel(), a["inside"].ravel(),
                    a["weights"].ravel())  # fmt: skip
            rows.append(np.column_stack(cols))
        table = np.vstack(rows) if rows else np.zeros((0, len(FIELD_COLUMNS)))
        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            fmt = ["%.17g", "%.17g", "%d", "%d"] + ["%.17g"] * 5 + ["%d", "%d", "%.17g"]
            np.savetxt(self.path, table, fmt=fmt, delimiter=",",
                       header=",".join(FIELD_COLUMNS), comments="")  # fmt: skip
        except OSError as e:
            raise InputError("field_file", str(self.path), words.REQ_FIELD_FILE(why=e)) from None

    def state(self) -> tuple:
        return tuple(self.captures)

    def set_state(self, s: tuple) -> None:
        """Restore the captures and rewrite the file (best effort: a file that cannot be
        written is reported by the next capture, not by a restore)."""
        changed = len(s) != len(self.captures)
        self.captures = list(s)
        if changed:
            try:
                self.write()
            except InputError:
                pass


class TransientBodyModel(BodyModel):
    """BodyModel with the transient stepper: internal steps also bounded in cells rolled,
    the field written at the requested times."""

    def __init__(
        self,
        stepper: TransientRollingBody,
        h_max: float,
        P: float,
        cells: float,
        recorder: FieldRecorder,
        max_work: float = MAX_WORK,
    ) -> None:
        super().__init__(stepper, h_max, P, max_work)
        self.cells = cells
        self.recorder = recorder
        field = stepper.field
        self.work = field.nx * field.ny * WORK_PER_CELL  # one internal step's cost
        self.cap = int(max_work // self.work)  # 0: not one step within the budget
        self.eval_work = field.nx * field.ny * WORK_PER_CELL_EVAL

    def needed_steps(self, h: float) -> int:
        """max(ceil(h/h_max), steps of at most ``cells`` cells at the present speed)."""
        by_cells = self.stepper.substeps_for(h, self.cells)
        return max(substeps(h, self.h_max, cap=2**62), by_cells)

    def internal_steps(self, h: float) -> int:
        """``needed_steps``, at most the budget's."""
        return min(self.needed_steps(h), self.cap)

    def beyond_cap(self, h: float) -> bool:
        return self.needed_steps(h) > self.cap

    def step(self, h: float, inputs: Mapping[str, float]) -> str | None:
        _in_contact(inputs["P"])
        if self.cap < 1:
            field = self.stepper.field
            raise InputError(
                "max_work",
                self.max_work,
                words.REQ_MAX_WORK_FIELD(work=self.work, nx=field.nx, ny=field.ny),
            )
        n = self.internal_steps(h)
        capped = n == self.cap and self.beyond_cap(h)
        note = super().step(h, inputs)
        if capped:
            limits = words.CAP_LIMITS_FIELD(h_max=self.h_max, cells=self.cells)
            note = self.cap_note(h, n, limits)
        self.recorder.capture_due(self.stepper.t, self.stepper.field_arrays)
        return note

    def snapshot(self) -> Any:
        return (super().snapshot(), self.recorder.state())

    def restore(self, snap: Any) -> None:
        body_snap, rec = snap
        super().restore(body_snap)
        self.recorder.set_state(rec)


def make_stepper(
    cfg: ModelConfig, p: Mapping[str, Any], P: float, t0: float, data_dir: Path | None = None
) -> TransientRollingBody:
    """The transient stepper at the initial state: field at rest (tau = 0)."""
    return TransientRollingBody(
        make_law(cfg, p, P, data_dir),
        make_body(p),
        make_lateral(cfg, p),
        **initial_state(p),
        t0=t0,
        nx=int(p["nx"]),
        ny=int(p["ny"]),
    )


def _in_contact(P: float) -> float:
    """P > 0, or InputError: the traction field (its grid over the ellipse, Eq. 34) needs
    a contact; lift-off (P = 0) is the steady phase's (docs/model.md, "Lift-off")."""
    if P == 0.0:
        raise InputError("P", P, words.REQ_LIFTOFF())
    return P


def build(
    cfg: ModelConfig,
    params: Mapping[str, Any],
    inputs: Mapping[str, float],
    t0: float,
    data_dir: Path | None = None,
) -> TransientBodyModel:
    """The transient body model from the FMU's parameters and inputs at t0 (s)."""
    P = _in_contact(inputs["P"])
    stepper = make_stepper(cfg, params, P, t0, data_dir)
    within_range(stepper.outputs(), start=True)
    recorder = FieldRecorder(str(params["field_file"]), parse_times(params["field_times"]))
    model = TransientBodyModel(
        stepper,
        params["h_max"],
        P,
        params["cells_per_step"],
        recorder,
        params.get("max_work", MAX_WORK),
    )
    recorder.capture_due(t0, stepper.field_arrays)
    return model
