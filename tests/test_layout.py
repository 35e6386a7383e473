"""The package's layers (docs/develop/architecture.md), read from the imports of every module.

Each module of contact_fmu (and the build, fmu_build) belongs to a package, and each
package to a layer; an import goes down or sideways, never up: the numerics (the laws,
the rolling body, the half-space theory) know nothing of the FMU, the build or the
applications, and the FMU's models nothing of the scenes that use them. The numerics
import only the standard library, numpy and scipy (matplotlib inside the functions that
plot, on demand), and the C core's loader (contact_fmu/native, which falls back to
Python where nothing is compiled); only the adapter fmu/slave.py imports pythonfmu.
The imports are read with ``ast`` from the sources, every import statement wherever it
stands (a function's own import counts), so the test needs nothing importable.
"""

from __future__ import annotations

import ast
import importlib
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "contact_fmu"

# package -> layer (0 the lowest); "" is contact_fmu/__init__.py, the public names
LAYERS = {
    "_validate": 0,
    "_moved": 0,
    "native": 0,
    "laws": 1,
    "dynamics": 2,
    "halfspace": 3,
    "examples": 3,
    "": 3,
    "fmu": 4,
    "scenario": 5,
    "fmu_build": 6,
    "study": 7,
    "report": 7,
    "figures": 7,
    "cli": 7,
}
NUMERICS = {p for p, layer in LAYERS.items() if layer <= 3}
THIRD_PARTY_NUMERICS = {"numpy", "scipy"}
ON_DEMAND = {"matplotlib"}  # imported inside the functions that plot
# Maintainer-time generators of committed C headers: they read a higher layer's tables
# (message_header: fmu/messages.py, to write native/cf_messages.h) when the header is
# written, never when the package runs; their own command imports them, nothing else does
# (test_generators_are_imported_by_their_command_only).
GENERATORS = {"contact_fmu.native.message_header"}
GENERATOR_COMMAND = "contact_fmu.native.abi_header"


def _modules() -> dict[str, Path]:
    """Dotted name -> file of every module of contact_fmu and fmu_build."""
    out = {}
    for top in ("contact_fmu", "fmu_build"):
        for path in sorted((ROOT / top).rglob("*.py")):
            parts = list(path.relative_to(ROOT).with_suffix("").parts)
            if parts[-1] == "__init__":
                parts = parts[:-1]
            out[".".join(parts)] = path
    return out


MODULES = _modules()


def _package(module: str) -> str:
    """The package of a dotted module name: its first part below contact_fmu."""
    parts = module.split(".")
    if parts[0] == "fmu_build":
        return "fmu_build"
    return parts[1] if len(parts) > 1 else ""


