"""Run a scene's FMU with fmpy and compare the result with the scene's references.

The runner knows no physics: it samples the scene's input signals on the
communication grid, passes them and the case parameters to ``fmpy.simulate_fmu``,
and compares recorded values with the stored reference tables within the stored
tolerances.
"""

from __future__ import annotations

import csv
import shutil
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import fmpy
import numpy as np
from numpy.typing import NDArray

from .schema import Case, Reference, Scene

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class CaseResult:
    """Recorded values of one case on the grid: time, inputs and outputs (SI)."""

    case: str
    columns: dict[str, FloatArray]
    error: str | None = None


@dataclass(frozen=True)
class Check:
    """One variable of one case against one reference."""

    reference: str
    case: str
    variable: str
    max_error: float
    tolerance: float
    worst_time: float
    points: int

    @property
    def ok(self) -> bool:
        return self.points > 0 and self.max_error <= self.tolerance


def input_table(scene: Scene, case: Case) -> np.ndarray:
    """fmpy's input: a structured array with time and one column per input."""
    t = scene.grid
    table = np.zeros(t.size, dtype=[("time", float)] + [(n, float) for n in scene.inputs])
    table["time"] = t
    for name in scene.inputs:
        table[name] = case.inputs[name](t)
    return table


def start_values(scene: Scene, case: Case, field_dir: Path | None = None) -> dict[str, Any]:
    """Every parameter of the case (and the stepper and scheme, when the FMU offers several);
    with ``field_dir``, the file and times of the scene's field output (one file per case)."""
    values = dict(case.parameters)
    if len(scene.config.methods) > 1:
        values["method"] = case.method
    if len(scene.config.schemes) > 1:
        values["scheme"] = case.scheme
    if scene.field is not None and field_dir is not None:
        values["field_file"] = str(scene.field.path(Path(field_dir).resolve(), case.name))
        values["field_times"] = " ".join(repr(t) for t in scene.field.times)
    return values


def simulate_case(
    fmu_dir: Path, scene: Scene, case: Case, field_dir: Path | None = None
) -> CaseResult:
    """Run one case of the scene on the extracted FMU ``fmu_dir`` (field files, if the
    scene asks for them, under ``field_dir``)."""
    inputs = input_table(scene, case)
    try:
        res = fmpy.simulate_fmu(
            str(fmu_dir),
            start_values=start_values(scene, case, field_dir),
            input=inputs,
            output=list(scene.outputs),
            stop_time=scene.stop_time,
            output_interval=scene.step,
        )
    except Exception as e:  # fmpy raises plain Exceptions for FMI errors
        return CaseResult(case.name, {}, error=f"{type(e).__name__}: {e}")
    cols = {"time": np.asarray(res["time"], float)}
    if cols["time"].size != scene.grid.size or not np.allclose(cols["time"], scene.grid):
        return CaseResult(case.name, cols, error="fmpy did not return the scene's time grid")
    for name in scene.inputs:
        cols[name] = inputs[name]
    for name in scene.outputs:
        cols[name] = np.asarray(res[name], float)
    bad = [n for n, v in cols.items() if not np.all(np.isfinite(v))]
    if bad:
        return CaseResult(case.name, cols, error=f"non-finite values in {bad}")
    return CaseResult(case.name, cols)


def simulate(fmu: Path, scene: Scene, field_dir: Path | None = None) -> list[CaseResult]:
    """Every case of the scene on the FMU file ``fmu`` (extracted once); the scene's field
    files, if any, are written under ``field_dir`` (none without it)."""
    tmp = Path(tempfile.mkdtemp(prefix=f"{scene.name}-"))
    try:
        fmpy.extract(str(fmu), str(tmp))
        return [simulate_case(tmp, scene, c, field_dir) for c in scene.cases]
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


def read_reference(path: Path) -> dict[str, dict[str, FloatArray]]:
    """A reference CSV (columns case, time, variables) as {case: {column: values}}."""
    rows: dict[str, dict[str, list[float]]] = {}
    with path.open(newline="") as f:
        reader = csv.DictReader(f)
        for row in reader:
            case = row.pop("case")
            d = rows.setdefault(case, {k: [] for k in row})
            for k, v in row.items():
                d[k].append(float(v) if v != "" else np.nan)
    return {c: {k: np.asarray(v, float) for k, v in d.items()} for c, d in rows.items()}


def write_reference(path: Path, tables: dict[str, dict[str, FloatArray]]) -> None:
    """Write {case: {time, variables...}} as a reference CSV (17 significant digits)."""
    names = sorted({k for d in tables.values() for k in d if k != "time"})
    path.parent.mkdir(parents=True, exist_ok=True)
    with path.open("w", newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(["case", "time", *names])
        for case, d in tables.items():
            for i in range(d["time"].size):
                w.writerow(
                    [case, repr(float(d["time"][i]))]
                    + [repr(float(d[n][i])) if n in d else "" for n in names]
                )


def compare(scene: Scene, results: list[CaseResult]) -> list[Check]:
    """Every (reference, case, variable) of the scene against the recorded results."""
    by_case = {r.case: r for r in results}
    checks = []
    for ref in scene.references:
        table = read_reference(ref.file)
        for case in ref.cases:
            rows = table.get(case, {})
            got = by_case.get(case)
            for var, tol in ref.tolerance.items():
                checks.append(_check(ref, case, var, tol, rows, got))
    return checks


def _check(
    ref: Reference,
    case: str,
    var: str,
    tol: float,
    rows: dict[str, FloatArray],
    got: CaseResult | None,
) -> Check:
    label = f"{ref.file.name} ({ref.source})"
    if got is None or got.error or var not in rows or var not in got.columns:
        return Check(label, case, var, np.inf, tol, np.nan, 0)
    t_ref, y_ref = rows["time"], rows[var]
    keep = np.isfinite(y_ref)
    t_ref, y_ref = t_ref[keep], y_ref[keep]
    y = np.interp(t_ref, got.columns["time"], got.columns[var])
    err = np.abs(y - y_ref)
    if err.size == 0:
        return Check(label, case, var, np.inf, tol, np.nan, 0)
    i = int(np.argmax(err))
    return Check(label, case, var, float(err[i]), tol, float(t_ref[i]), int(err.size))


def write_csv(path: Path, scene: Scene, results: list[CaseResult]) -> None:
    """All cases in one CSV: case, time, inputs, outputs."""
    names = ["time", *scene.inputs, *scene.outputs]
    path.parent.mkdir(parents=True, exist_ok=True)
    with path.open("w", newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(["case", *names])
        for r in results:
            if r.error:
                continue
            for i in range(r.columns["time"].size):
                w.writerow([r.case, *(repr(float(r.columns[n][i])) for n in names)])
