"""Figures regenerated from the model (matplotlib): ``python -m contact_fmu.figures``.

Each module of this package defines ``make_figures(outdir: pathlib.Path) -> list[Path]``;
``__main__`` runs them all (or those named on the command line).
"""
