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
from . import output, stiff
from .stiff_cases import cases
from .workprecision import SceneReport, run_scene

ROOT = Path(__file__).resolve().parents[2]
README_SECTION = "## Report: error against run time, stiff and extreme cases"
PERF_WP_SECTION = "## Error against run time (work-precision)"
PERF_STIFF_SECTION = "## Stiff and extreme cases"
DOC_PLOT_SCENE = "fig13"


def workprecision(
    scene_paths: list[Path],
    out: Path,
    fmu_dir: Path,
    quick: bool,
    repeats: int,
    held: bool,
    log: Callable[[str], None] = print,
) -> list[SceneReport]:
    reports = []
    for path in scene_paths:
        scene = load(path)
        log(f"{scene.name}: {scene.title}")
        t0 = time.perf_counter()
        rep = run_scene(scene, fmu_dir, quick=quick, repeats=repeats, held=held, log=log)
        base = out / "workprecision" / scene.name
        output.write_csv(rep, base.with_suffix(".csv"))
        base.with_suffix(".md").write_text(output.scene_markdown(rep))
        output.plot(rep, base.with_suffix(".png"))
        log(f"  -> {base}.{{csv,md,png}} ({time.perf_counter() - t0:.0f} s)")
        reports.append(rep)
    text = ["# Error against run time", "", output.summary_markdown(reports), ""]
    text += [output.scene_markdown(r) for r in reports]
    (out / "workprecision.md").write_text("\n".join(text))
    log(f"summary: {out / 'workprecision.md'}")
    return reports


def stiff_suite(
    out: Path, fmu_dir: Path, quick: bool, names: list[str], log: Callable[[str], None] = print
) -> list[stiff.Result]:
    selected = [c for c in cases() if (not names or c.name in names or c.group in names)]
    if quick and not names:
        selected = [c for c in selected if "long" not in c.tags]
    results = stiff.run_all(fmu_dir, selected, log=log)
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
    """README and docs/performance.md sections, and the Fig. 13 plot in docs/figures."""
    readme, perf = ROOT / "README.md", ROOT / "docs" / "performance.md"
    how = (
        "Run by `" + command + "` (numbers from a shared 2-core machine: times vary with its "
        "load, errors do not). Full tables and plots: `reports/workprecision/`, "
        "`reports/stiff.md` (gitignored; `contact-fmu report --quick` is the short version "
        "the tests run)."
    )
    parts_readme = [how, ""]
    if reports:
        src = out / "workprecision" / f"{DOC_PLOT_SCENE}.png"
        if src.exists():
            dst = ROOT / "docs" / "figures" / f"workprecision_{DOC_PLOT_SCENE}.png"
            shutil.copyfile(src, dst)
        parts_readme += [
            "**Error against run time.** Each scene's FMU run by fmpy over a sweep of "
            "communication steps h (the scene's step x 2^k), internal steps n per "
            "communication step, scheme (Lobatto IIIC, SDIRK2) and stepper (full, "
            "quasistationary where the loads stay admissible), against a reference of "
            "the same equations outside the FMU. " + output.ERROR_NOTE,
            "",
            f"![work-precision, {DOC_PLOT_SCENE}](docs/figures/workprecision_{DOC_PLOT_SCENE}.png)",
            "",
            "With n = 4 internal steps (every family: `docs/performance.md`):",
            "",
            output.summary_markdown(reports, only_substeps=4),
        ]
        figure = f"![work-precision, {DOC_PLOT_SCENE}](figures/workprecision_{DOC_PLOT_SCENE}.png)"
        body = [how, output.ERROR_NOTE, output.summary_markdown(reports), figure]
        output.replace_section(perf, PERF_WP_SECTION, "\n\n".join(body))
    if results:
        table = stiff.markdown(results)
        parts_readme += [
            "**Stiff and extreme cases** (`tests/test_stiff.py` runs the same list). " + stiff.NOTE,
            "",
            stiff.short_markdown(results),
        ]
        output.replace_section(perf, PERF_STIFF_SECTION, how + "\n\n" + stiff.NOTE + "\n\n" + table)
    output.replace_section(readme, README_SECTION, "\n".join(parts_readme))


def scene_paths(scenes: list[Path], scenarios: Path) -> list[Path]:
    return list(scenes) or discover(scenarios)
