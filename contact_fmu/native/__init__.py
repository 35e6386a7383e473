"""Compiled twin of the integrator's commonest path (stepper.c), loaded with ctypes.

``RollingBody`` hands a communication step to ``Kernel.advance`` when its path is
covered (Lobatto IIIC or SDIRK2, the thin-layer law or the half-space creep-force table,
vx the only stage unknown, vy held at a ratio to Vx, no spin, held loads). The kernel mirrors
the Python code expression by expression: for the thin-layer law without lateral slip
it gives the same doubles, otherwise the same to rounding (hypot, the table's patch
sums); it answers "not covered" (the Python path then takes the step) for what it
leaves out. ``VectorKernel`` does the same for either method with Vy and/or Omega_z
as stage unknowns (Eqs. 10-11; the law with spin), equal to the Python path to the
stage tolerance. See stepper.c. The same library holds the thin-layer law for arrays, spin
included (``cf_layer_forces``, ``cf_strip_march``: LayerContact.forces and
layer._Grid.march call them for rolling inputs when the library is there).

The body FMU's FMI calls themselves (doStep, setReal, getReal on the compiled step's
path) have a CPython extension, fmi.c (``fmi_module``), that the adapter puts in place
of its Python methods while the compiled step runs; it is built for the running
interpreter (its file name carries the extension suffix, so another Python finds none).
Its checks of a value and a doStep call are cf_core.h's, and its step stepper.c's
cf_body_step with the step's own checks: the same C as the native FMU's (instance.c).

Both libraries are looked for next to this file, where an FMU carries them (built by
fmu_build; a vendored copy uses only those). The package itself looks next in the
user's cache and otherwise compiles them there with the C compiler (``CC``, default
``cc``). Without a library, or with CONTACT_FMU_NATIVE=0, nothing changes but speed.
"""

from __future__ import annotations

import ctypes
import hashlib
import os
import shutil
import subprocess
import sys
import sysconfig
import tempfile
from functools import partial
from importlib.machinery import ExtensionFileLoader
from importlib.util import module_from_spec, spec_from_file_location
from pathlib import Path
from typing import Any

import numpy as np

from . import abi

SOURCE = Path(__file__).with_name("stepper.c")
HEADER = Path(__file__).with_name("stepper.h")  # its types and functions (the FMU's too)
ABI = abi.HEADER  # cf_abi.h, included by stepper.h: the structs and constants shared here
# The transient field (field.c, field.h: its stage, summary, the body's advance on it),
# built into the same library; its binding is native/field.py.
FIELD_SOURCES = (Path(__file__).with_name("field.c"), Path(__file__).with_name("field.h"))
# No contraction into fused multiply-adds, no fast math: the Python path's roundings.
# CF_GLIBC_COMPAT: the oldest glibc symbol versions of hypot and pow (stepper.h).
CFLAGS = ("-O2", "-fPIC", "-shared", "-ffp-contract=off", "-fno-fast-math", "-DCF_GLIBC_COMPAT")
# The kernel library exports the functions ctypes calls (stepper.h's CF_HIDDEN is empty
# with CF_KERNEL_EXPORT; the native FMU's library, built without it, exports fmi2* only).
KERNEL_FLAGS = (*CFLAGS, "-DCF_KERNEL_EXPORT")
OK = 0


# The structs the C code shares (stepper.h's, from cf_abi.h): their fields are declared
# once, in abi.py, which writes the C header too.
class Params(ctypes.Structure):
    """cf_params: the parameters of a step (the body, the law at its load, the path, the
    Python numerics' constants)."""

    _fields_ = abi.fields("cf_params")


class State(ctypes.Structure):
    """cf_state: the state of the scalar path (cf_advance)."""

    _fields_ = abi.fields("cf_state")


class VState(ctypes.Structure):
    """cf_vstate: the state of the vector path (cf_advance_vector)."""

    _fields_ = abi.fields("cf_vstate")


# RollingBody.outputs() keys in the order of cf_body.out
OUTPUTS = tuple(key for key, _, _ in abi.OUTPUTS)


