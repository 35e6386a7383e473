"""The benchmark runner (``python -m benchmarks``) and the generated blocks of the docs.

The runner cannot rot unnoticed: the cheap benchmarks run with ``--quick`` (small sizes,
seconds each, nothing written), and every marker block of the docs (docs/**/*.md)
(``<!-- NAME: table -->`` ... ``<!-- NAME: end -->``) must be one that a benchmark of
the runner writes, and the other way round, so that ``python -m benchmarks --write``
finds every block it writes. No timing is asserted: the benchmarks' numbers are for
the docs, not for the tests.
"""

from __future__ import annotations

import functools
import importlib.util
import re
import subprocess
import sys
from pathlib import Path

import pytest

from contact_fmu.fmu.variables import DOCS_MARKS as VARIABLES_MARKS
from contact_fmu.report.command import (
    ACCURACY_STIFF,
    ACCURACY_WP,
    PERF_STIFF_SECTION,
    PERF_WP_SECTION,
)

ROOT = Path(__file__).resolve().parents[1]
DOCS = sorted((ROOT / "docs").rglob("*.md"))
PERFORMANCE = ROOT / "docs" / "performance.md"
MARKER = re.compile(r"^<!-- (.+): (table|end) -->$")
# the sections of performance.md that `contact-fmu report --write-docs` writes whole
REPORT_SECTIONS = (PERF_WP_SECTION, PERF_STIFF_SECTION)
# ... and of every page (docs/accuracy.md too), by page name
WRITTEN_SECTIONS = {"performance.md": REPORT_SECTIONS, "accuracy.md": (ACCURACY_WP, ACCURACY_STIFF)}
# a table's header that names a time or a rate: a measurement of the machine, which only
# a benchmark (or the report) may write
SEPARATOR = re.compile(r"^\|(:?-+:?\|)+$")
TIMED_HEADER = re.compile(r"\((s|ms|us|ns)\)|\b(ms|us|ns)\b|seconds|\bwall\b|per second|steps/s")
# marker blocks written by the package itself, not by a benchmark: the table of
# docs/variables.md (python -m contact_fmu.fmu.variables --write-docs)
PACKAGE_BLOCKS = {MARKER.match(VARIABLES_MARKS[0]).group(1)}


def _runner(*args: str, timeout: float = 60) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "benchmarks", *args],
        cwd=ROOT, capture_output=True, text=True, timeout=timeout,
    )  # fmt: skip


def _listing() -> list[tuple[str, bool, tuple[str, ...]]]:
    """(name, cheap, blocks) of every benchmark, from ``--list``."""
    proc = _runner("--list")
    assert proc.returncode == 0, proc.stderr
    rows = []
    for line in proc.stdout.splitlines():
        name, quick, blocks, _ = line.split("\t")
        names = blocks.removeprefix("blocks: ")
        rows.append(
            (name, quick == "quick: seconds", tuple(names.split("; ")) if names != "-" else ())
        )
    return rows


def _doc_blocks(text: str) -> dict[str, tuple[int, int, str]]:
    """name -> (first line, last line, text) of each marker block (harness.block_spans,
    which refuses a marker without its partner or a name twice)."""
    lines = text.split("\n")
    spans = _load_harness().block_spans(text)
    return {name: (a, b, "\n".join(lines[a + 1 : b])) for name, (a, b) in spans.items()}


@functools.cache
def _load_harness():
    """benchmarks/harness.py as a module of its own (no change to sys.path), loaded once."""
    spec = importlib.util.spec_from_file_location(
        "bench_harness", ROOT / "benchmarks" / "harness.py"
    )
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # its dataclasses look their module up there
    spec.loader.exec_module(module)
    return module


def test_every_block_of_the_docs_is_written_by_a_benchmark_and_every_written_block_exists():
    listing = _listing()
    written = {b for _, _, blocks in listing for b in blocks}
    assert len(written) == sum(len(blocks) for _, _, blocks in listing)  # no block twice
    in_docs = {name for page in DOCS for name in _doc_blocks(page.read_text())}
    assert in_docs - written == PACKAGE_BLOCKS, "blocks that no benchmark writes"
    assert written - in_docs == set(), "blocks a benchmark writes that no page holds"


def test_every_table_of_the_performance_page_is_generated():
    """Each table row of docs/performance.md lies in a marker block or in a section that
    `contact-fmu report --write-docs` writes: no table pasted by hand."""
    text = PERFORMANCE.read_text()
    spans = [(a, b) for a, b, _ in _doc_blocks(text).values()]
    section = ""
    pasted = []
    for i, line in enumerate(text.split("\n")):
        if line.startswith("## "):
            section = line
        if line.startswith("|") and section not in REPORT_SECTIONS:
            if not any(a < i < b for a, b in spans):
                pasted.append(f"{i + 1}: {line[:60]}")
    assert pasted == []


