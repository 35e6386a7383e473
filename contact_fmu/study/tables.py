"""Creep-force tables built through an ``Engine``: the table's independent solves
(``halfspace.table.build_table``'s tasks: one line of nodes, or one load's onset of full
slip) as tasks, the same table as the serial build.

``ensure`` puts the table where the FMU build looks for it (``fmu_build.tables``: the
same content key and file), so a later ``fmu_build.build`` takes it from the cache.
"""

from __future__ import annotations

import json
import os
import tempfile
from pathlib import Path

from ..fmu.config import ModelConfig
from ..halfspace.spec import TableSpec
from ..halfspace.table import CreepTable
from .engine import Engine


def build(spec: TableSpec, engine: Engine, batch: int | None = None) -> CreepTable:
    """The table of ``spec`` with its solves run by ``engine``."""
    return spec.build(map_tasks=engine.mapper("creep-force table", batch=batch))


def ensure(cfg: ModelConfig, engine: Engine, cache: str | Path | None = None) -> Path | None:
    """The table file of ``cfg`` in the FMU build's table cache, built through ``engine``
    if missing (None for a law without a table). In this process (``workers=0``) the
    FMU build's own path builds it (a subprocess with single-threaded BLAS)."""
    from fmu_build import tables

    if not cfg.has_table:
        return None
    cache = Path(tables.DEFAULT_CACHE if cache is None else cache)
    target = tables.path(cfg, cache)
    if target.is_file():
        return target
    if engine.serial:
        return tables.ensure(cfg, cache)
    spec = TableSpec.from_dict(json.loads(json.dumps(cfg.law_spec)))  # as the build reads it
    table = build(spec, engine)
    target.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(prefix=".table-", dir=target.parent) as work:
        written = table.save(Path(work) / "table.npz")
        os.replace(written, target)  # atomic: concurrent builds of one key are harmless
    return target
