"""Work against precision: each scene's sweep run through its built FMU in fmpy, timed,
and compared with references computed outside the FMU.

Errors (per case, then over the cases: the largest max, the RMS of all points):

- Tx relative to mu P (P the largest normal load of the run), and Ty likewise where
  the scene outputs it and the reference has it;
- vx relative to the slip scale v_s = (creepage at the onset of full slip) x max |Vx|,
  the slip at which the law saturates at the run's largest speed (``creep_full_slip``
  of the contact law at the largest load).

They are taken at every communication point after t = 0 of the point's grid (in
contact mode at up to CONTACT_SAMPLES of them), against the reference of the same
equations. Along the communication step (``sweep.STEP_LADDER``) the reference takes
the *continuous* inputs (what co-simulation approximates: the zero-order hold of the
inputs counts as error), and optionally (``held=True``) also the inputs held over each
step as the FMU receives them (the FMU's own integration error). Along a ladder that
refines the model at the scene's step (the transient field's grid, the half-space
table's nodes) the reference takes the inputs as the FMU receives them: the error is
that of the refined discretisation. The wall time of a run is that of
``fmpy.simulate_fmu`` on the extracted FMU (instantiation, every step, termination),
the fastest of ``repeats`` runs (one if it takes more than REPEAT_BELOW), summed over
the cases; ``setup`` is a rung's one-off cost outside the runs (the build of its
creep-force table, as recorded in the table). Along a family (coarse to fine) a point
predicted to cost more than ``budget`` (times the ladder's ``budget_scale``) seconds is
skipped and listed as such.
"""

from __future__ import annotations

import json
import math
import shutil
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import fmpy
import numpy as np
from numpy.typing import NDArray

import fmu_build

from ..fmu.config import ModelConfig
from ..scenario import runner
from ..scenario.schema import Case, Scene
from ..study import tables as study_tables
from ..study.engine import Engine, once, release
from . import reference as ref
from .metrics import norms, observed_order, pairwise_orders
from .sweep import Family, Ladder, Rung, families, for_report, point, rungs

FloatArray = NDArray[np.float64]

# Errors below this (relative) are rounding: not used for the observed order.
ORDER_FLOOR = 1e-12
# Runs longer than this (s) are not repeated (the noise of a shared machine matters for
# short runs; a long one would only double the report's time).
REPEAT_BELOW = 2.0
# Default budget (s) of one point (all its cases): finer points of a family whose cost
# would exceed it (twice the previous point's) are skipped and listed as such.
BUDGET = 12.0


def _body_reference(continuous, held):
    return {"continuous": continuous, "held": held}


# Reference sources by (mode, phase, method): functions (scene, case, grid) -> Solution
# under the continuous and the held inputs. A new phase adds its own entries (a law is
# added in fmu.factory.FACTORIES); a setting without one is listed as not compared.
REFERENCES: dict[tuple[str, str, str], dict[str, Callable]] = {
    ("body", "steady", "full"): _body_reference(ref.full_continuous, ref.full_held),
    ("body", "steady", "quasistationary"): _body_reference(
        ref.quasistationary_continuous, ref.quasistationary_held
    ),
    ("body", "transient", "full"): _body_reference(ref.transient_continuous, ref.transient_held),
}


def _source(scene: Scene, method: str) -> dict[str, Callable]:
    key = (scene.config.mode, scene.config.phase, method)
    if key not in REFERENCES:
        raise ref.NoReferenceError(
            f"{scene.name}: no reference for mode {key[0]}, phase {key[1]!r}, method {key[2]!r}"
        )
    return REFERENCES[key]


@dataclass
class Row:
    """One point of one family: a rung of the scene's ladder (a communication step h, or
    a refined setting at the scene's h), its cost and its errors. ``spacing``: the
    length the observed order refers to (h along the communication step)."""

    scene: str
    family: str
    settings: dict[str, object]
    level: int
    h: float
    steps: int
    wall: float = math.nan
    Tx_max: float = math.nan
    Tx_rms: float = math.nan
    vx_max: float = math.nan
    vx_rms: float = math.nan
    Tx_max_held: float = math.nan
    vx_max_held: float = math.nan
    order_Tx: float = math.nan
    order_vx: float = math.nan
    error: str | None = None
    refined: str = "h"
    value: str = ""
    spacing: float = math.nan
    setup: float = math.nan
    Ty_max: float = math.nan
    Ty_rms: float = math.nan

    def __post_init__(self) -> None:
        if math.isnan(self.spacing):
            self.spacing = self.h
        if not self.value:
            self.value = f"{self.h:.3g}"


