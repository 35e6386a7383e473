"""The shell commands of the documentation run as written.

Every ```sh block of README.md and docs/*.md holds commands a user types from the
repository root after ``make run`` (``. .venv/bin/activate``: ``contact-fmu`` on the
PATH). Each command runs here in that setting, once (a command shown on several pages
runs once, in the order of first appearance: ``fmpy validate out/fmu/fig13.fmu`` after
the command that builds the FMU), and must exit 0. A command whose line carries one of
the MARKERS (``[long]``, ``[set-up]``, ``[maintainer]``) says so in the doc, and is
reported here as skipped with that reason. ```text blocks show forms with placeholders
and are not run. A command run here must leave the tracked files as they were (a
command that rewrites them is a maintainer's and says so).
"""

from __future__ import annotations

import os
import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
# what the doc writes next to a command that is not run here, and why
MARKERS = {
    "[long]": "runs for minutes (the doc marks it [long])",
    "[set-up]": "needs set-up beyond make venv (the doc marks it [set-up])",
    "[maintainer]": "rewrites tracked files (the doc marks it [maintainer])",
}
TIMEOUT = 600  # s: a cheap command takes seconds to a minute on two cores


def commands(text: str) -> list[str]:
    """The commands of the ```sh blocks: a line's trailing comment kept (for the
    markers), comment-only lines dropped, lines ending in a backslash joined."""
    out: list[str] = []
    for block in re.findall(r"^```(?:sh|bash|shell)\n(.*?)^```", text, flags=re.S | re.M):
        pending = ""
        for line in block.splitlines():
            if not line.strip() or (line.lstrip().startswith("#") and not pending):
                if line.lstrip().startswith("#") and out:
                    out[-1] += " " + line.strip()  # a comment continued below a command
                continue
            if line.rstrip().endswith("\\"):
                pending += line.rstrip()[:-1] + " "
                continue
            out.append(pending + line.strip())
            pending = ""
    return out


def split(line: str) -> tuple[str, str]:
    """(command, comment) of a line: the comment starts at the first '#' outside quotes
    that begins a word."""
    quote = None
    for i, ch in enumerate(line):
        if quote:
            quote = None if ch == quote else quote
        elif ch in "'\"":
            quote = ch
        elif ch == "#" and (i == 0 or line[i - 1].isspace()):
            return shlex.join(shlex.split(line[:i])), line[i + 1 :]
    return shlex.join(shlex.split(line)), ""


def documented() -> list[tuple[str, str, str]]:
    """(command, page, reason to skip or "") in order of first appearance."""
    seen: dict[str, tuple[str, str, str]] = {}
    for page in PAGES:
        for line in commands(page.read_text()):
            command, comment = split(line)
            reason = next((why for m, why in MARKERS.items() if m in comment), "")
            if command not in seen:
                seen[command] = (command, page.relative_to(ROOT).as_posix(), reason)
            elif reason and not seen[command][2]:  # marked on any page: skipped
                seen[command] = (command, seen[command][1], reason)
    return list(seen.values())


DOCUMENTED = documented()


def test_the_docs_show_shell_commands():
    """The collector finds the pages' commands (README's and the command-line page's)."""
    pages = {page for _, page, _ in DOCUMENTED}
    assert {"README.md", "docs/cli.md", "docs/studies.md", "docs/fmu.md"} <= pages
    assert ("make run", "README.md", "") in DOCUMENTED
    runs = [c for c, _, why in DOCUMENTED if not why]
    assert len(runs) >= 10, runs


def test_commands_are_split_from_their_comments():
    line = 'contact-fmu system x.toml --case "eta = 3" --set My_ex=-1  # [long] a # b'
    assert split(line) == (
        "contact-fmu system x.toml --case 'eta = 3' --set My_ex=-1",
        " [long] a # b",
    )
    text = "```sh\na --x \\\n    --y  # c\n# more of c [long]\n```\n```text\nb\n```\n"
    assert commands(text) == ["a --x  --y  # c # more of c [long]"]


def tracked_state() -> str:
    """The tracked files' changes (git status), to compare before and after."""
    done = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no"],
                          cwd=ROOT, capture_output=True, text=True)  # fmt: skip
    return done.stdout if done.returncode == 0 else ""


@pytest.mark.parametrize(("command", "page", "skip"), DOCUMENTED,
                         ids=[c[:60] for c, _, _ in DOCUMENTED])  # fmt: skip
def test_documented_command_exits_zero(command, page, skip):
    if skip:
        pytest.skip(f"{page}: {skip}")
    env = dict(os.environ)
    env["PATH"] = f"{Path(sys.executable).parent}{os.pathsep}{env.get('PATH', '')}"
    env["MPLBACKEND"] = "Agg"
    before = tracked_state()
    done = subprocess.run(command, shell=True, cwd=ROOT, env=env, capture_output=True,
                          text=True, timeout=TIMEOUT)  # fmt: skip
    assert done.returncode == 0, f"{page}: `{command}` exited {done.returncode}:\n" + (
        done.stdout[-1500:] + done.stderr[-1500:]
    )
    assert tracked_state() == before, f"{page}: `{command}` changed tracked files"


def test_the_studies_page_reads_the_sweep_with_pyarrow(capsys):
    """docs/studies.md's python block (pyarrow only: pandas is not installed) on the
    sweep its sh block writes: the first rows are mu = 0.2 exactly as typed, the first
    case (eta = 1.5), adhesion 0.834 (measured; it rises with mu, see the page)."""
    page = ROOT / "docs" / "studies.md"
    (code,) = re.findall(r"```python\n(.*?)```", page.read_text(), flags=re.S)
    if not (ROOT / "out" / "sweeps" / "mu" / "results.parquet").is_file():
        sweep = [c for c, p, _ in DOCUMENTED if p == "docs/studies.md" and "--out" in c]
        assert len(sweep) == 1
        test_documented_command_exits_zero(sweep[0] + " --workers 0", "docs/studies.md", "")
    capsys.readouterr()
    cwd = Path.cwd()
    try:
        os.chdir(ROOT)
        exec(compile(code, str(page), "exec"), {})
    finally:
        os.chdir(cwd)
    out = capsys.readouterr().out
    assert out.startswith("[(0.2, 'eta = 1.5', 0.834)"), out
