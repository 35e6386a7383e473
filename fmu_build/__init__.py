"""Build FMUs from model configurations: ``python -m fmu_build`` (see __main__).

``build(cfg)`` packages one FMU with pythonfmu: the adapter of ``contact_fmu.fmu`` and
only the modules the configured model imports, vendored under a package name of the
FMU's own, a generated script whose module and class names are unique, and a completed
model description (units, ranges, ModelStructure). Builds are cached by content: the
configuration, every vendored source file, this package's own sources and the pythonfmu
version make a SHA-256 key, and an FMU whose key exists is not built again.

Data a law needs at run time and the build generates (the half-space law's creep-force
table) is made by the numerics layer in a subprocess and cached by content of its own
(``tables``); its key is part of the FMU's, and the file travels in the FMU's resources.

This package only packages: it runs pythonfmu's command line in a subprocess and never
imports pythonfmu itself.
"""

from __future__ import annotations

import hashlib
import json
import os
import shutil
import subprocess
import sys
import tempfile
import uuid
import zipfile
from dataclasses import dataclass
from importlib import metadata
from pathlib import Path

import fmpy

from contact_fmu import native
from contact_fmu.fmu.config import ModelConfig
from contact_fmu.native import core

from . import documentation, model_description, script, sources, tables

DEFAULT_OUT = Path("out") / "fmu"
# Under the output folder: the content-keyed builds, <name>-<key[:12]>.fmu. The user's
# file is <name>.fmu beside it, the latest build of that name (``Built.stable``).
CACHE = "cache"
# Zip entries: readable by everyone (an extracted FMU may be shared between users),
# written by a Unix system (so that unzip applies the modes), at a fixed date (the
# same content gives the same bytes).
FILE_MODE, DIR_MODE = 0o100644, 0o040755
ZIP_DATE = (1980, 1, 1, 0, 0, 0)
# The GUID of an FMU: derived from its content key (same model, same GUID).
GUID_NAMESPACE = uuid.UUID("6f1f7d2e-6a55-4c8e-9d0b-2b1f6c0a9e11")
# Bump when the layout of built FMUs changes without a change of the sources.
FORMAT = "contact_fmu-fmu-1"
HERE = Path(__file__).resolve().parent
# The FMU's Linux binary in front of pythonfmu's (FMI statuses, FMU states: see its
# header); pythonfmu's own goes to resources/ + INNER, where the shim loads it from.
SHIM = Path(native.__file__).resolve().parents[1] / "fmu" / "pythonfmu_shim.c"
INNER = "pythonfmu/linux64/libpythonfmu-export.so"
SHIM_FLAGS = (
    "-O2",
    "-fPIC",
    "-shared",
    "-fvisibility=hidden",
    f"-I{Path(fmpy.__file__).parent / 'c-code'}",  # the FMI 2.0 headers
)


class BuildError(RuntimeError):
    """pythonfmu failed to build an FMU; the message carries its output."""


@dataclass(frozen=True)
class Built:
    """A built FMU: its content-keyed file (``path``, never rewritten), the user's
    stable copy (``stable``, <out>/<name>.fmu: the latest build of that name), its
    identity and whether it came from the cache. The modelIdentifier and modelName
    are the scene's name (``identifier``); the module, class and package inside the
    resources carry the content key, so that FMUs of one name but different content
    never share Python modules in one process."""

    path: Path
    key: str
    module: str
    class_name: str
    package: str
    modules: tuple[str, ...]
    cached: bool
    stable: Path
    identifier: str
    guid: str


def roots(cfg: ModelConfig) -> list[str]:
    """The modules an FMU of ``cfg`` starts from (dotted, relative to contact_fmu)."""
    r = ["fmu.slave", cfg.model_module]
    if cfg.law_module:
        r.append(cfg.law_module)
    if carries_core(cfg):
        r.append("native.core")
    return r


