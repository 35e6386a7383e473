"""The command line as a user meets it: values as typed, files where they belong, one
line for a mistake."""

from __future__ import annotations

import hashlib
from pathlib import Path

import pytest

from contact_fmu import cli
from contact_fmu.scenario import load
from contact_fmu.scenario.schema import sweep_values
from contact_fmu.study import engine

ROOT = Path(__file__).resolve().parents[1]
BRAKE = ROOT / "scenarios" / "brake.toml"


def test_a_range_gives_the_decimals_as_typed():
    """0.2:0.4:5 is 0.2, 0.25, 0.3, 0.35, 0.4: each value is the double nearest to the
    decimal (computed in decimal arithmetic, then rounded once), so it equals the literal
    a user types; numpy's linspace gives 0.30000000000000004 for the middle one."""
    assert sweep_values("--vary mu", "0.2:0.4:5") == (0.2, 0.25, 0.3, 0.35, 0.4)
    assert cli._vary("mu=0.2:0.4:5").values[2] == 0.3
    # a third is not a decimal: the nearest double, 1/3 rounded once
    assert sweep_values("x", "0:1:4")[1:3] == (1 / 3, 2 / 3)
    with pytest.raises(ValueError, match="start:stop:n"):
        sweep_values("x", "a:1:3")


def _digests(paths: list[Path]) -> dict[Path, str]:
    return {p: hashlib.sha256(p.read_bytes()).hexdigest() for p in paths}


def test_references_go_under_out_unless_overwrite(tmp_path, capsys):
    """The stored references (tracked files) stay as they are; the regenerated ones are
    written under OUT/references/<scene>/ with the same names."""
    scene = load(BRAKE)
    stored = [r.file for r in scene.references]
    before = _digests(stored)
    assert cli.main(["references", str(BRAKE), "--out", str(tmp_path)]) == 0
    assert _digests(stored) == before
    folder = tmp_path / "references" / "brake"
    assert sorted(p.name for p in folder.iterdir()) == sorted(p.name for p in stored)
    assert "--overwrite" in capsys.readouterr().out


def test_an_unreachable_scheduler_is_one_line(monkeypatch):
    """Nothing listens on port 1: the command ends with one line naming the address
    (after the connection timeout, shortened here), not a traceback."""
    monkeypatch.setattr(engine, "CONNECT_TIMEOUT", 2.0)
    args = ["sweep", str(ROOT / "scenarios" / "fig13.toml"), "--vary", "mu=0.2,0.3",
            "--scheduler", "tcp://127.0.0.1:1", "--no-progress"]  # fmt: skip
    with pytest.raises(SystemExit) as e:
        cli.main(args)
    message = str(e.value.code)
    assert message.startswith("contact-fmu sweep: scheduler = 'tcp://127.0.0.1:1'")
    assert "\n" not in message and "running Dask scheduler" in message


def test_a_load_that_varies_in_time_is_refused_in_one_line(capsys):
    """Fig. 13's moment is a sine: a system file (constant inputs) cannot carry it."""
    assert cli.main(["system", str(ROOT / "scenarios" / "fig13.toml")]) == 1
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "My_ex" in err and "--set My_ex=VALUE" in err
