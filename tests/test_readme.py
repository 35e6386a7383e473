"""The examples users copy run as written: the Python blocks of docs/python.md (the
numerical API) and of README.md (the FMU in fmpy)."""

from __future__ import annotations

import re
from pathlib import Path

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