def identity(cfg: ModelConfig) -> tuple[str, list[str]]:
    """(content key, vendored modules) of the FMU for ``cfg``."""
    modules = sources.closure(roots(cfg))
    h = hashlib.sha256()
    h.update(FORMAT.encode())
    h.update(metadata.version("pythonfmu").encode())
    h.update(json.dumps(cfg.to_dict(), sort_keys=True).encode())
    for rel, src in sources.files(modules, compiles(cfg)) + sources.data(cfg.data_files):
        h.update(rel.encode() + b"\0" + src.read_bytes() + b"\0")
    for rel in cfg.generated_files:  # the generated data's content key (no build needed)
        h.update(rel.encode() + b"\0" + tables.key(cfg).encode() + b"\0")
    # this package's modules that shape an FMU (not the command line, not the systems, not
    # the C importers' input)
    skip = ("__main__.py", "system.py", "c_importer.py")
    own_files = sorted(p for p in HERE.glob("*.py") if p.name not in skip)
    for own in own_files + [SHIM]:
        h.update(own.name.encode() + b"\0" + own.read_bytes() + b"\0")
    for doc in documentation.sources(cfg):  # the licence, the scene's figure
        h.update(doc.name.encode() + b"\0" + doc.read_bytes() + b"\0")
    if carries_core(cfg):  # the core's C files and its header's maker (native_fmu.py)
        from . import native_fmu

        for name in native_fmu.CORE:
            h.update(name.encode() + b"\0" + (native_fmu.NATIVE_DIR / name).read_bytes())
        h.update(Path(native_fmu.__file__).read_bytes() + Path(core.__file__).read_bytes())
    return h.hexdigest(), modules


def names(cfg: ModelConfig, key: str) -> tuple[str, str, str]:
    """(module, class, package) names, unique per content key."""
    short = key[:12]
    return (
        f"{cfg.name.lower()}_{short}",
        f"{cfg.name[0].upper()}{cfg.name[1:]}_{short}",
        f"cfmu_{short}",
    )


def identifier(cfg: ModelConfig) -> str:
    """modelIdentifier and modelName: the configuration's name, stable across rebuilds
    (the binaries are named after it: binaries/linux64/<identifier>.so)."""
    if not (cfg.name.isascii() and cfg.name.isidentifier()):
        raise BuildError(f"name {cfg.name!r} is not a C identifier (ASCII letters, digits, _)")
    return cfg.name


def guid(key: str) -> str:
    """The FMU's GUID from its content key: it changes when the model does, only then."""
    return str(uuid.uuid5(GUID_NAMESPACE, key))


def compiles(cfg: ModelConfig) -> bool:
    """Whether the FMU carries the compiled code of contact_fmu/native (and its C
    sources): body FMUs, whose stepper and FMI calls run in it, and contact FMUs of the
    thin-layer law with a spin input Omega_z, whose law marches its spin grid in it
    (LayerContact.forces: cf_layer_forces; its cost: docs/performance.md).
    A contact FMU without spin evaluates the law's closed forms for one float input in
    math (the loader's Python only), the half-space law's table runs in Python, and the
    rigid-body FMU has no law."""
    if cfg.mode == "body":
        return True
    return cfg.mode == "contact" and cfg.contact_law == "layer" and "Omega_z" in cfg.inputs


def carries_core(cfg: ModelConfig) -> bool:
    """Whether the FMU carries its model's C core (instance.c with model.c, stepper.c,
    field.c and the model's cf_model.h), to which the adapter delegates every FMI call
    (fmu/slave_core.py): every model the native FMU builds (``native_fmu.unsupported``)
    but the transient field, whose grid (the parameters nx, ny) the pythonfmu FMU lets
    the user set and the native core holds at the build's size. Linux only: the core is
    compiled here, for linux64."""
    from . import native_fmu  # it imports this package

    return (
        sys.platform.startswith("linux")
        and not cfg.transient
        and native_fmu.unsupported(cfg) is None
    )


