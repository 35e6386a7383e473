"""The native FMU: FMI 2.0 co-simulation in compiled C only (``python -m fmu_build --native``).

The binary is built from the C files of contact_fmu/native, each its own translation
unit (SOURCES): fmi2.c (the FMI 2.0 front end: arguments and statuses), instance.c (the
version-neutral instance layer: phases, checks, step admission, messages, FMU states),
model.c (the contact outputs, the rigid-body step, the analytic Jacobian) and stepper.c
(the kernel), with their headers instance.h, model.h, stepper.h, cf_abi.h (the structs
and the Python numerics' constants the C code shares with Python, generated from
contact_fmu/native/abi.py and committed), cf_core.h (the checks of a value and of a
doStep call, shared with the pythonfmu FMU's binding fmi.c) and a header generated here,
cf_model.h: the FMU's variables from ``contact_fmu.fmu.variables`` (names, kinds,
starts, ranges and the requirement texts of their check messages) and its GUID, so that
each lives once. The model description is written like the pythonfmu FMU's and completed by
the same ``model_description.patch`` (units, ranges, starts, ModelStructure); it lists the
C files (``<SourceFiles>``) that the FMU carries under ``sources/``, so that fmpy's
build (or any importer's) compiles it on Windows or macOS: every .c file into one shared
library, linked with libm (with fmpy's cmake: ``CMAKE_C_STANDARD_LIBRARIES=-lm``, which
it does not link by itself; docs/fmu.md); the sources export the fmi2* functions only,
without -fvisibility=hidden. The FMI headers are fmpy's (``fmpy/c-code``), found at
build time and not carried in this repository.

What the C kernel covers: the body mode on the thin-layer law, Lobatto IIIC and SDIRK2
(the String parameter ``scheme`` where the FMU offers both), methods "full" and
"quasistationary", vy zero, held at a ratio or from Eq. (10), Omega_z zero, held at a
ratio (vx the only stage unknown: CF_HELD_SPIN, the scalar step on the vector path's
state and spin grid) or from Eq. (11) (the scenes fig13, brake, fig12, railway,
cornering; ``--full body``); the
half-space creep-force table, body and contact mode (rail_traction, rail_creep; the table
travels as resources/table.bin: each load node's patches and, with several nodes, the
spline of their weights in log P, blended in C at the load as CreepTable._coefficients_at
does; with layers a load outside the nodes refused in TableLaw's words; at most
LOADS_MAX nodes); the contact mode on the thin-layer
law, with a spin input Omega_z too (sweep, ``--full contact``: the strip march on the
law's spin grid, built in C for each load, with its forward-mode derivative for the
directional derivatives); the rigid_body mode (``--full rigid_body``); the body on the
transient traction field (phase "transient": fig12_transient; vx the stage unknown, Vy
and Omega_z held at ratios or unknowns too by Eqs. 10-11, field.c's Newton iteration
with the field's Jacobian, its evaluations counted against max_work as the pythonfmu
FMU counts them; field.c's cf_field_advance, the field of the scene's nx x ny in the
instance's core, at most FIELD_CELLS_MAX cells; the field file written in C). Everything
else is refused here with a message that names the scene's feature
(``NativeUnsupportedError``); there is no silent fallback to the pythonfmu FMU.
"""

from __future__ import annotations

import hashlib
import importlib.util
import json
import math
import os
import re
import shutil
import subprocess
import tempfile
import uuid
import xml.etree.ElementTree as ET
import zipfile
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from contact_fmu import native
from contact_fmu.dynamics import integrator
from contact_fmu.fmu import body_model
from contact_fmu.fmu import variables as fv
from contact_fmu.fmu.config import ModelConfig
from contact_fmu.laws import thin_layer as layer
from fmu_build import model_description3

from . import CACHE, documentation, model_description, publish, write_archive
from . import identifier as model_identifier

