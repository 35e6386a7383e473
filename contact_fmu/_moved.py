"""The module paths of the flat layout before ``laws/`` and ``dynamics/``, for one release.

Importing one (``from contact_fmu.layer import LayerContact``) gives the module at its
new path, the same module object, with a DeprecationWarning naming the new path. The old
paths are served by an import hook rather than by files at the old places, so that the
moved files keep their history (a file at the old path would stop git from following
the rename). CHANGELOG.md has the table; the next release removes this module.
"""

from __future__ import annotations

import importlib
import importlib.abc
import importlib.util
import sys
import types
import warnings

# old path -> new path
MOVED = {
    "contact_fmu.law": "contact_fmu.laws.protocol",
    "contact_fmu.layer": "contact_fmu.laws.thin_layer",
    "contact_fmu.transient": "contact_fmu.dynamics.thin_layer_field",
    "contact_fmu.fmu.laws": "contact_fmu.fmu.factory",
    **{
        f"contact_fmu.{m}": f"contact_fmu.dynamics.{m}"
        for m in (
            "body_state",
            "coupling",
            "integrator",
            "kinematics",
            "simulate",
            "solvers",
            "transient_body",
        )
    },
}


def warn(old: str, stacklevel: int) -> None:
    warnings.warn(
        f"{old} moved to {MOVED[old]}; the old path goes in the next release",
        DeprecationWarning,
        stacklevel=stacklevel + 1,
    )


class _Finder(importlib.abc.MetaPathFinder, importlib.abc.Loader):
    """Finds the old paths; loads each as the module at its new path."""

    def find_spec(self, fullname: str, path=None, target=None):  # noqa: ANN001
        if fullname not in MOVED:
            return None
        return importlib.util.spec_from_loader(fullname, self)

    def __init__(self) -> None:
        self._specs: dict[str, object] = {}

    def create_module(self, spec) -> types.ModuleType:  # noqa: ANN001
        warn(spec.name, 2)  # the importer's frame (the import machinery's are skipped)
        module = importlib.import_module(MOVED[spec.name])
        self._specs[module.__name__] = module.__spec__
        return module

    def exec_module(self, module: types.ModuleType) -> None:
        # the import system gave the module the old path's spec: give it back its own
        module.__spec__ = self._specs[module.__name__]


def load(old: str) -> types.ModuleType:
    """The module of the old path ``old`` (imported there: warned once, by the caller)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        module = importlib.import_module(old)
    warn(old, 3)
    return module


def install() -> None:
    if not any(isinstance(f, _Finder) for f in sys.meta_path):
        sys.meta_path.append(_Finder())


class Package(types.ModuleType):
    """contact_fmu itself: ``contact_fmu.simulate`` stays the function when the old module
    path ``contact_fmu.simulate`` is imported (the import system would set the module
    there)."""

    def __setattr__(self, name: str, value: object) -> None:
        if name == "simulate" and isinstance(value, types.ModuleType):
            return
        super().__setattr__(name, value)
