"""A metric of a study over one varied name (lines) or two (a heat map).

Rows that differ in anything else (the case, other varied names) are drawn apart: one
line each, or one heat-map panel each (up to MAX_PANELS). Failed runs are gaps.
"""

from __future__ import annotations

import math
import textwrap
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from ..scenario.labels import axis_label, metric_label
from ..scenario.schema import Metric

MAX_PANELS = 12


def _groups(rows: list[dict[str, Any]], keys: list[str]) -> dict[tuple, list[dict[str, Any]]]:
    out: dict[tuple, list[dict[str, Any]]] = {}
    for r in rows:
        out.setdefault(tuple(r[k] for k in keys), []).append(r)
    return out


def _label(keys: list[str], values: tuple) -> str:
    return ", ".join(
        f"{v}" if k == "case" else f"{k} = {v:.4g}" for k, v in zip(keys, values, strict=True)
    )


def plot(
    rows: list[dict[str, Any]],
    varied: list[str],
    metric: str,
    x: str,
    y: str | None,
    path: Path,
    title: str = "",
    metrics: Sequence[Metric] = (),
) -> Path:
    """Write the plot of ``metric`` over ``x`` (and ``y``) to ``path`` (PNG); axes labelled
    with units (``scenario.labels``), the metric's from its definition among ``metrics``
    (without it, the metric's name alone)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.ticker import MaxNLocator

    defined = {m.name: m for m in metrics}
    zlabel = metric_label(defined[metric]) if metric in defined else metric
    rest = [k for k in varied if k not in (x, y)] + ["case"]
    groups = _groups(rows, rest)
    if y is None:
        fig, ax = plt.subplots(figsize=(6.4, 4.2))
        for key, rs in groups.items():
            rs = sorted(rs, key=lambda r: r[x])
            ax.plot([r[x] for r in rs], [r[metric] for r in rs], "o-", ms=3,
                    label=_label(rest, key))  # fmt: skip
        ax.set_xlabel(axis_label(x))
        ax.set_ylabel(zlabel)
        if len(groups) > 1:
            ax.legend(fontsize="small")
        ax.grid(alpha=0.3)
    else:
        keys = list(groups)[:MAX_PANELS]
        ncol = min(3, len(keys))
        nrow = math.ceil(len(keys) / ncol)
        size = (6.4, 4.8) if len(keys) == 1 else (4.6 * ncol, 3.8 * nrow)
        fig, axes = plt.subplots(nrow, ncol, figsize=size, squeeze=False)
        for ax, key in zip(axes.flat, keys, strict=False):
            rs = groups[key]
            xs = sorted({r[x] for r in rs})
            ys = sorted({r[y] for r in rs})
            z = np.full((len(ys), len(xs)), np.nan)
            for r in rs:
                z[ys.index(r[y]), xs.index(r[x])] = r[metric]
            m = ax.pcolormesh(_edges(xs), _edges(ys), np.ma.masked_invalid(z), shading="flat")
            fig.colorbar(m, ax=ax, label=zlabel)
            ax.set_xlabel(axis_label(x))
            ax.set_ylabel(axis_label(y))
            ax.xaxis.set_major_locator(MaxNLocator(5))
            if len(groups) > 1:
                ax.set_title(_label(rest, key), fontsize="small")
        for ax in list(axes.flat)[len(keys) :]:
            ax.set_visible(False)
    if title:
        fig.suptitle(textwrap.fill(title, 70), fontsize="medium")
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def _edges(v: list[float]) -> np.ndarray:
    """Cell edges around sorted centres (midpoints; the ends mirrored)."""
    c = np.asarray(v, float)
    if c.size == 1:
        return np.array([c[0] - 0.5, c[0] + 0.5])
    mid = 0.5 * (c[1:] + c[:-1])
    return np.concatenate([[2 * c[0] - mid[0]], mid, [2 * c[-1] - mid[-1]]])