FORMAT = "contact_fmu-native-fmu-1"
NATIVE_DIR = Path(native.__file__).resolve().parent
# the FMU's C files: each .c its own translation unit (listed in <SourceFiles>), the
# headers they include; with HEADER (generated) they are the FMU's sources/
# CORE: what every front end is linked with (the FMI 3.0 FMU's: native_fmu3.SOURCES)
FRONT_END = "fmi2.c"
CORE = ("instance.c", "model.c", "stepper.c", "field.c", "instance.h", "model.h", "stepper.h",
        "field.h", "cf_abi.h", "cf_core.h", "cf_messages.h")  # fmt: skip
SOURCES = (FRONT_END, *CORE)
HEADER = "cf_model.h"
# no -fvisibility=hidden: the sources hide what is not fmi2* themselves (stepper.h)
CFLAGS = (*native.CFLAGS, "-std=c11", "-D_DEFAULT_SOURCE")
PLATFORM = "linux64"
# the most load nodes of a creep-force table the C code blends (stepper.h, CF_LOADS_MAX)
LOADS_MAX = int(
    re.search(r"#define CF_LOADS_MAX (\d+)", (NATIVE_DIR / "stepper.h").read_text()).group(1)
)


class NativeUnsupportedError(ValueError):
    """The scene's model has a feature the C kernel does not cover (named in the text)."""


@dataclass(frozen=True)
class NativeBuilt:
    """A native FMU: its content-keyed file (``path``), the user's stable copy
    (``stable``, <out>/<name>_native.fmu, the latest build), GUID and identifier (the
    scene's name and _native: stable across rebuilds)."""

    path: Path
    key: str
    guid: str
    identifier: str
    cached: bool
    stable: Path


def unsupported(cfg: ModelConfig) -> str | None:
    """Why the native FMU cannot carry ``cfg``'s model, or None."""
    if cfg.mode == "rigid_body":
        return None  # Eqs. (8)-(9) alone: no law
    if cfg.has_table and len(cfg.table_spec.loads) > LOADS_MAX:
        return (
            f"[halfspace] loads = {list(cfg.table_spec.loads)} (more than {LOADS_MAX} load "
            "nodes: stepper.h's CF_LOADS_MAX)"
        )
    if cfg.transient:
        nx, ny = field_grid(cfg)
        if nx * ny > FIELD_CELLS_MAX:
            return (
                f'phase = "transient" on a {nx} x {ny} field (the native FMU holds the field '
                f"in its FMU state, copied whole: at most {FIELD_CELLS_MAX} cells)"
            )
        return None
    return None


def held_spin(cfg: ModelConfig) -> bool:
    """The body mode with a held spin ratio and vx the only stage unknown (vy zero or held):
    RollingBody's scalar path with spin, on the native FMU's vector path (CF_HELD_SPIN)."""
    return cfg.mode == "body" and cfg.spin == "ratio" and cfg.vy != "eq10"


# The largest field (nx ny cells) the native FMU carries: its state holds the field and
# the field file's captures (17 bytes a cell each, 9 times: 153 bytes a cell) and is
# copied whole (get/set state, serialisation): 2048 cells (the default 64 x 32) are 313
# kB.
FIELD_CELLS_MAX = 2048


def field_grid(cfg: ModelConfig) -> tuple[int, int]:
    """(nx, ny) of a transient scene's field: the build's, fixed in the native FMU."""
    return int(cfg.start(fv.BY_NAME["nx"])), int(cfg.start(fv.BY_NAME["ny"]))


def _fixed(cfg: ModelConfig) -> dict[str, tuple[float, str]]:
    """The values a native build fixes, with the requirement its check words: the
    table's (ModelConfig.fixed) and a transient scene's grid (its field's size is
    compiled into the instance's state)."""
    out = {name: (value, cfg.check(name, math.nextafter(value, math.inf)))
           for name, value in cfg.fixed.items()}  # fmt: skip
    if cfg.transient:
        for name, n in zip(("nx", "ny"), field_grid(cfg), strict=True):
            out[name] = (float(n), f"{n}, the field size this native FMU is compiled for")
    return out


