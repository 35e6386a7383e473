"""A parameter study: every combination of the varied values times every case of a
scene, one task per run, on an ``Engine``; one row per run.

The scene's FMU is built (or taken from the content-hashed cache) once, here; each
worker process extracts it once (``engine.once``, by its content key) and runs all its
tasks on that copy. It reaches a worker by path when the worker shares this file system
(a LocalCluster, or ``share_by_path``), or as bytes sent once to each worker otherwise.
The base scene travels as its TOML data and is checked once per worker; each run applies
its values (``scenario.variation``) and steps the FMU (``run.run_case``).

Rows, in run order (combinations in the order of the varied names, the last varying
fastest; each combination's cases in the scene's order): ``run``, the varied values,
``case``, ``status`` ("ok", or why the run stopped: a rejected value, the FMU's
fmi2Discard/fmi2Error message; a failed run is a row, never a failed sweep), and the
scene's metrics (NaN for a failed run). The same inputs give the same rows for any
number of workers.
"""

from __future__ import annotations

import atexit
import hashlib
import itertools
import json
import math
import shutil
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ..scenario import variation
from ..scenario.schema import Metric, ScenarioError, Scene, Vary, from_data
from . import metrics as mt
from .engine import Engine, forget, once
from .run import run_case


@dataclass(frozen=True)
class Run:
    """One task: its index, the values of the varied names and the case."""

    index: int
    values: tuple[tuple[str, float], ...]
    case: str


@dataclass(frozen=True)
class FmuRef:
    """The scene's FMU as a worker finds it: its content key, its path, and its bytes
    when the worker may not see the path."""

    key: str
    path: str
    data: bytes | None = None


@dataclass(frozen=True)
class Context:
    """What every task of a sweep shares (sent once per worker)."""

    scene_path: str
    scene_source: dict[str, Any]
    scene_key: str
    fmu: FmuRef
    metrics: tuple[Metric, ...]
    trajectories: bool


def runs(scene: Scene, vary: tuple[Vary, ...]) -> list[Run]:
    """Every combination of the varied values times every case, in run order."""
    names = [v.name for v in vary]
    combos = itertools.product(*(v.values for v in vary))
    out = []
    for combo in combos:
        for case in scene.cases:
            out.append(Run(len(out), tuple(zip(names, combo, strict=True)), case.name))
    return out


def merge_vary(scene: Scene, extra: list[Vary]) -> tuple[Vary, ...]:
    """The scene's varied names, those of ``extra`` replacing or added after them."""
    by_name = {v.name: v for v in scene.sweep.vary}
    for v in extra:
        by_name[v.name] = v
    return tuple(by_name.values())


def _fmu_dir(ref: FmuRef) -> Path:
    """The FMU extracted in this process (once per content key)."""

    def extract() -> Path:
        import fmpy

        d = Path(tempfile.mkdtemp(prefix=f"study-{ref.key[:12]}-"))
        atexit.register(shutil.rmtree, d, True)
        src = Path(ref.path)
        if ref.data is not None:  # shipped: the worker may not see the path
            src = d / "shipped.fmu"
            src.write_bytes(ref.data)
        elif not src.is_file():
            raise FileNotFoundError(f"{ref.path}: not on this worker, and not shipped")
        fmpy.extract(str(src), str(d / "fmu"))
        return d / "fmu"

    return once(f"fmu:{ref.key}", extract)


def _base(ctx: Context) -> Scene:
    return once(f"scene:{ctx.scene_key}", lambda: from_data(ctx.scene_path, ctx.scene_source))


def run_one(ctx: Context, run: Run) -> dict[str, Any]:
    """One run as a row (never raises for a run's own failure)."""
    row: dict[str, Any] = {"run": run.index, **dict(run.values), "case": run.case}
    nan = {m.name: math.nan for m in ctx.metrics}
    try:
        scene = variation.apply(_base(ctx), dict(run.values))
    except ScenarioError as e:
        return {**row, "status": f"rejected: {e}", **nan}
    case = scene.case(run.case)
    out = run_case(_fmu_dir(ctx.fmu), scene, case, name=f"run{run.index}")
    row["status"] = out.status
    if out.ok:
        row.update({m.name: mt.value(m, out.columns, case.parameters) for m in ctx.metrics})
    else:
        row.update(nan)
    if ctx.trajectories:
        row["_columns"] = out.columns
    return row


