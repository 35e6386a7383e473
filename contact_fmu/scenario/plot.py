"""PNG of a scene's result: one panel per group of variables, one line per case.

Reference points are drawn as markers on the line of their case. Scales and labels
come from the scene's [plot] table (e.g. Tx in units of mu p0 a1 a2, t in T_c); an
unscaled axis is labelled with its variable's SI unit (``labels.py``).
"""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from .labels import axis_label, axis_labels  # noqa: E402
from .runner import CaseResult, read_reference  # noqa: E402
from .schema import Scene  # noqa: E402


def _scaled(scene: Scene, name: str, values):
    factor, label = scene.plot.scale.get(name, (1.0, axis_label(name)))
    return values / factor, label


def _panel_label(scene: Scene, panel: tuple[str, ...]) -> str:
    """The y label of a panel: its scale's label, or the names with their units."""
    if len(panel) == 1:
        return _scaled(scene, panel[0], 1.0)[1]
    if any(v in scene.plot.scale for v in panel):
        return ", ".join(_scaled(scene, v, 1.0)[1] for v in panel)
    return axis_labels(panel)


def plot(scene: Scene, results: list[CaseResult], path: Path) -> Path:
    """Write the scene's figure to ``path`` (PNG) and return it."""
    panels = scene.plot.panels
    fig, axes = plt.subplots(
        len(panels), 1, figsize=(7.0, 2.4 * len(panels) + 0.8), sharex=True, squeeze=False
    )
    refs = [(ref, read_reference(ref.file)) for ref in scene.references if ref.file.is_file()]
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    xname = scene.plot.x
    xlabel = _scaled(scene, xname, 1.0)[1]
    circles = False
    for ax, panel in zip(axes[:, 0], panels, strict=True):
        for j, var in enumerate(panel):
            style = ("-", "--", ":", "-.")[j % 4]
            for k, r in enumerate(results):
                if r.error or var not in r.columns:
                    continue
                x = _scaled(scene, xname, r.columns[xname])[0]
                y = _scaled(scene, var, r.columns[var])[0]
                label = f"{r.case}" + (f": {var}" if len(panel) > 1 else "")
                ax.plot(x, y, style, color=colors[k % len(colors)], lw=1.4, label=label)
                for ref, table in refs:
                    rows = table.get(r.case, {})
                    if var in rows and r.case in ref.cases and var in ref.tolerance:
                        xr = rows[xname] if xname in rows else None
                        if xname == "time":
                            xr = rows["time"]
                        if xr is None:
                            continue
                        ax.plot(
                            _scaled(scene, xname, xr)[0],
                            _scaled(scene, var, rows[var])[0],
                            "o",
                            ms=3.5,
                            mfc="none",
                            color=colors[k % len(colors)],
                        )
                        circles = True
            ax.set_ylabel(_panel_label(scene, panel))
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7, loc="best")
    axes[-1, 0].set_xlabel(xlabel)
    what = "lines: FMU via fmpy" + ("; circles: reference" if circles else "")
    fig.suptitle(f"{scene.title}\n({what})", fontsize=9)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=120, metadata={"Title": scene.title, "Description": what})
    plt.close(fig)
    return path