def fix_grid(xml: bytes, cfg: ModelConfig) -> bytes:
    """A transient scene's model description (FMI 2.0's or 3.0's) with the Integer
    parameters nx and ny declared min = max = the grid compiled into the native FMU (the
    pythonfmu FMU's range is 4 to 1024 and 2 to 512); others unchanged."""
    if not cfg.transient:
        return xml
    text = xml.decode()
    for name, n in zip(("nx", "ny"), field_grid(cfg), strict=True):
        element = (rf'(<ScalarVariable name="{name}"[^>]*>\s*<Integer [^>]*?'
                   rf'|<Int32 name="{name}"[^>]*?)')  # fmt: skip
        text, count = re.subn(element + r'min="[^"]*" max="[^"]*"', rf'\g<1>min="{n}" max="{n}"',
                              text)  # fmt: skip
        if count != 1:
            raise NativeUnsupportedError(f"no range of {name} in the model description")
    return text.encode()


def _c(x: float) -> str:
    """A double as a C literal that reads back to the same double."""
    r = repr(float(x))
    if r in ("inf", "-inf"):
        return "(-INFINITY)" if r[0] == "-" else "INFINITY"
    if "." not in r and "e" not in r:
        r += ".0"
    return r


def _cstr(s: str) -> str:
    return json.dumps(s)  # a C string literal for the ASCII texts used here


_ROLES = {
    "mu", "Rx", "Ry", "k1", "k2", "kb", "ks", "M", "Iy", "vy_ratio", "Vx0", "vx0",
    "h_max", "method", "P", "Fx_ex", "My_ex", "Vx", "Vy", "Omega_y", "Omega_z", "Tx",
    "Iz", "Vy0", "Omega_z0", "spin_ratio", "Fy_ex", "Mz_ex", "scheme", "max_work",
    "nx", "ny", "cells_per_step", "field_file", "field_times",
}  # fmt: skip
# phase "transient"'s outputs after cf_body.out's (model.h: O_SLIP_CX ...)
FIELD_OUTPUTS = ("slip_centroid_x", "slip_centroid_y", "tau_peak")
_MODES = {"body": "MODE_BODY", "contact": "MODE_CONTACT", "rigid_body": "MODE_RIGID"}


def _role(cfg: ModelConfig, v: fv.Var) -> str:
    if v.causality[cfg.mode] == fv.OUTPUT:
        if v.name in FIELD_OUTPUTS:
            return f"R_OUT + {len(native.OUTPUTS) + FIELD_OUTPUTS.index(v.name)}"
        return f"R_OUT + {native.OUTPUTS.index(v.name)}"
    if v.name not in _ROLES:
        raise NativeUnsupportedError(f"variable {v.name} (not read by the native FMU's model)")
    return "R_SLIP0" if v.name == "vx0" else "R_" + v.name.upper()  # vx0: not R_VX0


