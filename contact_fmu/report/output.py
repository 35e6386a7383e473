"""Report files: CSV and Markdown tables, work-precision plots, documentation sections."""

from __future__ import annotations

import csv
import math
from pathlib import Path

import numpy as np

from .workprecision import Row, SceneReport

# Errors below this are drawn at this value on the log-log plots (exact results, e.g.
# the quasistationary stepper under constant loads, have zero error).
PLOT_FLOOR = 1e-16
COLUMNS = (
    "scene",
    "family",
    "method",
    "scheme",
    "substeps",
    "level",
    "h",
    "steps",
    "wall",
    "Tx_max",
    "Tx_rms",
    "vx_max",
    "vx_rms",
    "order_Tx",
    "order_vx",
    "Tx_max_held",
    "vx_max_held",
    "error",
    "refined",
    "value",
    "spacing",
    "setup",
    "Ty_max",
    "Ty_rms",
)
# Numeric columns written with repr (every digit) and read back as floats.
NUMBERS = COLUMNS[8:17] + ("spacing", "setup", "Ty_max", "Ty_rms")


def _fmt(x: object, spec: str = ".3g") -> str:
    if isinstance(x, float):
        return "-" if math.isnan(x) else format(x, spec)
    return "-" if x is None else str(x)


def write_csv(report: SceneReport, path: Path) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    with path.open("w", newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(COLUMNS)
        for r in report.rows:
            s = r.settings
            w.writerow(
                [r.scene, r.family, s.get("method", ""), s.get("scheme", ""),
                 s.get("substeps", ""), r.level, repr(r.h), r.steps]
                + [repr(getattr(r, c)) for c in COLUMNS[8:17]]
                + [r.error or "", r.refined, r.value, repr(r.spacing), repr(r.setup),
                   repr(r.Ty_max), repr(r.Ty_rms)]
            )  # fmt: skip
    return path


ERROR_NOTE = (
    "Errors at every communication point after t = 0: Tx relative to mu P, vx relative "
    "to the slip scale v_s = (creepage at the onset of full slip) x max |Vx| of the run; "
    "max over the cases and RMS over all their points. Reference: the same equations "
    "outside the FMU under the continuous inputs (solve_ivp Radau, rtol 1e-11, on "
    "Eqs. 8-11 for the full stepper; Eqs. 26, 28 in closed form for the quasistationary "
    "one; nested quadrature of Eq. 36 in contact mode), so the zero-order hold of the "
    "inputs over a communication step counts as error. Order: log(e(2h)/e(h))/log 2 of "
    "the max error against the next coarser step; the family's order is the least-squares "
    "slope. Wall time: fmpy.simulate_fmu (instantiate, all steps, terminate), fastest "
    "of the repeats, summed over the cases."
)
# Scenes whose ladder refines the model at their own step h (sweep.LADDERS), by ladder.
LADDER_NOTES = {
    "grid": (
        "fig12_transient (phase transient) refines the traction field's grid nx x ny at "
        "its own step h (nx = 16, 32, 64, ny = nx/2; cells_per_step 0.5, so the internal "
        "step halves with the cell; quick: 16 and 32 over the first 50 steps), against "
        "TransientRollingBody outside the FMU under the loads as the FMU receives them, "
        "on 64 x 32 and 128 x 64 combined by Richardson's extrapolation for second "
        "order (within 1.2e-4 of v_s and 5e-5 of mu P of the extrapolation from 128 x 64 "
        "and 256 x 128, measured over the first ms of eta = 10.9; the nx = 64 row's error "
        "is therefore Richardson's estimate 4/3 |F64 - R128|). Order: in the cell 1/nx."
    ),
    "table": (
        "rail_creep (half-space law, contact mode) refines the creep-force table's nodes "
        "along xi and eta at its own step h (the node spacing halved per row, 13 x 11, "
        "25 x 21, 49 x 41; spin axis as the scene's; quick: the first two, first case), "
        "against direct solves of the steady-rolling problem on the table's solver grid "
        "at the kinematics the FMU holds (41 points per case), with the table's radial "
        "saturation applied: the saturation itself moves |T| by at most (4/27) 0.02 = "
        "3.0e-3 of mu P (2.4e-3 to 2.9e-3 at these points), and the solver grid's own "
        "discretisation error is docs/halfspace.md's. Order: in the node spacing. Cost: "
        "the fmpy run, and apart the table's build (recorded in the table; built once, "
        "cached in out/tables). Ty relative to mu P."
    ),
}
LADDER_NOTE = " ".join(LADDER_NOTES.values())
HELD_NOTE = (
    "*held*: max error against the reference with the inputs held over each step as "
    "the FMU receives them (the FMU's own integration error)."
)


def scene_markdown(report: SceneReport) -> str:
    orders = report.family_orders()
    held = report.held
    ladder = report.refined != "h"
    with_ty = any(math.isfinite(r.Ty_max) for r in report.rows)
    with_setup = any(math.isfinite(r.setup) for r in report.rows)
    note = ERROR_NOTE + (" " + LADDER_NOTES.get(report.refined, "") if ladder else "")
    note += " " + HELD_NOTE if held else ""
    lines = [
        f"## {report.scene}: {report.title}",
        "",
        f"Mode {report.mode}; cases: {', '.join(report.cases)}; FMU `{report.fmu or '-'}`.",
        "",
        f"Refined along a family: {report.refined_doc}.",
        "",
        note,
        "",
    ]
    first = f"{report.refined} | h (s)" if ladder else "h (s)"
    head = f"| family | {first} | steps | wall (s) |"
    if with_setup:
        head += " table build (s) |"
    head += " Tx max | Tx RMS | vx max | vx RMS |"
    if with_ty:
        head += " Ty max | Ty RMS |"
    head += " order Tx | order vx |"
    if held:
        head += " Tx max held | vx max held |"
    sep = "|" + "---|" * (head.count("|") - 1)
    lines += [head, sep]
    for f in report.families():
        for r in report.of(f):
            cells = [r.family] + ([r.value] if ladder else []) + [_fmt(r.h), str(r.steps),
                                                                 _fmt(r.wall)]  # fmt: skip
            if with_setup:
                cells.append(_fmt(r.setup))
            at_error = len(cells)
            cells += [_fmt(r.Tx_max, ".2e"), _fmt(r.Tx_rms, ".2e"), _fmt(r.vx_max, ".2e"),
                      _fmt(r.vx_rms, ".2e")]  # fmt: skip
            if with_ty:
                cells += [_fmt(r.Ty_max, ".2e"), _fmt(r.Ty_rms, ".2e")]
            cells += [_fmt(r.order_Tx, ".2f"), _fmt(r.order_vx, ".2f")]
            if held:
                cells += [_fmt(r.Tx_max_held, ".2e"), _fmt(r.vx_max_held, ".2e")]
            if r.error:
                cells[at_error] = r.error if r.error.startswith("skipped") else f"failed: {r.error}"
            lines.append("| " + " | ".join(cells) + " |")
    lines += ["", "Observed order per family (least squares over the steps):", ""]
    lines += ["| family | order Tx | order vx |", "|---|---|---|"]
    for f, (pT, pv) in orders.items():
        lines.append(f"| {f} | {_fmt(pT, '.2f')} | {_fmt(pv, '.2f')} |")
    if report.notes:
        lines += ["", "Notes:", ""] + [f"- {n}" for n in dict.fromkeys(report.notes)]
    return "\n".join(lines) + "\n"


def _style(row: Row, families: list[str]):
    s = row.settings
    key = (s.get("method", ""), s.get("scheme", ""))
    colors = {
        ("full", "lobatto3c"): "tab:blue",
        ("full", "sdirk2"): "tab:orange",
        ("quasistationary", "lobatto3c"): "tab:green",
        ("quasistationary", "sdirk2"): "tab:red",
    }
    color = colors.get(key, f"C{families.index(row.family) % 10}")
    markers = {1: "o", 4: "s", 16: "^"}
    return color, markers.get(s.get("substeps"), "D"), "-" if s.get("substeps", 4) != 1 else "--"


def plot(report: SceneReport, path: Path) -> Path:
    """Max error of Tx and vx against wall time, log-log, one curve per family."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fams = report.families()
    orders = report.family_orders()
    fig, axes = plt.subplots(1, 2, figsize=(11, 5.6))
    for ax, var, label in (
        (axes[0], "Tx", "max |Tx - Tx_ref| / (mu P)"),
        (axes[1], "vx", "max |vx - vx_ref| / v_s"),
    ):
        for f in fams:
            rows = [r for r in report.of(f) if not r.error]
            if not rows:
                continue
            t = np.array([r.wall + (r.setup if math.isfinite(r.setup) else 0.0) for r in rows])
            e = np.maximum([getattr(r, f"{var}_max") for r in rows], PLOT_FLOOR)
            color, marker, ls = _style(rows[0], fams)
            p = orders[f][0 if var == "Tx" else 1]
            name = f"{f} (p = {p:.2f})" if math.isfinite(p) else f
            ax.loglog(t, e, ls, color=color, marker=marker, label=name, ms=5, lw=1.2)
        setup = any(math.isfinite(r.setup) for r in report.rows)
        ax.set_xlabel("wall time of the fmpy run" + (" + table build" if setup else "") + " (s)")
        ax.set_ylabel(label)
        ax.grid(True, which="both", alpha=0.3)
    handles, labels = axes[0].get_legend_handles_labels()
    if handles:
        fig.legend(handles, labels, loc="lower center", ncol=3, fontsize=7, frameon=False)
    if report.refined == "h":
        steps = sorted({r.h for r in report.rows}, reverse=True)
        span = f"h = {steps[0]:.3g} s to {steps[-1]:.3g} s" if steps else ""
        along = f"the communication step halves, {span}"
    else:
        values = [r.value for r in report.of(fams[0])] if fams else []
        span = f"{values[0]} to {values[-1]}" if values else ""
        along = f"the {report.refined} is refined, {span}"
    fig.suptitle(
        f"{report.scene}: error against run time; along a curve {along} (left to right); "
        "p: observed order of the Tx error",
        fontsize=10,
    )
    fig.tight_layout(rect=(0, 0.14, 1, 0.95))
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def read_csv(path: Path, title: str = "", mode: str = "") -> SceneReport:
    """A scene's report back from its CSV (to plot again without running it)."""
    with path.open(newline="") as f:
        rows = list(csv.DictReader(f))
    rep = SceneReport(rows[0]["scene"] if rows else path.stem, title, mode, [], "")
    for d in rows:
        settings: dict[str, object] = {}
        for k in ("method", "scheme"):
            if d[k]:
                settings[k] = d[k]
        if d["substeps"]:
            settings["substeps"] = int(d["substeps"])
        r = Row(d["scene"], d["family"], settings, int(d["level"]), float(d["h"]), int(d["steps"]))
        for c in NUMBERS:
            if d.get(c):
                setattr(r, c, float(d[c]))
        r.error = d["error"] or None
        r.refined = d.get("refined") or "h"
        r.value = d.get("value") or r.value
        rep.rows.append(r)
    if rep.rows:
        rep.refined = rep.rows[0].refined
    return rep


def summary_rows(reports: list[SceneReport]) -> list[list[str]]:
    """Per scene and family: step range, error range, order, time range (for the docs)."""
    rows = []
    for rep in reports:
        orders = rep.family_orders()
        for f in rep.families():
            rs = [r for r in rep.of(f) if not r.error]
            if not rs:
                continue
            pT, pv = orders[f]
            if rep.refined == "h":
                span = f"{rs[0].h:.3g} .. {rs[-1].h:.3g}"
            else:
                span = f"{rs[0].h:.3g}; {rep.refined} {rs[0].value} .. {rs[-1].value}"
            wall = f"{rs[0].wall:.3g} .. {rs[-1].wall:.3g}"
            if math.isfinite(rs[0].setup):
                wall += f" (+ table build {rs[0].setup:.3g} .. {rs[-1].setup:.3g})"
            rows.append(
                [
                    rep.scene,
                    f,
                    span,
                    f"{rs[0].Tx_max:.1e} .. {rs[-1].Tx_max:.1e}",
                    f"{rs[0].vx_max:.1e} .. {rs[-1].vx_max:.1e}",
                    f"{rs[0].Ty_max:.1e} .. {rs[-1].Ty_max:.1e}"
                    if math.isfinite(rs[0].Ty_max)
                    else "-",
                    _fmt(pT, ".2f"),
                    _fmt(pv, ".2f"),
                    wall,
                ]
            )
    return rows


def summary_markdown(reports: list[SceneReport], only_substeps: int | None = None) -> str:
    head = (
        "| scene | family | h (s) or refined | Tx max error / (mu P) | vx max error / v_s "
        "| Ty max error / (mu P) | order Tx | order vx | wall (s) |\n"
        "|---|---|---|---|---|---|---|---|---|"
    )
    body = []
    for row, rep_row in zip(summary_rows(reports), _families_of(reports), strict=True):
        if only_substeps is not None and rep_row.get("substeps") not in (None, only_substeps):
            continue
        body.append("| " + " | ".join(row) + " |")
    skipped = ["; ".join(dict.fromkeys(r.notes)) for r in reports if not r.rows]
    tail = "\nNot compared: " + "; ".join(skipped) + "\n" if skipped else ""
    return head + "\n" + "\n".join(body) + "\n" + tail


def _families_of(reports: list[SceneReport]) -> list[dict]:
    out = []
    for rep in reports:
        for f in rep.families():
            rs = [r for r in rep.of(f) if not r.error]
            if rs:
                out.append(rs[0].settings)
    return out


def wrap_prose(text: str, width: int = 88) -> str:
    """Wrap the prose paragraphs of Markdown text to ``width``; tables, lists, headings,
    images and indented or fenced code are kept as they are."""
    import textwrap

    out, fenced = [], False
    for block in text.split("\n\n"):
        first = block.lstrip("\n").split("\n", 1)[0]
        if first.startswith("```"):
            fenced = not fenced if block.count("```") % 2 else fenced
            out.append(block)
            continue
        listed = first.startswith(("- ", "* ")) or (first[:1].isdigit() and ". " in first[:4])
        keep = fenced or not first or first[0] in "|#!" or first.startswith("    ") or listed
        flat = " ".join(block.split())
        wrapped = textwrap.fill(flat, width, break_long_words=False, break_on_hyphens=False)
        out.append(block if keep else wrapped)
    return "\n\n".join(out)


def _heading_level(line: str) -> int:
    """Markdown ATX heading level of a line (0 if it is not a heading)."""
    stripped = line.lstrip("#")
    n = len(line) - len(stripped)
    return n if n and stripped.startswith(" ") else 0


def replace_section(path: Path, heading: str, body: str) -> None:
    """Replace the section that starts with the line ``heading`` (up to the next heading
    of the same or a higher level, outside code fences) by ``heading`` + ``body``;
    append it if absent."""
    text = path.read_text() if path.exists() else ""
    level = _heading_level(heading)
    section = (heading + "\n\n" + wrap_prose(body.strip("\n"))).split("\n")
    lines = text.split("\n")
    if heading not in lines:
        path.write_text(text.rstrip("\n") + "\n\n" + "\n".join(section) + "\n")
        return
    start = lines.index(heading)
    end, fenced = len(lines), False
    for i in range(start + 1, len(lines)):
        if lines[i].startswith("```"):
            fenced = not fenced
        elif not fenced and 0 < _heading_level(lines[i]) <= level:
            end = i
            break
    new = lines[:start] + section + [""] + lines[end:]
    path.write_text("\n".join(new).rstrip("\n") + "\n")
