"""The figure command regenerates the paper's figures (make figures; docs/cli.md)."""

from __future__ import annotations

from pathlib import Path

from contact_fmu.figures.__main__ import main

PAPER_FIGURES = (2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13)


def test_paper_figures_are_regenerated(tmp_path: Path, capsys):
    main(["paper", "--out", str(tmp_path)])
    printed = capsys.readouterr().out.split()
    made = sorted(tmp_path.glob("fig*.png"))
    assert [int(p.name[3:5]) for p in made] == list(PAPER_FIGURES)
    assert sorted(printed) == sorted(str(p) for p in made)
    assert all(p.stat().st_size > 10_000 for p in made)  # a real plot, not an empty canvas


HALFSPACE_FILES = (
    "halfspace_adhesion_areas.png",
    "halfspace_creep_curves.png",
    "halfspace_curves.csv",
    "halfspace_exact_fastsim.png",
    "halfspace_solution_plot.png",
)


def test_halfspace_figures_are_regenerated_and_shown_in_the_docs(tmp_path: Path, capsys):
    """The half-space figures (docs/halfspace.md): the curves, the adhesion areas, and the
    two pictures the library draws (RollingSolution.plot, plot_creep_curves), each a real
    plot, and each picture embedded in the docs page it belongs to."""
    main(["halfspace", "--out", str(tmp_path)])
    printed = capsys.readouterr().out.split()
    assert sorted(Path(p).name for p in printed) == list(HALFSPACE_FILES)
    pngs = [tmp_path / n for n in HALFSPACE_FILES if n.endswith(".png")]
    assert all(p.stat().st_size > 10_000 for p in pngs)
    page = (Path(__file__).resolve().parents[1] / "docs" / "halfspace.md").read_text()
    for name in ("halfspace_exact_fastsim.png", "halfspace_solution_plot.png"):
        assert f"](figures/{name})" in page
