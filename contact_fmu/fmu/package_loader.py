"""The vendored package of a pythonfmu FMU, imported and loaded from the instance's own
copy (``load_package``)."""

from __future__ import annotations

import importlib
import sys
from pathlib import Path

# This FMU's package (cfmu_<content hash> when built; contact_fmu in the source tree)
PACKAGE = __name__.split(".")[0]


def load_package(resources: str | Path | None) -> None:
    """Everything this FMU's vendored package holds, imported and loaded now, from this
    instance's own copy (``resources``/cfmu_<key>).

    The package's modules are shared by all instances of the FMU in a process and stay in
    sys.modules, but the folder they were first imported from belongs to one instance:
    fmpy (or any importer) deletes it when that instance is freed. A module imported
    later (the model at exitInitializationMode) or a compiled library looked for later
    (next to native/__init__.py) would be sought in a folder that may be gone. So at every
    instantiation the package's ``__path__`` points at the copy of the instance being
    made, which exists now, and every module of it is imported and the compiled libraries
    loaded: after that nothing is read from the package's folders but the instance's own
    data (``_data_dir``). An import that fails here (a host without scipy) is left to
    exitInitializationMode, which repeats it and answers fmi2Error with its message.
    Nothing to do outside an FMU (the source tree's contact_fmu)."""
    if not resources:
        return
    root = Path(resources) / PACKAGE
    if PACKAGE == "contact_fmu" or not root.is_dir():
        return
    prefix = PACKAGE + "."
    for name, module in list(sys.modules.items()):
        if (name == PACKAGE or name.startswith(prefix)) and hasattr(module, "__path__"):
            module.__path__[:] = [str(root.joinpath(*name.split(".")[1:]))]
    if _LOADED_FROM:
        return
    complete = True
    for file in sorted(root.rglob("*.py")):
        parts = file.relative_to(root).with_suffix("").parts
        if parts[-1] == "__init__":
            parts = parts[:-1]
        try:
            importlib.import_module(".".join((PACKAGE, *parts)))
            if parts == ("native",):  # looked for next to its file: in this copy, now
                native = sys.modules[prefix + "native"]
                native.library()
                native.fmi_module()
        except Exception:  # repeated, and reported, at exitInitializationMode
            complete = False
    if complete:
        _LOADED_FROM.append(str(root))


# the copy of this package from which all of it was imported and loaded (load_package)
_LOADED_FROM: list[str] = []
