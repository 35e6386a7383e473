"""The examples users copy run as written: the Python blocks of docs/python.md (the
numerical API) and of README.md (the FMU in fmpy)."""

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