def failed_row(ctx: Context, run: Run, exc: BaseException) -> dict[str, Any]:
    """The row of a task that raised or whose worker died (a crash in the FMU)."""
    return {
        "run": run.index,
        **dict(run.values),
        "case": run.case,
        "status": f"error: task failed: {type(exc).__name__}: {exc}",
        **{m.name: math.nan for m in ctx.metrics},
    }


def sweep(
    scene: Scene,
    vary: tuple[Vary, ...],
    engine: Engine,
    fmu_out: Path,
    metric_list: tuple[Metric, ...] | None = None,
    trajectories: bool | None = None,
    share_by_path: bool | None = None,
    batch: int | None = None,
) -> list[dict[str, Any]]:
    """The rows of every run of the study (see the module docstring); ``batch``: runs
    per task (default: the engine's batches)."""
    import fmu_build

    if not vary:
        raise ScenarioError(f"{scene.path}: nothing varied (--vary NAME=VALUES or [sweep].vary)")
    variation.check(scene, [v.name for v in vary])
    ms = metric_list or scene.sweep.metrics or mt.defaults(scene.outputs)
    clash = {v.name for v in vary} & ({"run", "case", "status"} | {m.name for m in ms})
    if clash:
        raise ScenarioError(f"{scene.path}: {sorted(clash)} cannot be varied (a column name)")
    built = fmu_build.build(scene.config, fmu_out)
    if share_by_path is None:
        share_by_path = engine.scheduler is None
    data = None if share_by_path else built.path.read_bytes()
    source_key = hashlib.sha256(
        json.dumps([str(scene.path), scene.source], sort_keys=True, default=str).encode()
    ).hexdigest()
    ctx = Context(
        str(scene.path),
        scene.source,
        source_key,
        FmuRef(built.key, str(built.path), data),
        tuple(ms),
        scene.sweep.trajectories if trajectories is None else trajectories,
    )
    todo = runs(scene, vary)
    return engine.map(
        run_one,
        todo,
        shared=ctx,
        desc=f"sweep {scene.name}",
        on_error=lambda run, exc: failed_row(ctx, run, exc),
        batch=batch,
    )


def write(
    rows: list[dict[str, Any]], vary: tuple[Vary, ...], out: Path, metric_names: list[str]
) -> list[Path]:
    """DIR/results.parquet (one row per run) and, when the rows carry them,
    DIR/trajectories.parquet (run, case, time and the recorded columns, one row per
    sample)."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    out.mkdir(parents=True, exist_ok=True)
    names = ["run", *(v.name for v in vary), "case", "status", *metric_names]
    types = {"run": pa.int64(), "case": pa.string(), "status": pa.string()}
    table = pa.table({n: pa.array([r[n] for r in rows], type=types.get(n, pa.float64()))
                      for n in names})  # fmt: skip
    written = [out / "results.parquet"]
    pq.write_table(table, written[0])
    traj = [r for r in rows if "_columns" in r]
    if traj:
        cols = list(dict.fromkeys(k for r in traj for k in r["_columns"]))
        data: dict[str, list] = {"run": [], "case": [], **{c: [] for c in cols}}
        for r in traj:
            c = r["_columns"]
            n = c["time"].size
            data["run"].append(np.full(n, r["run"]))
            data["case"] += [r["case"]] * n
            for k in cols:
                data[k].append(np.asarray(c.get(k, np.full(n, np.nan)), float))
        arrays = {k: (v if k == "case" else np.concatenate(v)) for k, v in data.items()}
        written.append(out / "trajectories.parquet")
        pq.write_table(pa.table(arrays), written[1])
    return written


def read(path: Path) -> list[dict[str, Any]]:
    """The rows of a results.parquet."""
    import pyarrow.parquet as pq

    return pq.read_table(path).to_pylist()


def strip(rows: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """Rows without their trajectories."""
    return [{k: v for k, v in r.items() if k != "_columns"} for r in rows]


def cleanup_local() -> None:
    """Remove the FMUs this process extracted (a serial sweep's; a worker's go when it
    exits)."""
    for d in forget("fmu:"):
        shutil.rmtree(Path(d).parent, ignore_errors=True)
