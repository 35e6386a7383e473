"""Session-wide pytest hooks.

The suite loads several dozen pythonfmu FMUs (fmpy and libcosim) into this one process.
pythonfmu's native wrapper can corrupt the heap when its libraries are torn down at
interpreter exit (its use-after-free in finalizePythonInterpreter, reported upstream at
https://github.com/NTNU-IHB/PythonFMU/issues/228: "free(): corrupted unsorted chunks";
seen here once, as "corrupted double-linked list" after every test had passed). The
results are reported by then, so the process ends without the interpreter's
finalisation, keeping pytest's exit status: a failing test still fails the run.
"""

from __future__ import annotations

import os
import sys

import pytest

_status: list[int] = []


@pytest.fixture(autouse=True)
def _fmpy_logger_alive():
    """fmpy passes every FMI 2.0 log message of the process to one global callback,
    the one registered last; ``simulate_fmu(logger=f)`` (as some tests call it) leaves
    it pointing at ``f`` after f is freed, and the next message of any FMU would crash
    the process (contact_fmu/scenario/fmpy_log.py). Each test ends with the global
    callback back on a live one."""
    yield
    from contact_fmu.scenario import fmpy_log

    fmpy_log.claim()


def pytest_sessionfinish(session: pytest.Session, exitstatus: int) -> None:
    _status.append(int(exitstatus))


@pytest.hookimpl(trylast=True)
def pytest_unconfigure(config: pytest.Config) -> None:
    """After the summary and every plugin's own unconfigure: exit with pytest's status."""
    if _status and not hasattr(sys, "ps1"):  # not inside an interactive session
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(_status[-1])
