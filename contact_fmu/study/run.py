"""One case of a scene on an extracted FMU, step by step, with the status of each call.

Like ``scenario.runner.simulate_case`` (fmpy's simulate_fmu), but a run that the FMU
discards or fails keeps its status and the FMU's message: fmpy ends a run quietly at
fmi2Discard, and a study records why a run stopped. Inputs are set at each
communication point before the step, as fmpy does; outputs are recorded after it.
"""

from __future__ import annotations

import sys
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from ..scenario import runner
from ..scenario.instance import DISCARD, OK, WARNING, Instance
from ..scenario.schema import Case, Scene

FloatArray = NDArray[np.float64]
STATUS = {OK: "ok", WARNING: "warning", DISCARD: "discard", 3: "error", 4: "fatal"}


@dataclass
class Outcome:
    """Recorded columns (time, inputs, outputs) up to the last completed step, and
    "ok" or the reason the run stopped."""

    columns: dict[str, FloatArray] = field(default_factory=dict)
    status: str = "ok"

    @property
    def ok(self) -> bool:
        return self.status == "ok"


def _reason(code: int, t: float, messages: list[tuple[int, str]]) -> str:
    """The status and the FMU's first message of at least warning level (its cause)."""
    text = next((m for s, m in messages if s >= WARNING and m), "")
    text = text or next((m for _s, m in reversed(messages) if m), "no message")
    return f"{STATUS.get(code, str(code))} at t = {t:g} s: {text}"


def _reader(inst: Instance, names: tuple[str, ...]):
    """A function returning [(name, value)] of the outputs, one get call per type."""
    getters = {"Real": inst.fmu.getReal, "Integer": inst.fmu.getInteger,
               "Boolean": inst.fmu.getBoolean}  # fmt: skip
    groups: dict[str, tuple[list[str], list[int]]] = {}
    for n in names:
        v = inst.vars[n]
        if v.type not in getters:
            raise TypeError(f"output {n}: type {v.type} cannot be recorded")
        g = groups.setdefault(v.type, ([], []))
        g[0].append(n)
        g[1].append(v.valueReference)

    def read() -> list[tuple[str, float]]:
        out = []
        for t, (ns, vrs) in groups.items():
            out += zip(ns, (float(x) for x in getters[t](vrs)), strict=True)
        return out

    return read


def run_case(fmu_dir: Path, scene: Scene, case: Case, name: str = "run") -> Outcome:
    """Every step of ``case`` on the FMU extracted at ``fmu_dir``."""
    grid = scene.grid
    inputs = runner.input_table(scene, case)
    starts = runner.start_values(scene, case)
    starts.update({n: float(inputs[n][0]) for n in scene.inputs})
    cols = {"time": grid.copy()}
    rec = {n: np.full(grid.size, np.nan) for n in scene.outputs}
    path_before = list(sys.path)
    inst = None
    t, last = 0.0, -1  # the time of the step under way, the last recorded point
    try:
        inst = Instance(None, name=name, start_values=starts, unzip_dir=fmu_dir)
        in_vr = [inst.vars[n].valueReference for n in scene.inputs]
        read = _reader(inst, scene.outputs)
        for n, v in read():
            rec[n][0] = v
        h = scene.step
        last = 0
        for i in range(grid.size - 1):
            t = float(grid[i])
            if in_vr:
                inst.fmu.setReal(in_vr, [float(inputs[n][i]) for n in scene.inputs])
            code = inst.step(h, time=t)
            if code not in (OK, WARNING):
                status = _reason(code, t, inst.messages)
                break
            for n, v in read():
                rec[n][i + 1] = v
            last = i + 1
        else:
            status = "ok"
    except Exception as e:  # fmpy raises plain Exceptions for fmi2Error/Fatal calls
        msgs = inst.messages if inst is not None else []
        status = f"error: {type(e).__name__}: {e}" + (f" ({_reason(3, t, msgs)})" if msgs else "")
    finally:
        if inst is not None:
            try:
                inst.close()
            except Exception:  # noqa: S110 - an instance after fmi2Error may refuse terminate
                pass
        # pythonfmu prepends the FMU's resources folder to sys.path at every
        # instantiation: in a long-lived worker it would grow by one entry per run
        sys.path[:] = path_before + [p for p in dict.fromkeys(sys.path) if p not in path_before]
    keep = slice(0, last + 1)
    cols["time"] = cols["time"][keep]
    for n in scene.inputs:
        cols[n] = np.asarray(inputs[n], float)[keep]
    for n in scene.outputs:
        cols[n] = rec[n][keep]
    if status == "ok":
        bad = [n for n, v in cols.items() if not np.all(np.isfinite(v))]
        if bad:
            status = f"error: non-finite values in {bad}"
    return Outcome(cols, status)