class Strips(ctypes.Structure):
    """cf_strips: the grid of layer._Grid for the compiled strip march."""

    _fields_ = abi.fields("cf_strips")


class BodyIO(ctypes.Structure):
    """cf_body: a communication step of the body (its inputs, parameters, outputs)."""

    _fields_ = abi.fields("cf_body")


SOURCE_FMI = Path(__file__).with_name("fmi.c")
# the checks both front ends make (included by fmi.c, and by stepper.c through stepper.h)
CORE = Path(__file__).with_name("cf_core.h")
FMI_MODULE = "contact_fmu_fmi"  # its PyInit_ name


def _fmi_flags() -> tuple[str, ...]:
    return (*CFLAGS, f"-I{sysconfig.get_paths()['include']}")


def _key(source: Path) -> str:
    """The content key of a library built from ``source`` (and the headers stepper.h,
    cf_abi.h and cf_core.h) with KERNEL_FLAGS; OSError where a file is not there."""
    text = source.read_bytes() + CORE.read_bytes() + " ".join(KERNEL_FLAGS).encode()
    if source == SOURCE:
        text += HEADER.read_bytes() + ABI.read_bytes()
        text += b"".join(p.read_bytes() for p in FIELD_SOURCES)
    return hashlib.sha256(text).hexdigest()[:12]


def library_name() -> str:
    """File name of the library built from this stepper.c with KERNEL_FLAGS."""
    return f"_stepper_{_key(SOURCE)}.so"


def fmi_name() -> str:
    """File name of the extension built from fmi.c for this interpreter."""
    return f"_fmi_{_key(SOURCE_FMI)}{sysconfig.get_config_var('EXT_SUFFIX')}"


# Why a compiled part that was there could not be used (a file that does not load: a
# damaged copy, or one needing a newer C library than the host's); the FMU adapter logs
# them as warnings. Without its C source (an FMU that does not carry it) a part is
# simply absent: that is no problem to report.
PROBLEMS: list[str] = []


def compile_to(target: Path, source: Path = SOURCE, flags: tuple[str, ...] = KERNEL_FLAGS) -> Path:
    """Compile ``source`` into ``target`` (atomically); CalledProcessError/OSError on
    failure."""
    target.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(suffix=".so", dir=target.parent)
    os.close(fd)
    try:
        cc = os.environ.get("CC", "cc")
        extra = [str(FIELD_SOURCES[0])] if source == SOURCE else []  # the kernel: + field.c
        cmd = [cc, *flags, "-o", tmp, str(source), *extra, "-lm"]
        subprocess.run(cmd, check=True, capture_output=True)
        os.replace(tmp, target)
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)
    return target


def compile_fmi_to(target: Path) -> Path:
    """Compile fmi.c for the running interpreter into ``target``."""
    return compile_to(target, SOURCE_FMI, _fmi_flags())


def _cache_dir() -> Path:
    base = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(base) / "contact_fmu"


# A copy vendored into an FMU (package cfmu_<key>) writes nothing on the target machine.
VENDORED = __name__.split(".")[0] != "contact_fmu"
_LOADED: dict[str, Any] = {}


def _find(name_fn: Any, compile_fn: Any) -> Path | None:
    """The file ``name_fn()`` next to this one or in the cache, else compiled into the
    cache; None when disabled, not on Linux, or not to be had."""
    if os.environ.get("CONTACT_FMU_NATIVE", "1") == "0" or not sys.platform.startswith("linux"):
        return None
    try:
        name = name_fn()
    except OSError:  # its C source is not there (not carried by this FMU)
        return None
    places = (Path(__file__).with_name(name),) + (() if VENDORED else (_cache_dir() / name,))
    for path in places:
        if path.is_file():
            return path
    if VENDORED or shutil.which(os.environ.get("CC", "cc")) is None:
        return None
    try:
        return compile_fn(_cache_dir() / name)
    except (OSError, subprocess.CalledProcessError):
        return None