@dataclass
class SceneReport:
    scene: str
    title: str
    mode: str
    cases: list[str]
    fmu: str
    rows: list[Row] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    held: bool = False
    refined: str = "h"
    refined_doc: str = "the communication step h"

    def families(self) -> list[str]:
        return list(dict.fromkeys(r.family for r in self.rows))

    def of(self, family: str) -> list[Row]:
        """The family's rows, coarse to fine."""
        return sorted((r for r in self.rows if r.family == family), key=lambda r: -r.spacing)

    def family_orders(self) -> dict[str, tuple[float, float]]:
        """Least-squares observed order of the max errors of Tx and vx, per family (in
        the ladder's spacing)."""
        out = {}
        for f in self.families():
            rows = self.of(f)
            h = [r.spacing for r in rows]
            out[f] = (
                observed_order(h, [r.Tx_max for r in rows], ORDER_FLOOR),
                observed_order(h, [r.vx_max for r in rows], ORDER_FLOOR),
            )
        return out


@dataclass
class _CaseRef:
    """A case's references per method at the finest grid's points ``index`` (every
    point in body mode; samples in contact mode, on the coarsest grid)."""

    case: Case
    by_method: dict[str, ref.Solution]
    index: NDArray[np.int_]
    Tx_scale: float
    v_scale: float


def _scales(scene: Scene, case: Case, grid: FloatArray, Vx: FloatArray) -> tuple[float, float]:
    """(mu P, v_s) of the case: the largest load, the slip scale at the largest speed."""
    p = case.parameters
    P = float(np.max(ref.signal_values(case, ("P",), grid)["P"]))
    Vmax = float(np.nanmax(np.abs(Vx))) if np.any(np.isfinite(Vx)) else abs(p.get("Vx0", 1.0))
    try:
        creep = ref.scene_law(scene, p, P).creep_full_slip
    except ref.NoReferenceError:
        creep = math.nan  # no reference for this law: nothing is compared
    return p["mu"] * P, creep * Vmax


def _fine_grid(scene: Scene, rs: list[Rung]) -> FloatArray:
    """The grid of the finest step among the rungs: every rung's grid is a subset."""
    h = min(r.h for r in rs)
    return np.arange(int(round(scene.stop_time / h)) + 1) * h


def _references(scene: Scene, case: Case, methods: list[str], lad: Ladder, rs: list[Rung]):
    grid = _fine_grid(scene, rs)
    sols: dict[str, ref.Solution] = {}
    notes = []
    if scene.config.mode == "contact":
        coarse = int(round(max(r.h for r in rs) / min(r.h for r in rs)))
        index = ref.contact_samples(grid[::coarse]) * coarse
        try:
            if lad.reading == "held":
                sols["contact"] = ref.contact_held(scene, case, grid, index)
            else:
                sols["contact"] = ref.contact_continuous(scene, case, grid[index])
            Vx = sols["contact"].Vx
        except ref.NoReferenceError as e:
            notes.append(str(e))
            Vx = np.array([np.nan])
    else:
        index = np.arange(grid.size)
        for m in methods:
            try:
                sols[m] = _source(scene, m)[lad.reading](scene, case, grid)
            except ref.NoReferenceError as e:
                notes.append(str(e))
        Vx = next(iter(sols.values())).Vx if sols else np.array([np.nan])
    Tx_scale, v_scale = _scales(scene, case, grid, Vx)
    return _CaseRef(case, sols, index, Tx_scale, v_scale), notes


def setup_cost(cfg: ModelConfig) -> float:
    """One-off cost (s) of an FMU's generated data outside its runs: the build time of
    its creep-force table as the table records it (built here first if missing); NaN
    for an FMU without generated data."""
    if not cfg.has_table:
        return math.nan
    from fmu_build import tables

    from ..halfspace.table import TableData

    meta = json.loads(TableData.load(tables.ensure(cfg)).meta)
    return float(meta.get("seconds", math.nan))