def _compile_core(cfg: ModelConfig, dest: Path, fmu_guid: str) -> None:
    """The model's core (``core.LIBRARY``, its GUID in ``core.GUID_FILE``) and, for a
    creep-force table, the table resource it reads (``table.bin``) into ``dest`` (the
    vendored contact_fmu/native); left out, with a note, where it cannot be compiled
    (the FMU then runs the adapter's Python path: the same answers)."""
    from . import native_fmu

    work = Path(tempfile.mkdtemp(prefix=".core-", dir=dest))
    try:
        for name in native_fmu.CORE:
            shutil.copyfile(native_fmu.NATIVE_DIR / name, work / name)
        (work / native_fmu.HEADER).write_text(native_fmu.header(cfg, fmu_guid))
        native_fmu.compile_binary(work, dest / core.LIBRARY, core.FLAGS, native_fmu.CORE)
        (dest / core.GUID_FILE).write_text(fmu_guid)
        if cfg.has_table:
            (dest / core.TABLE).write_bytes(native_fmu.table_bytes(cfg))
    except (OSError, subprocess.CalledProcessError, native_fmu.NativeUnsupportedError) as e:
        for name in (core.LIBRARY, core.GUID_FILE, core.TABLE):
            (dest / name).unlink(missing_ok=True)
        print(f"fmu_build: C core left out ({e}): the adapter's Python path", file=sys.stderr)
    finally:
        shutil.rmtree(work, ignore_errors=True)


def _compile_native(dest: Path, fmi: bool) -> None:
    """The compiled stepper and, with ``fmi`` (a body FMU's calls), the FMI calls'
    extension (for this interpreter), next to their vendored sources (contact_fmu/native);
    what cannot be compiled (no C compiler, no Python headers) is left out and that part
    runs in Python (same results)."""
    parts = [("compiled stepper", native.library_name(), native.compile_to)]
    if fmi:
        parts.append(("FMI calls' extension", native.fmi_name(), native.compile_fmi_to))
    for what, name, compile_fn in parts:
        try:
            compile_fn(dest / name)
        except (OSError, subprocess.CalledProcessError) as e:
            print(f"fmu_build: {what} left out ({e}): runs in Python", file=sys.stderr)


def build(
    cfg: ModelConfig,
    out_dir: str | Path = DEFAULT_OUT,
    force: bool = False,
    table_cache: str | Path = tables.DEFAULT_CACHE,
) -> Built:
    """The FMU for ``cfg`` under ``out_dir`` (built unless cached); generated law data
    (creep-force tables) is taken from, or built into, ``table_cache``."""
    out_dir = Path(out_dir).resolve()
    key, modules = identity(cfg)
    module, class_name, package = names(cfg, key)
    ident = identifier(cfg)
    target = out_dir / CACHE / f"{cfg.name}-{key[:12]}.fmu"
    stable = out_dir / f"{ident}.fmu"
    info = Built(
        target, key, module, class_name, package, tuple(modules), True, stable, ident, guid(key)
    )
    if target.is_file() and not force and zipfile.is_zipfile(target):
        publish(target, stable)
        return info
    target.parent.mkdir(parents=True, exist_ok=True)
    work = Path(tempfile.mkdtemp(prefix=f".build-{cfg.name}-", dir=target.parent))
    try:
        stage = work / "stage"
        sources.vendor(modules, stage / package, cfg.data_files, compiles(cfg))
        if "native" in modules and compiles(cfg):
            _compile_native(stage / package / "native", fmi=cfg.mode == "body")
        if "native.core" in modules and carries_core(cfg):
            _compile_core(cfg, stage / package / "native", info.guid)
        for rel in cfg.generated_files:
            shutil.copyfile(tables.ensure(cfg, table_cache), stage / package / rel)
        script_file = stage / f"{module}.py"
        script_file.write_text(script.render(cfg, package, class_name))
        cmd = [
            sys.executable,
            "-m",
            "pythonfmu",
            "build",
            "-f",
            str(script_file),
            "-d",
            str(work / "dist"),
            str(stage / package),
            "--handle-state",
            "--serialize-state",
        ]
        env = dict(os.environ, PYTHONDONTWRITEBYTECODE="1")
        proc = subprocess.run(cmd, cwd=work, capture_output=True, text=True, env=env)
        raw = work / "dist" / f"{class_name}.fmu"
        if proc.returncode != 0 or not raw.is_file():
            raise BuildError(
                f"pythonfmu build of {cfg.name} failed ({proc.returncode}):\n"
                f"{proc.stdout}\n{proc.stderr}"
            )
        final = work / "final.fmu"
        _finish(raw, final, cfg, _compile_shim(work), ident, info.guid)
        os.replace(final, target)  # atomic: concurrent builds of one key are harmless
    finally:
        shutil.rmtree(work, ignore_errors=True)
    publish(target, stable)
    return Built(
        target, key, module, class_name, package, tuple(modules), False, stable, ident, info.guid
    )