def library() -> Any:
    """The loaded kernel, or None (disabled, not on Linux, or no compiler)."""
    if "stepper" in _LOADED:
        return _LOADED["stepper"]
    path = _find(library_name, compile_to)
    lib = _LOADED["stepper"] = None if path is None else _load(path, ctypes.CDLL)
    if lib is None:
        return None
    lib.cf_advance.argtypes = [
        ctypes.POINTER(Params), ctypes.POINTER(State),
        ctypes.c_double, ctypes.c_double, ctypes.c_double, ctypes.c_int,
    ]  # fmt: skip
    lib.cf_advance.restype = ctypes.c_int
    lib.cf_body_step.argtypes = [ctypes.c_void_p, ctypes.c_void_p, ctypes.c_void_p, ctypes.c_double]
    lib.cf_body_step.restype = ctypes.c_int
    lib.cf_body_outputs.argtypes = [ctypes.c_void_p, ctypes.c_void_p, ctypes.c_void_p]
    lib.cf_body_outputs.restype = None
    lib.cf_strip_march.argtypes = [ctypes.POINTER(Strips), ctypes.c_int] + [ctypes.c_void_p] * 6
    lib.cf_strip_march.restype = None
    lib.cf_layer_forces.argtypes = [ctypes.POINTER(Params), ctypes.POINTER(Strips), ctypes.c_int]
    lib.cf_layer_forces.argtypes += [ctypes.c_void_p] * 5
    lib.cf_layer_forces.restype = None
    lib.cf_advance_vector.argtypes = [
        ctypes.POINTER(Params), ctypes.POINTER(VState), ctypes.c_double,
        ctypes.POINTER(ctypes.c_double * 4), ctypes.c_int,
    ]  # fmt: skip
    lib.cf_advance_vector.restype = ctypes.c_int
    return lib


def fmi_module() -> Any:
    """The loaded fmi.c extension, or None (as ``library``, or no Python headers)."""
    if "fmi" not in _LOADED:
        path = _find(fmi_name, compile_fmi_to)
        _LOADED["fmi"] = None if path is None else _load(path, _import_extension)
    return _LOADED["fmi"]


def _import_extension(path: str) -> Any:
    spec = spec_from_file_location(FMI_MODULE, path, loader=ExtensionFileLoader(FMI_MODULE, path))
    module = module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _load(path: Path, loader: Any) -> Any:
    """``loader(path)``, or None with the reason in PROBLEMS: a file that is there but
    does not load leaves that part to Python (same results, slower)."""
    try:
        return loader(str(path))
    except (ImportError, OSError) as e:
        PROBLEMS.append(f"{path.name} cannot be loaded ({e}): that part runs in Python")
        return None


