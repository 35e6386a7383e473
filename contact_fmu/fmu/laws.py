"""Contact laws by scene name, built from FMU parameters (SI).

Imports are lazy so that a built FMU carries only the law it uses; the module of each
law is listed in ``config.LAW_MODULES`` for the build.

The half-space law reads the creep-force table that the build generated and shipped in
the FMU's resources (``config.GENERATED_DATA``, relative to the vendored package this
module belongs to): each FMU reads its own table, never one of the source tree or of
the build cache. The table is loaded once per FMU and process and shared by its
instances (the law objects are immutable).
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


def _layer(cfg: ModelConfig, p: Mapping[str, Any], P: float) -> Any:
    layer = importlib.import_module(f"..{LAW_MODULES['layer']}", __package__)
    return layer.LayerContact(
        P=P, Rx=p["Rx"], Ry=p["Ry"], k1=p["k1"], k2=p["k2"], kb=p["kb"], ks=p["ks"], mu=p["mu"]
    )


def table_path() -> Path:
    """Where this FMU's creep-force table lies: in its own resources."""
    return PACKAGE_DIR / GENERATED_DATA["halfspace"]


def _halfspace(cfg: ModelConfig, p: Mapping[str, Any], P: float) -> Any:
    spec = cfg.table_spec
    law = _TABLES.get(spec.key)
    if law is None:
        law = spec.load_law(table_path())
        _TABLES[spec.key] = law
    return law.with_load(P).with_mu(p["mu"])


FACTORIES: dict[str, Callable[[ModelConfig, Mapping[str, Any], float], Any]] = {
    "layer": _layer,
    "halfspace": _halfspace,
}


def make_law(cfg: ModelConfig, params: Mapping[str, Any], P: float) -> Any:
    """The contact law of ``cfg`` (a ContactLaw) under normal load P (N)."""
    return FACTORIES[cfg.contact_law](cfg, params, P)
