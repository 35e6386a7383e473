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
