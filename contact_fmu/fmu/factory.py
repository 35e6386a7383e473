"""From parameters to law and body: the one place where the FMU's parameters (SI, by the
names of fmu/variables.py) become a contact law, a Body, its Lateral constraint and its
initial state. The FMU's models (body_model.py, body_transient.py, contact_model.py,
rigid_body.py), the build's coupled systems (fmu_build/system.py), the scenes'
references (scenario/references.py) and the report's (report/reference.py) all build
through here, so that a reference integrates the model the FMU runs.

The laws' imports are lazy so that a built FMU carries only the law it uses; the module
of each law is listed in ``config.LAW_MODULES`` for the build.

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

from ..dynamics.body import Body, Lateral
from ..dynamics.kinematics import spin_for_slip
from .config import GENERATED_DATA, LAW_MODULES, ModelConfig

# The package this module was vendored into (contact_fmu in the source tree).
PACKAGE_DIR = Path(__file__).resolve().parent.parent
# Half-space tables loaded in this process: spec key -> TableLaw at its first load node.
_TABLES: dict[str, Any] = {}


def thin_layer_law(p: Mapping[str, Any], P: float) -> Any:
    """The thin-layer law (LayerContact, Eqs. 31-43) of the parameters p under the load P
    (N)."""
    layer = importlib.import_module(f"..{LAW_MODULES['layer']}", __package__)
    return layer.LayerContact(
        P=P, Rx=p["Rx"], Ry=p["Ry"], k1=p["k1"], k2=p["k2"], kb=p["kb"], ks=p["ks"], mu=p["mu"]
    )


def table_path(data_dir: Path | None = None) -> Path:
    """Where the creep-force table lies: under ``data_dir`` (the instance's copy of the
    vendored package), by default next to this module's package."""
    return Path(data_dir or PACKAGE_DIR) / GENERATED_DATA["halfspace"]


def _layer(cfg: ModelConfig, p: Mapping[str, Any], P: float, table: Path) -> Any:
    return thin_layer_law(p, P)


def _halfspace(cfg: ModelConfig, p: Mapping[str, Any], P: float, table: Path) -> Any:
    spec = cfg.table_spec
    law = _TABLES.get(spec.key)
    if law is None:
        law = spec.load_law(table)
        _TABLES[spec.key] = law
    return law.with_load(P).with_mu(p["mu"])


FACTORIES: dict[str, Callable[[ModelConfig, Mapping[str, Any], float, Path], Any]] = {
    "layer": _layer,
    "halfspace": _halfspace,
}


def make_law(
    cfg: ModelConfig,
    params: Mapping[str, Any],
    P: float,
    data_dir: Path | None = None,
    table: Path | None = None,
) -> Any:
    """The contact law of ``cfg`` (a ContactLaw) under normal load P (N); generated data
    (the half-space law's table) is read under ``data_dir``, or from the file ``table``
    (outside an FMU: the build's cache, fmu_build.tables.ensure)."""
    return FACTORIES[cfg.contact_law](cfg, params, P, table or table_path(data_dir))


def make_body(p: Mapping[str, Any]) -> Body:
    """The body (M, Rx, Iy and, for Eq. 11, Iz) of the parameters p."""
    return Body(M=p["M"], Rx=p["Rx"], Iy=p["Iy"], Iz=p.get("Iz"))


def make_lateral(cfg: ModelConfig, p: Mapping[str, Any]) -> Lateral:
    """The lateral motion of ``cfg``: vy and Omega_z held at zero, at a ratio of Vx (the
    parameters vy_ratio, spin_ratio), or free by Eqs. (10)-(11) (None)."""
    return Lateral(
        vy_ratio={"zero": 0.0, "ratio": p.get("vy_ratio"), "eq10": None}[cfg.vy],
        spin_ratio={"zero": 0.0, "ratio": p.get("spin_ratio"), "eq11": None}[cfg.spin],
    )


def initial_state(p: Mapping[str, Any]) -> dict[str, float]:
    """The steppers' initial conditions from the parameters: Vx0 (m/s), Omega_y0 (rad/s)
    for the initial slip vx0 = Vx0 - Omega_y0 Rx (Eq. 3), Vy0 (m/s), Omega_z0 (rad/s)."""
    return {
        "Vx0": p["Vx0"],
        "Omega_y0": spin_for_slip(p["Vx0"], p["vx0"], p["Rx"]),
        "Vy0": p.get("Vy0", 0.0),
        "Omega_z0": p.get("Omega_z0", 0.0),
    }