def header(cfg: ModelConfig, guid: str) -> str:
    """cf_model.h for ``cfg``: the variables in value-reference order, the GUID, the
    start method and scheme, the model parts it has (the constants the C code shares
    with Python are cf_abi.h's)."""
    kinds = {fv.PARAMETER: "K_PARAMETER", fv.INPUT: "K_INPUT", fv.OUTPUT: "K_OUTPUT"}
    types = {"Real": "T_REAL", "Integer": "T_INTEGER", "String": "T_STRING"}
    rows = []
    fixed = _fixed(cfg)
    for v in cfg.variables:
        lo, hi = v.bounds(cfg.mode)  # Var.check's range; a fixed value is checked after it
        fix, fix_req = 0.0, "NULL"
        if v.name in fixed:
            fix, text = fixed[v.name]
            fix_req = _cstr(text)
        # outputs start at their declared value before set-up (slave.py's _out)
        start = v.start if v.causality[cfg.mode] == fv.OUTPUT else cfg.start(v)
        lo_req = hi_req = "NULL"
        if lo is not None:  # Var.check's texts
            lo_req = _cstr(v.lower_requirement())
        if hi is not None:
            hi_req = _cstr(f"<= {hi:g}")
        rows.append(
            f"    {{{_cstr(v.name)}, {kinds[v.causality[cfg.mode]]}, {types[v.type]}, "
            f"{_role(cfg, v)}, {_c(0.0 if v.type == 'String' else float(start))}, "
            f"{_c(-float('inf') if lo is None else lo)}, {_c(float('inf') if hi is None else hi)}, "
            f"{int(v.open_min)}, {lo_req}, {hi_req}, {_c(fix)}, {fix_req}}},"
        )
    method = cfg.start(fv.BY_NAME["method"])
    scheme = cfg.start(fv.BY_NAME["scheme"])  # the scene's scheme where it offers one only
    lines = [
        "/* Generated by fmu_build/native_fmu.py from contact_fmu/fmu/variables.py. */",
        f"#define CF_GUID {_cstr(guid)}",
        f"#define CF_N_VARS {len(rows)}",
        f"#define CF_MODE {_MODES[cfg.mode]}",
        # the vector path (stepper.c, cf_advance_vector): Vy and/or Omega_z as unknowns
        f"#define CF_DYN_VY {int(cfg.mode == 'body' and cfg.vy == 'eq10')}",
        f"#define CF_DYN_SPIN {int(cfg.mode == 'body' and cfg.spin == 'eq11')}",
        # a held spin ratio with vx the only unknown: the scalar step on the vector
        # path's state, grid and outputs (stepper.c's advance_held)
        f"#define CF_HELD_SPIN {int(held_spin(cfg))}",
        "#define CF_VECTOR (CF_DYN_VY || CF_DYN_SPIN || CF_HELD_SPIN)",
        # the contact mode's spin input on the thin-layer law: the march on its grid
        "#define CF_CONTACT_SPIN "
        f"{int(cfg.mode == 'contact' and 'Omega_z' in cfg.inputs and not cfg.has_table)}",
        f"#define CF_SPIN_NX {layer.SPIN_GRID[0]}",
        f"#define CF_SPIN_NY {layer.SPIN_GRID[1]}",
        f"#define CF_TINY {_c(layer.TINY)}",
        f"#define CF_LINE_N {model_description3.LINE_N}",
        # phase "transient": the body on the traction field (field.c), its grid
        f"#define CF_TRANSIENT {int(cfg.transient)}",
        # the field's evaluations in the stage solves with Vy or Omega_z as unknowns
        f"#define CF_WORK_PER_CELL_EVAL {_c(body_model.WORK_PER_CELL_EVAL)}",
        *(
            f"#define CF_FIELD_{k} {n}"
            for k, n in zip(("NX", "NY"), field_grid(cfg) if cfg.transient else (1, 1), strict=True)
        ),  # fmt: skip
        *_table_header(cfg),
        f"#define CF_METHOD_START {('full', 'quasistationary').index(method)}",
        f"#define CF_SCHEME_START {integrator.SCHEMES.index(scheme)}",
        "static const cf_var CF_VARS[CF_N_VARS] = {",
        *rows,
        "};",
    ]
    return "\n".join(lines) + "\n"


_TABLE_LAWS: dict[str, object] = {}


def _table_law(cfg: ModelConfig):
    """The creep-force table of a half-space FMU, as the pythonfmu FMU loads it (kept per
    table key: the identity and the build read it)."""
    from contact_fmu.halfspace.table import TableData

    from . import tables

    key = tables.key(cfg)
    if key not in _TABLE_LAWS:
        _TABLE_LAWS[key] = cfg.table_spec.law(TableData.load(tables.ensure(cfg)))
    return _TABLE_LAWS[key]


