"""Data files that an FMU's contact law needs and the build generates: creep-force tables.

A half-space FMU ships the creep-force table of its scene's ``[halfspace]`` declaration
in its resources. This module only packages: the table is computed by the numerics
layer (``python -m contact_fmu.halfspace build-table``, i.e.
``contact_fmu.halfspace.spec.TableSpec.build``) in a process of its own with
single-threaded BLAS, and cached by content under ``cache`` (default ``out/tables``):
the declaration, the sources of the modules that compute the table, and the numpy and
scipy versions make a SHA-256 key. FMUs of several scenes with one declaration (a
contact-mode and a body-mode FMU of one wheel on rail) share one table build, and a
second build of an FMU costs nothing.
"""

from __future__ import annotations

import hashlib
import json
import os
import subprocess
import sys
import tempfile
from importlib import metadata
from pathlib import Path

from contact_fmu.fmu.config import LAW_MODULES, ModelConfig

from . import sources

DEFAULT_CACHE = Path("out") / "tables"
# Threads of BLAS/OpenMP in the table build: GMRES's many small vector operations are
# about ten times slower with threaded OpenBLAS on a shared machine (docs/performance.md).
ENV = {"OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}


class TableBuildError(RuntimeError):
    """The numerics failed to build a table; the message carries their output."""


def key(cfg: ModelConfig) -> str:
    """Content key of the table of ``cfg`` (hex), computed without building it."""
    h = hashlib.sha256()
    h.update(json.dumps(cfg.law_spec, sort_keys=True).encode())
    for dist in ("numpy", "scipy"):
        h.update(f"{dist}={metadata.version(dist)}".encode())
    for rel, src in sources.files(sources.closure([LAW_MODULES[cfg.contact_law]])):
        h.update(rel.encode() + b"\0" + src.read_bytes() + b"\0")
    return h.hexdigest()


def path(cfg: ModelConfig, cache: str | Path = DEFAULT_CACHE) -> Path:
    """Where the table file of ``cfg`` lies in ``cache`` (built or not)."""
    return Path(cache).resolve() / f"{cfg.contact_law}-{key(cfg)[:16]}.npz"


def ensure(cfg: ModelConfig, cache: str | Path = DEFAULT_CACHE) -> Path:
    """The table file of ``cfg`` in ``cache``, built there first if it is missing."""
    cache = Path(cache).resolve()
    target = path(cfg, cache)
    if target.is_file():
        return target
    cache.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(prefix=".table-", dir=cache) as work:
        spec_file = Path(work) / "spec.json"
        spec_file.write_text(json.dumps(cfg.law_spec, indent=1))
        out = Path(work) / "table.npz"
        cmd = [sys.executable, "-m", "contact_fmu.halfspace", "build-table", str(spec_file),
               str(out)]  # fmt: skip
        env = dict(os.environ, PYTHONDONTWRITEBYTECODE="1", **ENV)
        proc = subprocess.run(cmd, capture_output=True, text=True, env=env)
        if proc.returncode != 0 or not out.is_file():
            raise TableBuildError(
                f"creep-force table of {cfg.name} failed ({proc.returncode}):\n"
                f"{proc.stdout}\n{proc.stderr}"
            )
        os.replace(out, target)  # atomic: concurrent builds of one key are harmless
    return target
