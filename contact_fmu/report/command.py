"""``contact-fmu report``: the work-precision sweep of every scene and the stiff suite.

Files (under ``--out``, default reports/, gitignored):

    workprecision/<scene>.csv, .md, .png   per scene: every point, its error and time
    workprecision.md                       every scene's table and the summary
    stiff.md, stiff.csv                    the stiff and extreme cases

``--write-docs`` (full runs only) copies the summary into README.md and
docs/performance.md and the Fig. 13 plot into docs/figures/.
"""

from __future__ import annotations

import csv
import shutil
import time
from collections.abc import Callable
from pathlib import Path

from ..scenario import discover, load
from ..study.engine import Engine
from . import output, stiff
from .stiff_cases import cases
from .workprecision import BUDGET, SceneReport, run_scene

ROOT = Path(__file__).resolve().parents[2]
README_SECTION = "## Report: error against run time, stiff and extreme cases"
README_WP = "### Error against run time"
README_STIFF = "### Stiff and extreme cases"
PERF_WP_SECTION = "## Error against run time (work-precision)"
PERF_STIFF_SECTION = "## Stiff and extreme cases"
DOC_PLOT_SCENE = "fig13"
READING = """Reading it:

- Constant loads (Fig. 12): no hold error. The full stepper converges at second order in
  h, SDIRK2 with the smaller error constant; the quasistationary stepper is exact
  (Eq. 26 holds exactly and Vx is linear in time).
- Continuously varying loads (Fig. 13, railway, rail_traction): the zero-order hold of
  the inputs over a communication step dominates, first order in h whatever the scheme
  and n; internal steps cost time and buy little. The full stepper's max error at the
  smallest steps is set by the first communication steps, where the loads meet a body in
  pure rolling and the slip relaxes within tau_r (the hump of stiff problems where the
  internal step is of the order of tau_r); its RMS keeps falling at first order.
- Jumps between communication points (brake, two coarsest steps): the hold delays a jump
  by up to h, and the error there is of the order of the jump.
- Contact mode (sweep): no time integration; the error is the hold of the swept
  kinematics. Against the held kinematics the FMU's closed form agrees with the
  quadrature of the traction to below 1e-13 of mu P (`--held`).
- Transient field (fig12_transient): the error falls with the field's cell (and the
  internal step with it); the largest errors are in the first contact lengths, while
  the field forms and the body oscillates on the layer's stiffness.
- Half-space table (rail_creep): the table's interpolation error falls with the node
  spacing; the FMU's run costs the same at every resolution, the table's build (once,
  cached) grows with the nodes.
"""
USAGE = """    contact-fmu report                  # both parts, every scene (minutes)
    contact-fmu report --quick          # two steps per family, first case; no long run
    contact-fmu report --workprecision [scenes...] [--held] [--repeats N]
    contact-fmu report --stiff [--case NAME_OR_GROUP ...]
    contact-fmu report --write-docs     # also rewrite this section and docs/performance.md
    contact-fmu report --workers 2      # the families on two worker processes (Dask)
"""


def workprecision(
    scene_paths: list[Path],
    out: Path,
    fmu_dir: Path,
    quick: bool,
    repeats: int,
    held: bool,
    log: Callable[[str], None] = print,
    budget: float = BUDGET,
    engine: Engine | None = None,
) -> list[SceneReport]:
    """Every scene's work-precision sweep; its families as tasks of ``engine`` (default:
    in this process)."""
    reports = []
    for path in scene_paths:
        scene = load(path)
        log(f"{scene.name}: {scene.title}")
        t0 = time.perf_counter()
        rep = run_scene(
            scene,
            fmu_dir,
            quick=quick,
            repeats=repeats,
            held=held,
            log=log,
            budget=budget,
            engine=engine,
        )
        base = out / "workprecision" / scene.name
        output.write_csv(rep, base.with_suffix(".csv"))
        base.with_suffix(".md").write_text(output.scene_markdown(rep))
        if rep.rows:
            output.plot(rep, base.with_suffix(".png"))
        log(f"  -> {base}.{{csv,md,png}} ({time.perf_counter() - t0:.0f} s)")
        reports.append(rep)
    text = ["# Error against run time", "", output.summary_markdown(reports), ""]
    text += [output.scene_markdown(r) for r in reports]
    (out / "workprecision.md").write_text("\n".join(text))
    log(f"summary: {out / 'workprecision.md'}")
    return reports