def run_scene(
    scene: Scene,
    fmu_dir: Path,
    quick: bool = False,
    repeats: int = 2,
    held: bool = False,
    all_cases: bool = True,
    log: Callable[[str], None] = print,
    budget: float = BUDGET,
    engine: Engine | None = None,
) -> SceneReport:
    """The scene's sweep through its FMU (built or cached under ``fmu_dir``; one per rung
    where the ladder changes the model). Each family is one task of ``engine`` (default:
    in this process, in order); with workers, families run at once, one per worker
    process, and each worker extracts an FMU once. The FMUs (and their creep-force
    tables, through the engine) are built here first."""
    engine = engine or Engine(workers=0, progress=False)
    scene = for_report(scene, quick)
    fams, cfg = families(scene, quick)
    lad, rs = rungs(scene, quick)
    cases = list(scene.cases if all_cases and not quick else scene.cases[:1])
    report = SceneReport(scene.name, scene.title, scene.config.mode, [c.name for c in cases], "")
    report.held = held
    report.refined, report.refined_doc = lad.name, lad.doc
    methods = sorted({f.value("method", "full") for f in fams})
    refs = []
    for c in cases:
        r, notes = _references(scene, c, methods, lad, rs)
        refs.append(r)
        report.notes += notes
    if not any(r.by_method for r in refs):  # nothing to compare with: not run
        log(f"  {scene.name}: skipped, " + "; ".join(dict.fromkeys(report.notes)))
        return report
    fmus: dict[str, str] = {}
    setups: dict[str, float] = {}
    for rung in rs:
        rcfg = lad.configure(cfg, rung.value)
        key = _config_key(rcfg)
        if key not in fmus:
            study_tables.ensure(rcfg, engine)  # through the engine when it has workers
            setups[key] = setup_cost(rcfg)
            built = fmu_build.build(rcfg, fmu_dir)
            fmus[key] = str(built.path)
            report.fmu = ", ".join(filter(None, [report.fmu, built.path.name]))
    ctx = _FamilyContext(scene, cfg, lad, rs, refs, fmus, setups, repeats, held, budget)
    try:
        results = engine.map(_family_rows, fams, shared=ctx, desc=f"report {scene.name}", batch=1)
    finally:
        release("report-fmu:")  # this process's copies (a worker's: at the engine's end)
    for rows in results:
        for r in rows:
            report.rows.append(r)
            log(
                f"  {scene.name:8s} {r.family:28s} {lad.name} = {r.value:>9s}  "
                f"{r.wall:7.3f} s  Tx {r.Tx_max:9.2e}  vx {r.vx_max:9.2e}"
                + (f"  {r.error}" if r.error else "")
            )
    _orders(report)
    return report


@dataclass(frozen=True)
class _FamilyContext:
    """What every family of a scene shares: the FMUs by configuration (file paths) and
    their setup costs, the references, the settings of the sweep."""

    scene: Scene
    cfg: ModelConfig
    lad: Ladder
    rs: list[Rung]
    refs: list[_CaseRef]
    fmus: dict[str, str]
    setups: dict[str, float]
    repeats: int
    held: bool
    budget: float


def _extracted(path: str) -> Path:
    """The FMU file ``path`` extracted once in this process (removed when released)."""

    def extract() -> Path:
        d = Path(tempfile.mkdtemp(prefix="report-fmu-"))
        fmpy.extract(path, str(d))
        return d

    return once(f"report-fmu:{path}", extract, lambda d: shutil.rmtree(d, True))


def _family_rows(ctx: _FamilyContext, fam: Family) -> list[Row]:
    """One family's points, coarse to fine; a point predicted to cost more than the
    budget (the previous point's time times the ladder's growth) is skipped."""
    scene, lad = ctx.scene, ctx.lad
    rows = []
    last = 0.0
    for rung in ctx.rs:  # coarse to fine: the cost grows by about lad.growth per rung
        predicted = lad.growth * last
        n_steps = int(round(scene.stop_time / rung.h))
        if predicted > ctx.budget * lad.budget_scale:
            r = Row(scene.name, fam.label, dict(fam.settings), rung.level, rung.h,
                    n_steps, refined=lad.name, value=rung.label,
                    spacing=rung.spacing)  # fmt: skip
            r.error = (
                f"skipped: about {predicted:.0f} s > budget {ctx.budget * lad.budget_scale:g} s"
            )
            rows.append(r)
            continue
        rcfg = lad.configure(ctx.cfg, rung.value)
        key = _config_key(rcfg)
        fmu = _extracted(ctx.fmus[key])
        r = _point(scene, rcfg, fam, lad, rung, ctx.rs, ctx.refs, fmu, ctx.repeats, ctx.held)
        r.setup = ctx.setups[key]
        rows.append(r)
        last = r.wall if math.isfinite(r.wall) else last
    return rows