def _imports(module: str) -> list[tuple[str, bool]]:
    """(imported module, at module level) for each import of ``module``: package-relative
    imports resolved; ``from pkg import name`` gives pkg.name where that is a module."""
    path = MODULES[module]
    is_package = path.name == "__init__.py"
    tree = ast.parse(path.read_text(), filename=str(path))
    nested = {
        id(n)
        for f in ast.walk(tree)
        if isinstance(f, ast.FunctionDef | ast.AsyncFunctionDef)
        for n in ast.walk(f)
    }
    out = []
    for node in ast.walk(tree):
        top = id(node) not in nested
        if isinstance(node, ast.Import):
            out += [(a.name, top) for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = module.split(".")
                if not is_package:
                    base = base[:-1]
                base = base[: len(base) - (node.level - 1)]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            for a in node.names:
                sub = f"{target}.{a.name}"
                out.append((sub if sub in MODULES else target, top))
    return out


def _edges() -> set[tuple[str, str, str]]:
    """(package, imported package, importing module) over contact_fmu and fmu_build."""
    edges = set()
    for module in MODULES:
        if module in GENERATORS:
            continue
        for target, _ in _imports(module):
            if target.split(".")[0] in ("contact_fmu", "fmu_build"):
                a, b = _package(module), _package(target)
                if a != b:
                    edges.add((a, b, module))
    return edges


def test_generators_are_imported_by_their_command_only():
    """A generator's upward import stays out of the running package: only the header
    command imports it (and nothing imports that command)."""
    users = sorted((m, t) for m in MODULES for t, _ in _imports(m)
                   if t in GENERATORS | {GENERATOR_COMMAND})  # fmt: skip
    assert users == [(GENERATOR_COMMAND, g) for g in sorted(GENERATORS)]


def test_every_package_has_a_layer():
    assert {_package(m) for m in MODULES} == set(LAYERS)


def test_no_import_goes_up_a_layer():
    """numerics < FMU models < scenes < build < applications: an import from a lower
    layer to a higher one would make the numerics depend on what is built on them."""
    up = sorted(f"{m} imports {b} (layer {LAYERS[b]} > {LAYERS[a]})"
                for a, b, m in _edges() if LAYERS[b] > LAYERS[a])  # fmt: skip
    assert up == []


def test_packages_import_each_other_without_a_cycle():
    """The package graph is acyclic (within one layer too): each package can be read,
    tested and vendored with only those below it."""
    graph: dict[str, set[str]] = {p: set() for p in LAYERS}
    for a, b, _ in _edges():
        graph[a].add(b)
    state: dict[str, int] = {}  # 1 on the path, 2 done
    cycles = []

    def visit(p: str, path: list[str]) -> None:
        state[p] = 1
        for q in sorted(graph[p]):
            if state.get(q) == 1:
                cycles.append(" -> ".join(path[path.index(q) :] + [p, q]) if q in path else q)
            elif q not in state:
                visit(q, path + [p])
        state[p] = 2

    for p in sorted(graph):
        if p not in state:
            visit(p, [])
    assert cycles == []


def test_numerics_import_only_numpy_scipy_and_the_standard_library():
    found = []
    for module in MODULES:
        if _package(module) not in NUMERICS or module.startswith("fmu_build"):
            continue
        for target, top in _imports(module):
            root = target.split(".")[0]
            if root == "contact_fmu" or root in sys.stdlib_module_names or root == "":
                continue
            if root in THIRD_PARTY_NUMERICS or (root in ON_DEMAND and not top):
                continue
            found.append(f"{module}: {target}" + ("" if top else " (in a function)"))
    assert found == []


def test_only_the_adapter_imports_pythonfmu():
    users = sorted({m for m in MODULES for t, _ in _imports(m) if t.split(".")[0] == "pythonfmu"})
    assert users == ["contact_fmu.fmu.slave"]


def test_the_ast_reading_sees_the_known_imports():
    """The reader itself: relative imports resolved, ``from . import module`` as the
    module, a function's import marked as such (matplotlib in halfspace/plotting.py)."""
    integrator = dict(_imports("contact_fmu.dynamics.integrator"))
    assert integrator["contact_fmu.native"] is True
    assert integrator["contact_fmu.dynamics.solvers"] is True
    assert integrator["contact_fmu.laws.protocol"] is True
    assert ("matplotlib.pyplot", False) in _imports("contact_fmu.halfspace.plotting")
    assert ("contact_fmu", "contact_fmu.dynamics", "fmu_build.system") not in _edges()
    assert ("fmu_build", "dynamics", "fmu_build.system") in _edges()


OLD_PATHS = ["contact_fmu.layer", "contact_fmu.integrator", "contact_fmu.transient",
             "contact_fmu.simulate"]  # fmt: skip


@pytest.mark.parametrize("old", OLD_PATHS)
def test_an_old_module_path_gives_the_moved_module_with_a_deprecation_warning(old):
    """The flat layout's paths keep working for one release (contact_fmu/_moved.py):
    the same module object, and a DeprecationWarning naming the new path."""
    import contact_fmu
    from contact_fmu import _moved

    new = importlib.import_module(_moved.MOVED[old])
    sys.modules.pop(old, None)
    with pytest.warns(DeprecationWarning, match=rf"{old} moved to {_moved.MOVED[old]}"):
        module = importlib.import_module(old)
    assert module is new
    assert module.__spec__.name == _moved.MOVED[old]  # its own spec, not the old path's
    assert callable(contact_fmu.simulate)  # the function, not the module of the old path
    sys.modules.pop(old, None)
