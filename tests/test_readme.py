"""The examples users copy run as written: the Python blocks of docs/python.md (the
numerical API), docs/halfspace.md (the half-space solver as CONTACT users call it) and
README.md (the FMU in fmpy)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def python_blocks(path: Path) -> list[str]:
    return re.findall(r"```python\n(.*?)```", path.read_text(), flags=re.S)


def test_numerical_api_example_runs(capsys):
    page = ROOT / "docs" / "python.md"
    blocks = python_blocks(page)
    assert blocks, "docs/python.md has a python example"
    for code in blocks:
        exec(compile(code, str(page), "exec"), {})
    out = capsys.readouterr().out.split()
    # the example prints the contact ellipse (a1 ~ 2.6 mm) and a finished trajectory
    assert float(out[0]) > 0 and float(out[4]) == 0.05


def test_halfspace_page_examples_run(monkeypatch):
    """docs/halfspace.md's blocks (constructors, solve, creepages_for, plots, FASTSIM,
    Carter's line contact, CONTACT's sign conventions) run as written. Checked from
    their results: creepages_for's solution carries the prescribed forces (Fx, Fy) =
    (20, 5) kN to its tolerance rtol = 1e-8 of mu P = 30 kN, and CONTACT's forces on
    the wheel are the opposite of the forces on the substrate."""
    import matplotlib

    matplotlib.use("Agg")
    monkeypatch.chdir(ROOT)
    page = ROOT / "docs" / "halfspace.md"
    blocks = python_blocks(page)
    assert len(blocks) == 2, "docs/halfspace.md: the API block and the FASTSIM block"
    ns: dict = {}
    for code in blocks:
        exec(compile(code, str(page), "exec"), ns)
    mu_P = 0.3 * 1e5
    s, Fx, Fy = ns["s"], ns["Fx"], ns["Fy"]
    assert abs(s.Tx - 20e3) <= 1e-8 * mu_P and abs(s.Ty - 5e3) <= 1e-8 * mu_P
    assert (Fx, Fy) == (-s.Tx, -s.Ty)


def test_readme_fmpy_example_runs(capsys, monkeypatch):
    """README's fmpy example on the Fig. 13 FMU with eta = 3 (Iy = 8.33e-4): after the
    slip transient Tx follows Eq. (26), Tx = A2 Fx_ex - A1 My_ex/Rx, largest where
    sin(t/T_c) = -1: A2 191 + A1 1.91/0.05 = 76.39 N (A1 = eta/(1 + eta), A2 = 1 -
    A1), within the scene's Tx tolerance against Eq. (26), 0.2 N (derived in
    scenarios/fig13.toml); 76.4 N < mu P = 300 N, so the body keeps rolling."""
    import fmu_build
    from contact_fmu.scenario import load

    fmu_build.build(load(ROOT / "scenarios" / "fig13.toml").config, ROOT / "out" / "fmu")
    monkeypatch.chdir(ROOT)  # the example names out/fmu/fig13.fmu, as after `make run`
    blocks = python_blocks(ROOT / "README.md")
    assert len(blocks) == 1, "README has one python example (the fmpy run)"
    exec(compile(blocks[0], "README.md", "exec"), {})
    t_end, tx_max, regime = (float(x) for x in capsys.readouterr().out.split())
    eta = 1.0 * 0.05**2 / 8.33e-4
    a1 = eta / (1.0 + eta)
    assert t_end == pytest.approx(0.056, abs=1e-12)
    assert abs(tx_max - ((1.0 - a1) * 191.0 + a1 * 1.91 / 0.05)) < 0.2
    assert regime == 0.0