def _table_header(cfg: ModelConfig) -> list[str]:
    """The table's constants: sizes (the doubles after the axes: CF_T_NCOEF; each load
    node's patches: CF_T_STRIDE), the load nodes and their spline's degree, the Hertz
    ellipse's geometry (eccentricity parameter m, kfac = (K - E)/m, hertz.Hertz._axes),
    the elastic constants, the onset of full slip of one node, the load range a table
    with layers admits (TableLaw.load_range, spec.LOAD_RTOL); CF_TABLE 0 without a
    table."""
    from contact_fmu.halfspace.spec import LOAD_RTOL
    from contact_fmu.halfspace.table import SATURATION_WIDTH

    lines = [f"#define CF_SAT_WIDTH {_c(SATURATION_WIDTH)}"]
    if not cfg.has_table:
        return (
            [*lines, "#define CF_TABLE 0"]
            + [
                f"#define CF_T_{n} 1"
                for n in ("N1", "N2", "N3", "NCOEF", "A_LE_B", "NLOADS", "STRIDE")
            ]  # fmt: skip
            + ["#define CF_T_SPLINE_K 0", "#define CF_T_LAYERED 0"]
            + [
                f"#define CF_T_{n} 1.0"
                for n in ("KFAC", "M", "AMIN", "ESTAR", "G", "ONSET", "P_LO", "P_HI", "LOAD_RTOL")
            ]  # fmt: skip
        )
    from scipy.special import ellipe, ellipk

    law = _table_law(cfg)
    d, h = law.data, law.hertz
    m = h.m
    kfac = math.pi / 4.0 if m == 0.0 else (ellipk(m) - ellipe(m)) / m  # hertz.Hertz._axes
    n1, n2, n3 = (len(a) for a in d.axes)
    lo, hi = law.load_range
    return [*lines, "#define CF_TABLE 1"] + [
        f"#define CF_T_N1 {n1}", f"#define CF_T_N2 {n2}", f"#define CF_T_N3 {n3}",
        f"#define CF_T_NCOEF {_table_data(law)[1].size}",
        f"#define CF_T_NLOADS {len(d.P)}", f"#define CF_T_STRIDE {d.patches[0].size}",
        f"#define CF_T_SPLINE_K {min(3, len(d.P) - 1)}",
        f"#define CF_T_KFAC {_c(float(kfac))}", f"#define CF_T_M {_c(m)}",
        f"#define CF_T_AMIN {_c(min(d.A, d.B))}", f"#define CF_T_A_LE_B {int(d.A <= d.B)}",
        f"#define CF_T_ESTAR {_c(d.Estar)}", f"#define CF_T_G {_c(d.G)}",
        f"#define CF_T_ONSET {_c(float(d.onset[0]))}",
        # TableLaw.__post_init__: with layers, P within [lo, hi] to LOAD_RTOL (or P = 0)
        f"#define CF_T_LAYERED {int(d.k > 0.0)}",
        f"#define CF_T_P_LO {_c(lo)}", f"#define CF_T_P_HI {_c(hi)}",
        f"#define CF_T_LOAD_RTOL {_c(LOAD_RTOL)}",
    ]  # fmt: skip


def _table_data(law):
    """The table's axes and the doubles after them (numpy arrays): each load node's
    patch coefficients in turn ((N1-1, N2-1, N3-1, 64, 4) each: CreepTable._coef_flat's
    layout), then with several nodes the spline of their weights (CreepTable._weights:
    log P of the first and last node, the knots and the n x n coefficients of
    make_interp_spline(log P_j, eye(n), min(3, n - 1))) and their onsets of full slip."""
    import numpy as np
    from scipy.interpolate import make_interp_spline

    d = law.data
    axes = [np.ascontiguousarray(a, float) for a in d.axes]
    parts = [np.ascontiguousarray(p, float).ravel() for p in d.patches]
    n = len(d.P)
    if n > 1:
        nodes = np.log(d.P)  # as CreepTable._weights
        spl = make_interp_spline(nodes, np.eye(n), k=min(3, n - 1))
        c = np.ascontiguousarray(spl.c, float)
        if c.shape != (n, n) or len(spl.t) != n + spl.k + 1:
            raise NativeUnsupportedError(f"a spline of {c.shape} coefficients for {n} nodes")
        parts += [np.array([nodes[0], nodes[-1]], float), np.asarray(spl.t, float), c.ravel(),
                  np.asarray(d.onset, float)]  # fmt: skip
    return axes, np.concatenate(parts)


def table_bytes(cfg: ModelConfig) -> bytes:
    """The table resource read by instance.c (load_table): magic, sizes, the axes and the
    doubles after them (_table_data: the nodes' patch coefficients, their spline), a
    CRC-32 (zlib's) of all before it (host byte order)."""
    import struct
    import zlib

    import numpy as np

    law = _table_law(cfg)
    axes, coef = _table_data(law)
    data = np.concatenate([*axes, coef])
    head = b"cfmuTBL1" + struct.pack("=3IQ", *(len(a) for a in axes), data.size)
    body = head + data.tobytes()
    return body + struct.pack("=Q", zlib.crc32(body))


