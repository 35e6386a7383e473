"""The model parts an FMU carries: the modules of ``contact_fmu`` it imports, and no more.

Starting from the adapter, the configured model module and the contact law's module,
the closure under relative imports (``from .x import``, ``from ..x import``) is
collected with ``ast``; only those files are copied, into a package with a name of the
FMU's own so that FMUs loaded in one process never share a module.
"""

from __future__ import annotations

import ast
import shutil
from pathlib import Path

import contact_fmu

PACKAGE_DIR = Path(contact_fmu.__file__).resolve().parent
PACKAGE = "contact_fmu"


class SourceError(RuntimeError):
    """A module of the closure cannot be vendored (absolute import of the package)."""


def _module_file(dotted: str) -> Path:
    """contact_fmu-relative dotted name -> file ("fmu.slave" -> fmu/slave.py)."""
    base = PACKAGE_DIR.joinpath(*dotted.split("."))
    if base.with_suffix(".py").is_file():
        return base.with_suffix(".py")
    if (base / "__init__.py").is_file():
        return base / "__init__.py"
    raise SourceError(f"no module {PACKAGE}.{dotted}")


def _resolve(current: str, is_package: bool, level: int, name: str | None) -> str:
    parts = current.split(".") if current else []
    if not is_package:
        parts = parts[:-1]
    if level > 1:
        parts = parts[: len(parts) - (level - 1)]
    if name:
        parts += name.split(".")
    return ".".join(parts)


def _imports(dotted: str) -> set[str]:
    path = _module_file(dotted)
    tree = ast.parse(path.read_text(), filename=str(path))
    is_package = path.name == "__init__.py"
    found: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom):
            if node.level == 0:
                if node.module and node.module.split(".")[0] == PACKAGE:
                    raise SourceError(f"{path}: absolute import of {node.module}; use relative")
                continue
            target = _resolve(dotted, is_package, node.level, node.module)
            try:
                _module_file(target)
                found.add(target)
            except SourceError:
                pass
            for alias in node.names:  # from . import module
                sub = f"{target}.{alias.name}" if target else alias.name
                try:
                    _module_file(sub)
                    found.add(sub)
                except SourceError:
                    pass
        elif isinstance(node, ast.Import):
            for alias in node.names:
                if alias.name.split(".")[0] == PACKAGE:
                    raise SourceError(f"{path}: absolute import of {alias.name}; use relative")
    return found


def closure(roots: list[str]) -> list[str]:
    """Dotted names (relative to contact_fmu) of the roots and all they import.

    Importing a module of a subpackage runs the subpackage's __init__ first, so its
    __init__ and everything that imports are part of the closure too."""
    todo, seen = list(roots), set()
    while todo:
        m = todo.pop()
        if m in seen or m == "":
            continue
        seen.add(m)
        todo.extend(_imports(m))
        parts = m.split(".")[:-1]
        todo.extend(".".join(parts[: i + 1]) for i in range(len(parts)))
    return sorted(seen)


# Files other than Python a module reads next to itself, by module.
COMPANIONS = {
    "native": tuple(
        f"native/{n}"
        for n in ("stepper.c", "stepper.h", "cf_abi.h", "fmi.c", "cf_core.h", "field.c", "field.h")
    )
}


def files(modules: list[str], companions: bool = True) -> list[tuple[str, Path]]:
    """(path inside the vendored package, source file) for each module and, with
    ``companions``, the files it reads (the C sources of what the build compiles)."""
    out = []
    for m in modules:
        src = _module_file(m)
        rel = src.relative_to(PACKAGE_DIR).as_posix()
        out.append((rel, src))
        if companions:
            out += data(COMPANIONS.get(m, ()))
    return out


PACKAGE_INIT = '"""Parts of contact_fmu vendored into this FMU by fmu_build (do not edit)."""\n'


def data(paths: tuple[str, ...]) -> list[tuple[str, Path]]:
    """(path inside the vendored package, source file) for package-relative data files."""
    out = []
    for rel in paths:
        src = PACKAGE_DIR / rel
        if not src.is_file():
            raise SourceError(f"data file {PACKAGE}/{rel} does not exist")
        out.append((Path(rel).as_posix(), src))
    return out


def vendor(
    modules: list[str], dest: Path, data_files: tuple[str, ...] = (), companions: bool = True
) -> None:
    """Copy the modules (and data files; companions: see ``files``) into the package
    folder ``dest``."""
    dest.mkdir(parents=True)
    (dest / "__init__.py").write_text(PACKAGE_INIT)
    for rel, src in files(modules, companions) + data(data_files):
        if rel == "__init__.py":
            continue
        target = dest / rel
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(src, target)
