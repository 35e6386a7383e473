"""Contact laws by scene name, built from FMU parameters (SI).

Imports are lazy so that a built FMU carries only the law it uses; the module of each
law is listed in ``config.LAW_MODULES`` for the build.

The half-space law reads the creep-force table that the build generated and shipped in
the FMU's resources (``config.GENERATED_DATA``, relative to ``data_dir``: the adapter
passes the vendored package's folder in the resources of the instance being set up,
since FMUs of one content key share their imported modules in a process, but not their
extraction folders). An FMU reads its own table, never one of the source tree or of the
build cache. A table is loaded once per declaration and process and shared by the
instances (the law objects are immutable; equal declarations give equal tables).
"""

from __future__ import annotations

import importlib
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

from .config import GENERATED_DATA, LAW_MODULES, ModelConfig

# The package this module was vendored into (contact_fmu in the source tree).
PACKAGE_DIR = Path(__file__).resolve().parent.parent
# Half-space tables loaded in this process: spec key -> TableLaw at its first load node.
_TABLES: dict[str, Any] = {}


def _layer(cfg: ModelConfig, p: Mapping[str, Any], P: float, data_dir: Path | None) -> Any:
    layer = importlib.import_module(f"..{LAW_MODULES['layer']}", __package__)
    return layer.LayerContact(
        P=P, Rx=p["Rx"], Ry=p["Ry"], k1=p["k1"], k2=p["k2"], kb=p["kb"], ks=p["ks"], mu=p["mu"]
    )


def table_path(data_dir: Path | None = None) -> Path:
    """Where the creep-force table lies: under ``data_dir`` (the instance's copy of the
    vendored package), by default next to this module's package."""
    return Path(data_dir or PACKAGE_DIR) / GENERATED_DATA["halfspace"]


def _halfspace(cfg: ModelConfig, p: Mapping[str, Any], P: float, data_dir: Path | None) -> Any:
    spec = cfg.table_spec
    law = _TABLES.get(spec.key)
    if law is None:
        law = spec.load_law(table_path(data_dir))
        _TABLES[spec.key] = law
    return law.with_load(P).with_mu(p["mu"])


FACTORIES: dict[str, Callable[[ModelConfig, Mapping[str, Any], float, Path | None], Any]] = {
    "layer": _layer,
    "halfspace": _halfspace,
}


def make_law(
    cfg: ModelConfig, params: Mapping[str, Any], P: float, data_dir: Path | None = None
) -> Any:
    """The contact law of ``cfg`` (a ContactLaw) under normal load P (N); generated data
    (the half-space law's table) is read under ``data_dir``."""
    return FACTORIES[cfg.contact_law](cfg, params, P, data_dir)
