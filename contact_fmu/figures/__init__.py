"""Figures regenerated from the model (matplotlib): ``python -m contact_fmu.figures``.

Each module of this package defines ``make_figures(outdir: pathlib.Path) -> list[Path]``;
``__main__`` runs them all (or those named on the command line).
"""

from pathlib import Path

import matplotlib.pyplot as plt


def save(fig, outdir: Path, name: str) -> Path:
    """Write ``fig`` to outdir/name.png (tight layout, 110 dpi) and close it."""
    path = outdir / f"{name}.png"
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