def stiff_suite(
    out: Path,
    fmu_dir: Path,
    quick: bool,
    names: list[str],
    log: Callable[[str], None] = print,
    engine: Engine | None = None,
) -> list[stiff.Result]:
    known = cases()
    unknown = [n for n in names if n not in {c.name for c in known} | {c.group for c in known}]
    if unknown:
        raise ValueError(
            f"--case {unknown[0]!r} is not a stiff case or group; cases: "
            + ", ".join(c.name for c in known)
            + "; groups: "
            + ", ".join(dict.fromkeys(c.group for c in known))
        )
    selected = [c for c in known if (not names or c.name in names or c.group in names)]
    if quick and not names:
        selected = [c for c in selected if "long" not in c.tags]
    results = stiff.run_all(fmu_dir, selected, log=log, engine=engine)
    table = stiff.markdown(results)
    out.mkdir(parents=True, exist_ok=True)
    (out / "stiff.md").write_text("# Stiff and extreme cases\n\n" + stiff.NOTE + "\n\n" + table)
    with (out / "stiff.csv").open("w", newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(["case", "group", "method", "scheme", "h", "steps", "substeps", "ok"]
                   + [f"{n}_{k}" for n in stiff.CHECK_NAMES for k in ("ok", "value")])  # fmt: skip
        for r in results:
            by = {c.name: c for c in r.checks}
            c = r.case
            row = [c.name, c.group, c.method, c.scheme, c.h, c.steps, c.substeps, r.ok]
            for n in stiff.CHECK_NAMES:
                row += [by[n].ok, by[n].value] if n in by else ["", ""]
            w.writerow(row)
    print(table)
    n_fail = sum(not r.ok for r in results)
    log(f"{len(results) - n_fail} of {len(results)} cases pass; {out / 'stiff.md'}")
    return results


def write_docs(
    reports: list[SceneReport] | None, results: list[stiff.Result] | None, out: Path, command: str
) -> None:
    """README and docs/performance.md sections of the parts that ran (the other part's
    sections are kept), and the Fig. 13 plot in docs/figures."""
    readme, perf = ROOT / "README.md", ROOT / "docs" / "performance.md"
    how = (
        "Run by `" + command + "` (numbers from a shared 2-core machine: times vary with its "
        "load, errors do not). Full tables and plots: `reports/workprecision/`, "
        "`reports/stiff.md` (gitignored; `contact-fmu report --quick` is the short version "
        "the tests run)."
    )
    ensure_readme_section(readme)
    if reports:
        src = out / "workprecision" / f"{DOC_PLOT_SCENE}.png"
        if src.exists():
            dst = ROOT / "docs" / "figures" / f"workprecision_{DOC_PLOT_SCENE}.png"
            shutil.copyfile(src, dst)
        readme_wp = [
            how,
            "Each scene's FMU run by fmpy over a sweep of communication steps h (the scene's "
            "step x 2^k), internal steps n per communication step, scheme (Lobatto IIIC, "
            "SDIRK2) and stepper (full, quasistationary where the loads stay admissible), "
            "against a reference of the same equations outside the FMU. "
            + output.ERROR_NOTE
            + " "
            + output.LADDER_NOTE,
            f"![work-precision, {DOC_PLOT_SCENE}](docs/figures/workprecision_{DOC_PLOT_SCENE}.png)",
            "With n = 4 internal steps (every family: `docs/performance.md`):",
            output.summary_markdown(reports, only_substeps=4),
            READING,
        ]
        output.replace_section(readme, README_WP, "\n\n".join(readme_wp))
        figure = f"![work-precision, {DOC_PLOT_SCENE}](figures/workprecision_{DOC_PLOT_SCENE}.png)"
        body = [how, output.ERROR_NOTE + " " + output.LADDER_NOTE,
                output.summary_markdown(reports), figure]  # fmt: skip
        output.replace_section(perf, PERF_WP_SECTION, "\n\n".join(body))
    if results:
        readme_stiff = [
            how,
            "`tests/test_stiff.py` runs the same list. " + stiff.NOTE,
            stiff.short_markdown(results),
            stiff.failures(results),
        ]
        output.replace_section(readme, README_STIFF, "\n\n".join(readme_stiff))
        table = stiff.markdown(results)
        output.replace_section(perf, PERF_STIFF_SECTION, how + "\n\n" + stiff.NOTE + "\n\n" + table)


def ensure_readme_section(readme: Path) -> None:
    """The README's report section with its usage and two subsections (placeholders
    until a part has run), appended if absent; a missing subsection is added at its end."""
    text = readme.read_text()
    lines = text.split("\n")
    if README_SECTION not in lines:
        parts = [README_SECTION, USAGE.rstrip("\n"), README_WP, "Not run yet.", README_STIFF,
                 "Not run yet."]  # fmt: skip
        readme.write_text(text.rstrip("\n") + "\n\n" + "\n\n".join(parts) + "\n")
        return
    start = lines.index(README_SECTION)
    end = next((i for i in range(start + 1, len(lines)) if lines[i].startswith("## ")), len(lines))
    for sub in (README_WP, README_STIFF):
        if sub not in lines[start:end]:
            lines[end:end] = [sub, "", "Not run yet.", ""]
            end += 4
    readme.write_text("\n".join(lines))


def scene_paths(scenes: list[Path], scenarios: Path) -> list[Path]:
    return list(scenes) or discover(scenarios)