class Kernel:
    """The compiled stepper for one RollingBody's covered path (see module docstring)."""

    def __init__(self, lib: Any, constants: dict[str, float], quasistationary: bool) -> None:
        self._lib = lib
        self._advance = lib.cf_advance
        self._constants = constants
        self._qs = int(quasistationary)
        self._law: Any = None
        self._params = Params()
        self._state = State()

    def params(self, rb: Any) -> Params:
        """The parameter block for rb's body and law (rebuilt when the law changes)."""
        body, law = rb.body, rb.law
        if law is not self._law:
            p = self._params
            for k, v in self._constants.items():
                setattr(p, k, v)
            p.M, p.Rx, p.A1, p.A2, p.m_slip = body.M, body.Rx, body.A1, body.A2, body.m_slip
            p.Iy = body.Iy
            for k, v in law.native_fields().items():  # the law's (arrays kept by the law)
                setattr(p, k, v)
            self._path(p, rb)
            self._law = law
        return self._params

    def _path(self, p: Params, rb: Any) -> None:
        """The fields of this kernel's path: the held lateral and spin ratios, the
        method, and with a held spin the thin-layer law's spin grid (the law keeps it)."""
        p.ry = rb.lateral.vy_ratio
        p.rz = rb.lateral.spin_ratio
        p.quasistationary = self._qs
        self._strips(p, rb)

    @staticmethod
    def _strips(p: Params, rb: Any) -> None:
        """The law's spin grid for stepper.c's march (none where the law has none, and at
        lift-off: P = 0, no grid, no law: the free step)."""
        strips = getattr(rb.law, "native_strips", None)
        lifted = getattr(rb.law, "lifted", False)
        p.strips = None if strips is None or lifted else ctypes.addressof(strips())

    def advance(self, rb: Any, h: float, loads: Any, n: int) -> bool:
        """Advance rb's state by h in n steps under held ``loads`` (dynamics.Loads);
        False (rb unchanged) where the Python path must take the step."""
        self.write(rb)
        s = ctypes.byref(self._state)
        if self._advance(ctypes.byref(self._params), s, h, loads.Fx_ex, loads.My_ex, n) != OK:
            return False
        self.read(rb)
        return True

    # ---- the state in the struct: for FastBody ------------------------------------------
    def write(self, rb: Any) -> None:
        """rb's state into the struct (and the parameters, if its law changed)."""
        s = self._state
        s.Vx, s.vx, s.t, s.dv = float(rb.y[0]), float(rb.y[1]), rb.t, rb._dv
        s.Tx, s.Ty, s.Mz = rb.out.Tx, rb.out.Ty, rb.out.Mz
        s.out_sliding, s.sliding = int(rb.out.sliding), int(rb.sliding)
        self.params(rb)

    def read(self, rb: Any) -> None:
        """The struct's state into rb."""
        s = self._state
        rb.y = rb._state(s.Vx, s.vx)
        rb.t, rb._dv, rb.sliding = s.t, s.dv, bool(s.sliding)
        rb.out = type(rb.out)(s.Tx, s.Ty, s.Mz, bool(s.out_sliding))


class VectorKernel(Kernel):
    """The compiled step with Vy and/or Omega_z as stage unknowns, either scheme and
    method (stepper.c, cf_advance_vector; integrator.RollingBody._lobatto_vector or
    _sdirk_vector and, for the quasistationary method, the algebraic stages and regime):
    the same Newton iteration, equal to the Python path's to the stage tolerance."""

    def __init__(self, lib: Any, constants: dict[str, float], quasistationary: bool) -> None:
        super().__init__(lib, constants, quasistationary)
        self._advance = lib.cf_advance_vector
        self._state = VState()
        self._loads = (ctypes.c_double * 4)()

    def _path(self, p: Params, rb: Any) -> None:
        """The held ratios (0 where a rate is a stage unknown), which are unknowns, Iz,
        and the thin-layer law's spin grid (the law keeps it)."""
        lateral = rb.lateral
        p.ry = lateral.vy_ratio if lateral.vy_ratio is not None else 0.0
        p.rz = lateral.spin_ratio if lateral.spin_ratio is not None else 0.0
        p.dyn_vy, p.dyn_spin = int(lateral.dynamic_vy), int(lateral.dynamic_spin)
        p.Iz = rb.body.Iz if rb.body.Iz is not None else 0.0
        p.quasistationary = self._qs
        self._strips(p, rb)

    def advance(self, rb: Any, h: float, loads: Any, n: int) -> bool:
        self.write(rb)
        self._loads[:] = (loads.Fx_ex, loads.Fy_ex, loads.My_ex, loads.Mz_ex)
        if self._advance(ctypes.byref(self._params), self._state, h, self._loads, n) != OK:
            return False
        self.read(rb)
        return True

    def write(self, rb: Any) -> None:
        s = self._state
        s.Vx, s.vx, s.Vy, s.Oz = rb.y.tolist()
        s.t, s.dv = rb.t, rb._dv
        s.Tx, s.Ty, s.Mz, s.out_sliding = rb.out.Tx, rb.out.Ty, rb.out.Mz, int(rb.out.sliding)
        s.sliding = int(rb.sliding)
        s.jac_valid = rb._jac is not None
        if rb._jac is not None:  # the kept Newton matrix (solvers.newton's memo)
            s.jac_h, J = rb._jac
            s.J[: J.size] = J.ravel().tolist()
        self.params(rb)

    def read(self, rb: Any) -> None:
        s = self._state
        rb.y = np.array([s.Vx, s.vx, s.Vy, s.Oz])
        rb.t, rb._dv, rb.sliding = s.t, s.dv, bool(s.sliding)
        rb.out = type(rb.out)(s.Tx, s.Ty, s.Mz, bool(s.out_sliding))
        # the Lobatto stages' matrix is 2n x 2n, the algebraic stage's n x n
        N = len(rb._idx) * (1 if s.jac_h == self._params.algebraic_key else 2)
        rb._jac = (s.jac_h, np.array(s.J[: N * N]).reshape(N, N)) if s.jac_valid else None