def _skeleton(cfg: ModelConfig, identifier: str, guid: str) -> bytes:
    """A model description in pythonfmu's layout, for model_description.patch."""
    root = ET.Element(
        "fmiModelDescription",
        fmiVersion="2.0",
        modelName=identifier,
        guid=guid,
        generationTool="contact_fmu fmu_build --native",
        variableNamingConvention="structured",
        description=cfg.description or f"Spector & Batra (1995) contact, {cfg.mode} mode",
        author="contact_fmu",
        license="MIT",
    )
    cs = ET.SubElement(
        root,
        "CoSimulation",
        modelIdentifier=identifier,
        needsExecutionTool="false",
        canHandleVariableCommunicationStepSize="true",
        canInterpolateInputs="false",
        canBeInstantiatedOnlyOncePerProcess="false",
        canNotUseMemoryManagementFunctions="false",
        canGetAndSetFMUstate="true",
        canSerializeFMUstate="true",
        # the contact mode's force element, for masters that couple implicitly
        providesDirectionalDerivative="true" if cfg.mode == "contact" else "false",
    )
    files = ET.SubElement(cs, "SourceFiles")
    for name in c_files():
        ET.SubElement(files, "File", name=name)
    cats = ET.SubElement(root, "LogCategories")
    for name, text in (
        ("logStatusWarning", "Log messages with fmi2Warning status."),
        ("logStatusDiscard", "Log messages with fmi2Discard status."),
        ("logStatusError", "Log messages with fmi2Error status."),
        ("logStatusFatal", "Log messages with fmi2Fatal status."),
        ("logAll", "Log all messages."),
    ):
        ET.SubElement(cats, "Category", name=name, description=text)
    if cfg.experiment is not None:
        start, stop, step = cfg.experiment
        ET.SubElement(
            root,
            "DefaultExperiment",
            startTime=repr(float(start)),
            stopTime=repr(float(stop)),
            stepSize=repr(float(step)),
        )
    mv = ET.SubElement(root, "ModelVariables")
    for vr, v in enumerate(cfg.variables):
        c = v.causality[cfg.mode]
        attrs = {"name": v.name, "valueReference": str(vr), "description": v.description}
        attrs["causality"] = c
        attrs["variability"] = fv.variability(v, cfg.mode)
        if c == fv.OUTPUT:
            attrs["initial"] = "calculated"
        sv = ET.SubElement(mv, "ScalarVariable", attrs)
        typed = ET.SubElement(sv, v.type)
        if c != fv.OUTPUT:
            typed.set("start", str(cfg.start(v)))
    ET.SubElement(root, "ModelStructure")
    return ET.tostring(root, encoding="UTF-8")


def fmi_headers() -> Path:
    """fmpy's copy of the FMI 2.0 headers (fmpy/c-code)."""
    spec = importlib.util.find_spec("fmpy")
    if spec is None or spec.origin is None:
        raise NativeUnsupportedError("fmpy is not installed: its FMI headers are needed")
    path = Path(spec.origin).parent / "c-code"
    if not (path / "fmi2Functions.h").is_file():
        raise NativeUnsupportedError(f"no fmi2Functions.h under {path}")
    return path


def identity(cfg: ModelConfig) -> str:
    """The content key: the configuration, the C sources, the variables' header, the
    creep-force table's key (its data travel as a resource: the header alone does not
    change with them) and this module; the GUID and the model identifier follow from it."""
    h = hashlib.sha256(FORMAT.encode())
    h.update(json.dumps(cfg.to_dict(), sort_keys=True).encode())
    if cfg.has_table:
        from . import tables

        h.update(tables.key(cfg).encode())
    h.update(header(cfg, "").encode())
    h.update(_skeleton(cfg, "", ""))
    for name in SOURCES:
        h.update((NATIVE_DIR / name).read_bytes())
    h.update(Path(__file__).read_bytes())
    h.update(Path(model_description.__file__).read_bytes())
    h.update(Path(documentation.__file__).read_bytes())
    for doc in documentation.sources(cfg):  # the licence, the scene's figure
        h.update(doc.read_bytes())
    h.update(" ".join(CFLAGS).encode())
    return h.hexdigest()


