"""Shrink the reproducers of a fuzz summary: the fewest ops that still show each class.

    PYTHONPATH=.:tests python -m fmu_fuzz.shrink out/fuzz/long/summary.json [CLASS ...]

For each failure class (all, or those named) the summary's shortest run is reduced by
deleting ops (halves, quarters, ... single ops) as long as a replay still shows the
class (setupExperiment, enter/exitInitializationMode are kept); the result is printed
as KIND and the ops' JSON. A class that depends on the
draw of a random state byte (a flipped byte) shrinks only as far as its replays agree.
"""

from __future__ import annotations

import json
import sys
import tempfile
from pathlib import Path

from .invariants import check
from .kinds import KINDS
from .pool import Pool

# the life cycle stays, so that a reproducer is a legal call sequence where the run was
KEEP = ("setup", "enter", "exit")


def shows(pool: Pool, kind: str, ops: list[dict], cls: str) -> bool:
    res = pool.execute(KINDS[kind].path, ops)
    return any(v.cls == cls for v in check(KINDS[kind], ops, res))


def shrink(pool: Pool, kind: str, ops: list[dict], cls: str) -> list[dict]:
    if not shows(pool, kind, ops, cls):
        return ops
    size = max(len(ops) // 2, 1)
    while size >= 1:
        i, changed = 0, False
        while i < len(ops):
            trial = ops[:i] + ops[i + size :]
            if any(op["op"] in KEEP for op in ops[i : i + size]):
                i += size
            elif trial and shows(pool, kind, trial, cls):
                ops, changed = trial, True
            else:
                i += size
        if not changed:
            size //= 2
    return ops


def main(argv: list[str]) -> int:
    summary = json.loads(Path(argv[0]).read_text())
    wanted = argv[1:] or list(summary["examples"])
    pool = Pool(Path(tempfile.mkdtemp(prefix="fuzz-shrink-")))
    try:
        for cls in wanted:
            ex = summary["examples"][cls]
            ops = shrink(pool, ex["kind"], ex["ops"], cls)
            print(f"{cls}  {ex['kind']}  {json.dumps(ops)}", flush=True)
    finally:
        pool.close()
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