def _unblocked_rows(page: Path, row) -> list[str]:
    """The table lines of ``page`` for which ``row(line, header)`` holds that lie neither
    in a marker block nor in a section the report writes whole."""
    text = page.read_text()
    spans = [(a, b) for a, b, _ in _doc_blocks(text).values()]
    written = WRITTEN_SECTIONS.get(page.name, ())
    section, header, found = "", "", []
    lines = text.split("\n")
    for i, line in enumerate(lines):
        if line.startswith("## "):
            section = line
        if not line.startswith("|"):
            header = ""
            continue
        if not header:  # a table starts at a row followed by its separator row
            following = lines[i + 1] if i + 1 < len(lines) else ""
            if not SEPARATOR.match(following.replace(" ", "")):
                continue  # a line of prose that starts with |x|
            header = line
        if section in written or any(a < i < b for a, b in spans):
            continue
        if row(line, header):
            found.append(f"{page.parent.name}/{page.name}:{i + 1}: {line[:60]}")
    return found


def test_every_timed_table_of_the_docs_is_generated():
    """On every page of the docs, a table that reports times or rates (a header naming
    s, ms, us, seconds, wall or a rate) lies in a marker block a benchmark writes, or in a
    section the report writes: the numbers of a machine are never pasted by hand, so
    that a page quoting them links to the one generated table."""
    timed = []
    for page in DOCS:
        timed += _unblocked_rows(page, lambda line, header: bool(TIMED_HEADER.search(header)))
    assert timed == []


def test_the_timed_table_check_sees_a_pasted_table(tmp_path):
    """The check is not vacuous: a pasted table of times is found, the same table in a
    block is not, nor is a table without times."""
    page = tmp_path / "page.md"
    table = "| grid | solve (ms) |\n|---|---|\n| 16 | 1.0 |\n"
    page.write_text("# P\n\n" + table + "\n| a | b |\n|---|---|\n| 1 | 2 |\n\n|v| (s) is prose\n")
    rows = _unblocked_rows(page, lambda line, header: bool(TIMED_HEADER.search(header)))
    assert [r.split(": ", 1)[1] for r in rows] == ["| grid | solve (ms) |", "|---|---|",
                                                   "| 16 | 1.0 |"]  # fmt: skip
    page.write_text("# P\n\n<!-- b.py: table -->\n" + table + "<!-- b.py: end -->\n")
    assert _unblocked_rows(page, lambda line, header: True) == []


def test_every_block_names_the_command_that_made_it():
    """A block's text carries its command in backticks: the script of the block's name
    (bench_native.py for "bench_native.py spin") or the runner."""
    for page in DOCS:
        for name, (_, _, body) in _doc_blocks(page.read_text()).items():
            if name in PACKAGE_BLOCKS:
                continue
            script = name.split()[0]
            commands = re.findall(r"`([^`]+)`", body.replace("\n", " "))
            assert any(script in c or "-m benchmarks" in c for c in commands), (page.name, name)


def test_write_block_replaces_only_the_block_and_refuses_a_page_without_its_markers(tmp_path):
    harness = _load_harness()
    page = "# Page\n\nprose before\n<!-- b.py: table -->\nold\n<!-- b.py: end -->\nprose after\n"
    doc = tmp_path / "page.md"
    doc.write_text(page)
    harness.write_block(doc, "b.py", "| a | b |\n|---|---|\n| 1 | 2 |")
    assert doc.read_text() == page.replace("old", "| a | b |\n|---|---|\n| 1 | 2 |")
    with pytest.raises(ValueError, match="c.py"):
        harness.write_block(doc, "c.py", "new")
    with pytest.raises(ValueError, match="no end marker"):
        harness.blocks("<!-- b.py: table -->\ntext\n")


def test_quick_and_write_together_are_refused_and_an_unknown_name_is_named():
    proc = _runner("--quick", "--write")
    assert proc.returncode == 2 and "--quick with --write" in proc.stderr
    proc = _runner("no_such_bench", "--quick")
    assert proc.returncode == 2 and "'no_such_bench'" in proc.stderr


def _cheap() -> list[str]:
    return [name for name, cheap, _ in _listing() if cheap]


def _has_revision(rev: str) -> bool:
    cmd = ["git", "cat-file", "-e", f"{rev}^{{commit}}"]
    return subprocess.run(cmd, cwd=ROOT, capture_output=True).returncode == 0


@pytest.mark.parametrize("name", _cheap())
def test_a_cheap_benchmark_runs_with_quick_and_writes_nothing(name):
    if name == "halfspace_small" and not _has_revision("cc7bca5"):
        pytest.skip("the previous solver's revision cc7bca5 is not in this clone")
    pages = {p: p.read_bytes() for p in DOCS}
    proc = _runner(name, "--quick", timeout=300)
    assert proc.returncode == 0, (proc.stdout[-2000:], proc.stderr[-3000:])
    assert f"=== {name}" in proc.stdout
    assert {p: p.read_bytes() for p in DOCS} == pages


@pytest.mark.parametrize("script", sorted(p.name for p in (ROOT / "benchmarks").glob("bench_*.py")))
def test_each_benchmark_still_runs_as_a_script(script):
    """The command lines of the docs call the scripts themselves: run as a script (its
    folder first on sys.path, no package), each imports harness and its siblings."""
    proc = subprocess.run(
        [sys.executable, f"benchmarks/{script}", "--help"],
        cwd=ROOT, capture_output=True, text=True, timeout=120,
    )  # fmt: skip
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert "usage:" in proc.stdout
