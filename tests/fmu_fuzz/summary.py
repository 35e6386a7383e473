"""Counts of a fuzz session: runs, calls, statuses per call, crashes, violations.

``Stats.add`` takes each run; ``write`` puts the summary as JSON and Markdown under
out/fuzz (the Markdown table is what `make fuzz` prints), with the shortest run that
showed each failure class as its reproducer.
"""

from __future__ import annotations

import json
import time
from collections import Counter, defaultdict
from pathlib import Path

from .invariants import Violation
from .pool import Result

STATUS = ("OK", "Warning", "Discard", "Error", "Fatal")


class Stats:
    def __init__(self) -> None:
        self.t0 = time.monotonic()
        self.runs: Counter[str] = Counter()
        self.calls = 0
        self.statuses: dict[str, Counter[str]] = defaultdict(Counter)
        self.classes: Counter[str] = Counter()  # runs showing each class
        self.by_kind: dict[str, Counter[str]] = defaultdict(Counter)
        self.examples: dict[str, dict] = {}  # class -> the shortest run showing it
        self.crashes = 0
        self.hangs = 0
        self.seconds: Counter[str] = Counter()

    def add(self, kind: str, ops: list[dict], res: Result, violations: list[Violation]) -> None:
        self.runs[kind] += 1
        self.seconds[kind] += res.seconds
        self.calls += len(res.records)
        for r in res.records:
            self.statuses[r["call"]][STATUS[r["status"]] if 0 <= r["status"] < 5 else "?"] += 1
        self.crashes += res.crashed
        self.hangs += res.hung
        for cls in {v.cls for v in violations}:
            self.classes[cls] += 1
            self.by_kind[cls][kind] += 1
            first = next(v for v in violations if v.cls == cls)
            old = self.examples.get(cls)
            if old is None or len(ops) < len(old["ops"]):
                self.examples[cls] = {
                    "kind": kind,
                    "ops": ops,
                    "record": first.index,
                    "detail": first.detail,
                }

    def as_dict(self) -> dict:
        return {
            "runs": dict(self.runs),
            "runs_total": sum(self.runs.values()),
            "calls": self.calls,
            "statuses": {c: dict(s) for c, s in sorted(self.statuses.items())},
            "crashes": self.crashes,
            "hangs": self.hangs,
            "violations": {c: dict(self.by_kind[c]) for c, _ in self.classes.most_common()},
            "examples": self.examples,
            "seconds": round(time.monotonic() - self.t0, 1),
            "seconds_in_runs": {k: round(v, 1) for k, v in self.seconds.items()},
        }

    def markdown(self, command: str) -> str:
        d = self.as_dict()
        lines = [
            f"# FMU fuzz summary (`{command}`)",
            "",
            f"{d['runs_total']} runs, {d['calls']} FMI calls, {d['crashes']} crashes, "
            f"{d['hangs']} hangs, {d['seconds']} s.",
            "",
            "Runs per kind: " + ", ".join(f"{k} {n}" for k, n in sorted(d["runs"].items())),
            "",
            "| call | " + " | ".join(STATUS) + " |",
            "|---|" + "---|" * len(STATUS),
        ]
        for call, s in d["statuses"].items():
            lines.append(f"| {call} | " + " | ".join(str(s.get(x, 0)) for x in STATUS) + " |")
        lines += ["", "| failure class | runs | by kind |", "|---|---|---|"]
        for cls, kinds in d["violations"].items():
            by = ", ".join(f"{k} {n}" for k, n in sorted(kinds.items()))
            lines.append(f"| {cls} | {sum(kinds.values())} | {by} |")
        lines += ["", "Shortest run per class (worker ops; `record`: the call that failed):", ""]
        for cls, ex in d["examples"].items():
            lines.append(f"- {cls} ({ex['kind']}): {ex['detail'][:300]}")
            lines.append(f"  ops: `{json.dumps(ex['ops'])}`")
        return "\n".join(lines) + "\n"

    def write(self, out_dir: Path, command: str) -> Path:
        out_dir.mkdir(parents=True, exist_ok=True)
        (out_dir / "summary.json").write_text(json.dumps(self.as_dict(), indent=1) + "\n")
        md = out_dir / "summary.md"
        md.write_text(self.markdown(command))
        return md