def publish(target: Path, stable: Path) -> None:
    """``stable`` becomes the content of ``target``, atomically (a hard link, or a copy
    where links are not possible, renamed over it): a reader never sees a partial file."""
    tmp = stable.with_name(f".{stable.name}.{os.getpid()}.tmp")
    tmp.unlink(missing_ok=True)
    try:
        os.link(target, tmp)
    except OSError:
        shutil.copyfile(target, tmp)
    os.replace(tmp, stable)


def _compile_shim(work: Path) -> bytes | None:
    """The shim's Linux binary, or None (no C compiler: the FMU keeps pythonfmu's
    binary alone, whose statuses are OK, Discard from doStep and Fatal)."""
    try:
        return native.compile_to(work / "shim.so", SHIM, SHIM_FLAGS).read_bytes()
    except (OSError, subprocess.CalledProcessError) as e:
        print(
            f"fmu_build: FMI status shim left out ({e}): errors answer fmi2Fatal",
            file=sys.stderr,
        )
        return None


def _finish(
    raw: Path, final: Path, cfg: ModelConfig, shim: bytes | None, ident: str, guid: str
) -> None:
    """Copy pythonfmu's FMU with the completed model description (stable identifier,
    content GUID), compressed; the binaries named after the identifier, with the shim as
    the Linux binary and pythonfmu's under resources/; the documentation and icon
    added; every entry readable by everyone."""
    entries: dict[str, bytes] = {}
    with zipfile.ZipFile(raw) as zin:
        for item in zin.infolist():
            name = item.filename
            if "__pycache__" in name or name.endswith("/"):
                continue
            data = zin.read(name)
            if name == "modelDescription.xml":
                data = model_description.patch(data, cfg, model_identifier=ident, guid=guid)
            if name.startswith("binaries/"):  # pythonfmu names them after the class
                folder, file = name.rsplit("/", 1)
                name = f"{folder}/{ident}{Path(file).suffix}"
                if shim is not None and folder == "binaries/linux64":
                    entries[f"resources/{INNER}"] = data
                    data = shim
            entries[name] = data
    entries.update(documentation.files(cfg, ident))
    write_archive(final, entries)


def write_archive(final: Path, entries: dict[str, bytes]) -> None:
    """An FMU archive of ``entries`` (path -> content): an entry per folder (0755) and
    per file (0644), from a Unix system at a fixed date, compressed."""
    folders = sorted({n.rsplit("/", i)[0] for n in entries for i in range(1, n.count("/") + 1)})
    with zipfile.ZipFile(final, "w", zipfile.ZIP_DEFLATED) as zout:
        for folder in folders:
            info = zipfile.ZipInfo(folder + "/", ZIP_DATE)
            info.create_system = 3
            info.external_attr = (DIR_MODE << 16) | 0x10  # 0x10: MS-DOS directory flag
            zout.writestr(info, b"")
        for name in sorted(entries):
            info = zipfile.ZipInfo(name, ZIP_DATE)
            info.create_system = 3
            info.external_attr = FILE_MODE << 16
            info.compress_type = zipfile.ZIP_DEFLATED
            zout.writestr(info, entries[name])