def _config_key(cfg: ModelConfig) -> str:
    return json.dumps(cfg.to_dict(), sort_keys=True, default=str)


def _point(
    scene: Scene,
    cfg: ModelConfig,
    fam: Family,
    lad: Ladder,
    rung: Rung,
    rs: list[Rung],
    refs: list[_CaseRef],
    fmu_dir: Path,
    repeats: int,
    held: bool,
) -> Row:
    h = rung.h
    n = int(round(scene.stop_time / h))
    row = Row(scene.name, fam.label, dict(fam.settings), rung.level, h, n, refined=lad.name,
              value=rung.label, spacing=rung.spacing)  # fmt: skip
    method = fam.value("method", "full")
    stride = int(round(h / min(r.h for r in rs)))
    errs: dict[str, list[FloatArray]] = {
        "Tx": [], "vx": [], "Ty": [], "Tx_held": [], "vx_held": []
    }  # fmt: skip
    wall = 0.0
    for cr in refs:
        sc, case = point(scene, cr.case, cfg, fam, h, lad.start(rung.value))
        key = "contact" if scene.config.mode == "contact" else method
        if key not in cr.by_method:
            row.error = f"no reference for {method}"
            return row
        best, result = math.inf, None
        for _ in range(max(1, repeats)):
            t0 = time.perf_counter()
            result = runner.simulate_case(fmu_dir, sc, case)
            best = min(best, time.perf_counter() - t0)
            if best > REPEAT_BELOW:  # long runs are not repeated: noise is small there
                break
        wall += best
        if result is None or result.error:
            row.error = result.error if result is not None else "not run"
            return row
        sol = cr.by_method[key]
        on = (cr.index % stride == 0) & (cr.index > 0)  # this level's points after t = 0
        idx = cr.index[on] // stride
        compared = [("Tx", cr.Tx_scale), ("vx", cr.v_scale)]
        if sol.Ty is not None and "Ty" in result.columns:
            compared.append(("Ty", cr.Tx_scale))
        for var, scale in compared:
            errs[var].append((result.columns[var][idx] - getattr(sol, var)[on]) / scale)
        if held and lad.reading == "continuous":
            for var, e in _held_errors(scene, sc, case, result, key, idx, cr).items():
                errs[f"{var}_held"].append(e)
    row.wall = wall
    for var in ("Tx", "vx", "Ty"):
        if not errs[var]:
            continue
        e = np.concatenate(errs[var])
        mx, rms = norms(e, 1.0)
        setattr(row, f"{var}_max", mx)
        setattr(row, f"{var}_rms", rms)
    if held:  # a ladder whose reference takes the held inputs: the same errors
        for var in ("Tx", "vx"):
            e = errs[f"{var}_held"] or errs[var]
            setattr(row, f"{var}_max_held", norms(np.concatenate(e), 1.0)[0])
    return row


def _held_errors(scene, sc, case, result, key, idx, cr: _CaseRef) -> dict[str, FloatArray]:
    """Errors against the reference with the inputs held as the FMU receives them."""
    grid = sc.grid
    if key == "contact":
        sol = ref.contact_held(sc, case, grid, idx)
        want = {"Tx": sol.Tx, "vx": sol.vx}
    else:
        sol = _source(scene, key)["held"](sc, case, grid)
        want = {"Tx": sol.Tx[idx], "vx": sol.vx[idx]}
    scale = {"Tx": cr.Tx_scale, "vx": cr.v_scale}
    return {v: (result.columns[v][idx] - want[v]) / scale[v] for v in ("Tx", "vx")}


def _orders(report: SceneReport) -> None:
    for f in report.families():
        rows = report.of(f)
        h = [r.spacing for r in rows]
        for var in ("Tx", "vx"):
            e = np.array([getattr(r, f"{var}_max") for r in rows])
            p = pairwise_orders(h, e)
            p[e <= ORDER_FLOOR] = np.nan  # at rounding level an order means nothing
            p[1:][e[:-1] <= ORDER_FLOOR] = np.nan
            for r, o in zip(rows, p, strict=True):
                setattr(r, f"order_{var}", float(o))