class FastBody:
    """A body-mode communication step in one C call (stepper.c, cf_body_step): inputs
    held, the internal steps of fmu/body_model.py, the stepper, the outputs and their
    finiteness, for the path the kernel covers. The state lives in the kernel's struct
    between ``pull`` (struct -> RollingBody, before anything in Python reads or steps
    it) and ``push`` (RollingBody -> struct, after Python changed it). ``io`` holds the
    inputs P, Fx_ex, My_ex (set by the caller) and ``out``, the outputs in the order of
    OUTPUTS."""

    def __init__(self, kernel: Kernel, rb: Any, h_max: float, constants: dict[str, float]):
        self._kernel, self._rb = kernel, rb
        self._step = kernel._lib.cf_body_step
        self._outputs = kernel._lib.cf_body_outputs
        self.io = BodyIO(h_max=h_max, **constants)
        # the three structs live as long as this object: their addresses once
        self._pointers = tuple(
            ctypes.addressof(x) for x in (kernel._params, kernel._state, self.io)
        )

    def push(self) -> None:
        """The RollingBody's state into the struct, and the outputs at it."""
        rb, io = self._rb, self.io
        self._kernel.write(rb)
        io.a2, io.p0 = rb.law.a2, rb.law.p0
        self._outputs(*self._pointers)

    def pull(self) -> None:
        """The struct's state into the RollingBody."""
        self._kernel.read(self._rb)

    # inputs the compiled step reads (Fy_ex, Mz_ex act only on lateral degrees of
    # freedom, which this path does not have)
    INPUTS = ("P", "Fx_ex", "My_ex")

    @staticmethod
    def index(name: str) -> int:
        """Position of the output ``name`` in ``io.out``."""
        return OUTPUTS.index(name)

    def step(self, h: float) -> bool:
        """One communication step of h (s) > 0; False (nothing changed) where Python
        must take it."""
        return self._step(*self._pointers, h) == OK

    def stepper(self) -> Any:
        """``step`` as one C call f(h) -> 0 (OK) or not, for the per-step caller."""
        return partial(self._step, *self._pointers)

    def bind_fmi(
        self, shared: Any, methods: tuple[Any, Any, Any], rtol: float, slots: list, outs: list
    ) -> Any:
        """An adapter's FMI calls on this step in C (fmi.c: do_step, set_real and get_real,
        falling back on ``methods``, the adapter's own), or None without the extension.
        shared: the adapter's CallState (fmu/call_state.py), which the calls read and
        write; slots: (vr, name, min, max, open min) of the Real inputs the adapter checks
        itself; outs: (vr, name) of the Real outputs read from ``io.out``."""
        fmi = fmi_module()
        if fmi is None:
            return None
        io = ctypes.addressof(self.io)
        rows = [
            (vr, n, lo, hi, o, io + getattr(BodyIO, n).offset if n in self.INPUTS else 0)
            for vr, n, lo, hi, o in slots
        ]
        step = ctypes.cast(self._step, ctypes.c_void_p).value
        out = io + BodyIO.out.offset
        idx = [(vr, self.index(n)) for vr, n in outs]
        return fmi.bind(shared, self, *methods, step, *self._pointers, out, rtol, rows, idx)
