"""Replay one run and print its call records and violations.

    PYTHONPATH=.:tests python -m fmu_fuzz.replay KIND 'OPS-JSON'   (or @file.json)

KIND is a key of ``kinds.KINDS``; OPS-JSON the worker ops of a reproducer (as the
test's failure message or out/fuzz/*/summary.md print them).
"""

from __future__ import annotations

import json
import sys
import tempfile
from pathlib import Path

from .invariants import check
from .kinds import KINDS
from .pool import Pool


def main(argv: list[str]) -> int:
    kind, text = argv[0], argv[1]
    ops = json.loads(Path(text[1:]).read_text() if text.startswith("@") else text)
    k = KINDS[kind]
    pool = Pool(Path(tempfile.mkdtemp(prefix="fuzz-replay-")))
    try:
        res = pool.execute(k.path, ops)
    finally:
        pool.close()
    for n, rec in enumerate(res.records):
        op = ops[rec["i"]] if 0 <= rec["i"] < len(ops) else {}
        extra = {x: rec[x] for x in ("t", "h", "name", "phase", "skipped") if x in rec}
        print(f"{n:3d} op {rec['i']:2d} {rec['call']:24s} -> {rec['status']} {extra} {op}")
        for s, m in rec["log"]:
            print(f"        log [{s}] {m[:300]}")
    if res.crashed or res.hung:
        print(f"crashed={res.crashed} hung={res.hung} rc={res.returncode}\n{res.stderr_tail}")
    for v in check(k, ops, res):
        print(f"VIOLATION {v.cls} at record {v.index}: {v.detail[:400]}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