def c_files(sources: tuple[str, ...] = SOURCES) -> tuple[str, ...]:
    """The translation units among ``sources`` (compiled each on its own, linked together)."""
    return tuple(n for n in sources if n.endswith(".c"))


def compile_binary(
    src_dir: Path, target: Path, extra: tuple[str, ...] = (), sources: tuple[str, ...] = SOURCES
) -> Path:
    """The C files of ``sources`` in ``src_dir`` (with the headers and cf_model.h there)
    into the library ``target``, linked with libm; CalledProcessError with the compiler's
    output on failure."""
    cc = os.environ.get("CC", "cc")
    units = [str(src_dir / n) for n in c_files(sources)]
    cmd = [cc, *CFLAGS, *extra, f"-I{src_dir}", f"-I{fmi_headers()}", "-o", str(target),
           *units, "-lm"]  # fmt: skip
    subprocess.run(cmd, check=True, capture_output=True, text=True)
    return target


def build(cfg: ModelConfig, out_dir: str | Path, force: bool = False) -> NativeBuilt:
    """The native FMU of ``cfg`` under ``out_dir`` (built unless cached); NativeUnsupportedError
    naming the feature where the C kernel does not cover the model."""

    def described(identifier: str, guid: str) -> dict[str, bytes]:
        xml = fix_grid(model_description.patch(_skeleton(cfg, identifier, guid), cfg), cfg)
        return {"modelDescription.xml": xml,
                **documentation.files(cfg, identifier, target="native")}  # fmt: skip

    return assemble(cfg, out_dir, force, "native", identity, SOURCES, PLATFORM, described)


def assemble(
    cfg: ModelConfig,
    out_dir: str | Path,
    force: bool,
    suffix: str,
    identity_of: Callable[[ModelConfig], str],
    sources: tuple[str, ...],
    platform: str,
    described: Callable[[str, str], dict[str, bytes]],
) -> NativeBuilt:
    """A native FMU of either FMI version: <out>/<name>_<suffix>.fmu from ``sources`` (the
    front end and CORE) and the generated header, compiled for ``platform``, with the
    files ``described(identifier, guid)`` gives (model description, documentation); cached
    under its content key ``identity_of(cfg)``."""
    why = unsupported(cfg)
    if why is not None:
        raise NativeUnsupportedError(f"no native FMU for scene {cfg.name!r}: {why}")
    key = identity_of(cfg)
    guid = "{" + str(uuid.UUID(key[:32])) + "}"
    identifier = f"{model_identifier(cfg)}_{suffix}"
    out_dir = Path(out_dir).resolve()
    target = out_dir / CACHE / f"{cfg.name}-{suffix}-{key[:12]}.fmu"
    stable = out_dir / f"{identifier}.fmu"
    if target.is_file() and not force and zipfile.is_zipfile(target):
        publish(target, stable)
        return NativeBuilt(target, key, guid, identifier, True, stable)
    target.parent.mkdir(parents=True, exist_ok=True)
    work = Path(tempfile.mkdtemp(prefix=f".{suffix}-{cfg.name}-", dir=target.parent))
    try:
        src = work / "sources"
        src.mkdir()
        for name in sources:
            shutil.copyfile(NATIVE_DIR / name, src / name)
        (src / HEADER).write_text(header(cfg, guid))
        lib = compile_binary(src, work / f"{identifier}.so", sources=sources)
        files = {f"binaries/{platform}/{identifier}.so": lib.read_bytes()}
        for name in (*sources, HEADER):
            files[f"sources/{name}"] = (src / name).read_bytes()
        if cfg.has_table:
            files["resources/table.bin"] = table_bytes(cfg)
        files.update(described(identifier, guid))
        final = work / "final.fmu"
        write_archive(final, files)
        os.replace(final, target)
    finally:
        shutil.rmtree(work, ignore_errors=True)
    publish(target, stable)
    return NativeBuilt(target, key, guid, identifier, False, stable)
