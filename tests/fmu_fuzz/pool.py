"""Persistent worker subprocesses, one per FMU kind: a crash costs a restart, not the run.

``Pool.execute(kind, ops)`` sends a run to the kind's worker (started on first use:
importing fmpy and extracting the FMU once) and returns a ``Result``: the per-call
records, and whether the worker crashed (died by a signal or exited) or hung (no
answer within the time limit: killed). A worker that died, hung, or ended a run at an
fmi2Fatal is replaced by a fresh one for the next run.
"""

from __future__ import annotations

import json
import os
import selectors
import signal
import subprocess
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

WORKER = Path(__file__).resolve().with_name("worker.py")


@dataclass
class Result:
    records: list[dict] = field(default_factory=list)
    crashed: bool = False  # the process died during the run (returncode below)
    returncode: int | None = None
    hung: bool = False  # no answer within the time limit
    fatal: bool = False  # ended at an fmi2Fatal
    stderr_tail: str = ""
    seconds: float = 0.0


class Worker:
    def __init__(self, fmu: Path, log_dir: Path) -> None:
        log_dir.mkdir(parents=True, exist_ok=True)
        self.log_path = log_dir / f"worker-{fmu.stem}.log"
        self.log = open(self.log_path, "ab")  # noqa: SIM115 - lives as long as the worker
        self._log_start = self.log.tell()
        env = dict(os.environ, OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1")
        self.proc = subprocess.Popen(
            [sys.executable, str(WORKER), str(fmu)],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=self.log,
            env=env,
        )
        self.sel = selectors.DefaultSelector()
        self.sel.register(self.proc.stdout, selectors.EVENT_READ)
        self.buf = b""
        ready = self._line(60.0)
        if not ready or not json.loads(ready).get("ready"):
            self.close()
            raise RuntimeError(f"fuzz worker for {fmu} did not start: {self._tail()}")

    def _line(self, timeout: float) -> bytes | None:
        """The next line of the protocol; None after ``timeout`` s; b"" at EOF."""
        deadline = time.monotonic() + timeout
        while b"\n" not in self.buf:
            left = deadline - time.monotonic()
            if left <= 0 or not self.sel.select(left):
                return None
            chunk = os.read(self.proc.stdout.fileno(), 1 << 16)
            if not chunk:
                return b""
            self.buf += chunk
        line, _, self.buf = self.buf.partition(b"\n")
        return line

    def _tail(self, n: int = 6000) -> str:
        self.log.flush()
        try:
            with open(self.log_path, "rb") as f:
                f.seek(self._log_start)
                return f.read().decode(errors="replace")[-n:]
        except OSError:
            return ""

    def run(self, ops: list[dict], timeout: float) -> Result:
        res = Result()
        t0 = time.monotonic()
        try:
            self.proc.stdin.write((json.dumps({"ops": ops}) + "\n").encode())
            self.proc.stdin.flush()
        except BrokenPipeError:
            res.crashed = True
        while not res.crashed:
            line = self._line(max(0.0, t0 + timeout - time.monotonic()))
            if line is None:  # alive but silent: hung
                res.hung = True
                self.proc.kill()
                break
            if line == b"":  # the pipe closed: the worker died
                res.crashed = True
                break
            msg = json.loads(line)
            if msg.get("done"):
                res.fatal = bool(msg.get("fatal"))
                break
            res.records.append(msg)
        res.seconds = time.monotonic() - t0
        if res.crashed or res.hung:
            res.returncode = self.proc.wait()
            res.stderr_tail = self._tail()
        return res

    @property
    def alive(self) -> bool:
        return self.proc.poll() is None

    def close(self) -> None:
        if self.proc.poll() is None:
            try:
                self.proc.stdin.close()
                self.proc.wait(timeout=10)
            except (OSError, subprocess.TimeoutExpired):
                self.proc.kill()
                self.proc.wait()
        self.sel.close()
        self.log.close()


class Pool:
    """A worker per FMU, restarted whenever one could not go on."""

    def __init__(self, log_dir: Path, timeout: float = 120.0) -> None:
        self.log_dir = log_dir
        self.timeout = timeout
        self.workers: dict[Path, Worker] = {}
        self.restarts = 0

    def execute(self, fmu: Path, ops: list[dict]) -> Result:
        w = self.workers.get(fmu)
        if w is None or not w.alive:
            if w is not None:
                w.close()
                self.restarts += 1
            w = self.workers[fmu] = Worker(fmu, self.log_dir)
        res = w.run(ops, self.timeout)
        if res.crashed or res.hung or res.fatal:
            w.close()
            del self.workers[fmu]
            self.restarts += 1
        return res

    def release(self, fmu: Path) -> None:
        """End the worker of ``fmu`` (its runs are done)."""
        w = self.workers.pop(fmu, None)
        if w is not None:
            w.close()

    def close(self) -> None:
        for w in self.workers.values():
            w.close()
        self.workers.clear()


def signal_name(returncode: int | None) -> str:
    if returncode is not None and returncode < 0:
        try:
            return signal.Signals(-returncode).name
        except ValueError:
            pass
    return f"exit {returncode}"
