"""Contact laws by scene name, built from FMU parameters (SI).

Imports are lazy so that a built FMU carries only the law it uses; the module of each
law is listed in ``config.LAW_MODULES`` for the build.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable, Mapping
from typing import Any

from .config import LAW_MODULES


def _layer(p: Mapping[str, Any], P: float) -> Any:
    layer = importlib.import_module(f"..{LAW_MODULES['layer']}", __package__)
    return layer.LayerContact(
        P=P, Rx=p["Rx"], Ry=p["Ry"], k1=p["k1"], k2=p["k2"], kb=p["kb"], ks=p["ks"], mu=p["mu"]
    )


FACTORIES: dict[str, Callable[[Mapping[str, Any], float], Any]] = {"layer": _layer}


def make_law(name: str, params: Mapping[str, Any], P: float) -> Any:
    """The contact law ``name`` (a ContactLaw of ``integrator``) under normal load P (N)."""
    return FACTORIES[name](params, P)
