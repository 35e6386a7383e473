"""The README's numerical example runs as written (users copy it)."""

from __future__ import annotations

import re
from pathlib import Path

README = Path(__file__).resolve().parents[1] / "README.md"


def test_readme_python_example_runs(capsys):
    blocks = re.findall(r"```python\n(.*?)```", README.read_text(), flags=re.S)
    assert blocks, "README has a python example"
    for code in blocks:
        exec(compile(code, str(README), "exec"), {})
    out = capsys.readouterr().out.split()
    # the example prints the contact ellipse (a1 ~ 2.6 mm) and a finished trajectory
    assert float(out[0]) > 0 and float(out[4]) == 0.05
