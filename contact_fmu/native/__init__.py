"""Compiled twin of the integrator's commonest path (stepper.c), loaded with ctypes.

``RollingBody`` hands a communication step to ``Kernel.advance`` when its path is
covered (Lobatto IIIC, the thin-layer law, vx the only stage unknown, vy held at a
ratio to Vx, no spin, held loads). The kernel mirrors the Python code expression by
expression: without lateral slip it gives the same doubles, with a held ratio the same
to rounding (hypot); it answers "not covered" (the Python path then takes the step)
for what it leaves out. See stepper.c.

The shared library is looked for next to this file, where an FMU carries it (built by
fmu_build; a vendored copy uses only that one). The package itself looks next in the
user's cache and otherwise compiles it there with the C compiler (``CC``, default
``cc``). Without a library, or with CONTACT_FMU_NATIVE=0, nothing changes but speed.
"""

from __future__ import annotations

import ctypes
import hashlib
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import Any

SOURCE = Path(__file__).with_name("stepper.c")
# No contraction into fused multiply-adds, no fast math: the Python path's roundings.
CFLAGS = ("-O2", "-fPIC", "-shared", "-ffp-contract=off", "-fno-fast-math")
OK = 0


class Params(ctypes.Structure):
    _fields_ = [
        (n, ctypes.c_double)
        for n in (
            "M", "Rx", "A1", "A2", "m_slip", "mu", "P", "a1", "creep_full_slip",
            "beta_per_creep", "ry", "v_standstill", "v_scale_floor", "z_algebraic",
            "capacity_margin", "solve_rtol", "expand", "beta_full_slip", "beta_series",
        )
    ] + [("max_newton", ctypes.c_int), ("quasistationary", ctypes.c_int)]  # fmt: skip


class State(ctypes.Structure):
    _fields_ = [(n, ctypes.c_double) for n in ("Vx", "vx", "t", "dv", "Tx", "Ty", "Mz")] + [
        ("out_sliding", ctypes.c_int),
        ("sliding", ctypes.c_int),
    ]


def library_name() -> str:
    """File name of the library built from this stepper.c with CFLAGS."""
    key = hashlib.sha256(SOURCE.read_bytes() + " ".join(CFLAGS).encode()).hexdigest()[:12]
    return f"_stepper_{key}.so"


def compile_to(target: Path) -> Path:
    """Compile stepper.c into ``target`` (atomically); CalledProcessError/OSError on failure."""
    target.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(suffix=".so", dir=target.parent)
    os.close(fd)
    try:
        cc = os.environ.get("CC", "cc")
        cmd = [cc, *CFLAGS, "-o", tmp, str(SOURCE), "-lm"]
        subprocess.run(cmd, check=True, capture_output=True)
        os.replace(tmp, target)
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)
    return target


def _cache_dir() -> Path:
    base = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(base) / "contact_fmu"


_LIB: Any = None
_TRIED = False
# A copy vendored into an FMU (package cfmu_<key>) writes nothing on the target machine.
VENDORED = __name__.split(".")[0] != "contact_fmu"


def library() -> Any:
    """The loaded kernel, or None (disabled, not on Linux, or no compiler)."""
    global _LIB, _TRIED
    if _TRIED:
        return _LIB
    _TRIED = True
    if os.environ.get("CONTACT_FMU_NATIVE", "1") == "0" or not sys.platform.startswith("linux"):
        return None
    name = library_name()
    places = (Path(__file__).with_name(name),) + (() if VENDORED else (_cache_dir() / name,))
    for path in places:
        if path.is_file():
            break
    else:
        if VENDORED or shutil.which(os.environ.get("CC", "cc")) is None:
            return None
        try:
            path = compile_to(_cache_dir() / name)
        except (OSError, subprocess.CalledProcessError):
            return None
    lib = ctypes.CDLL(str(path))
    lib.cf_advance.argtypes = [
        ctypes.POINTER(Params), ctypes.POINTER(State),
        ctypes.c_double, ctypes.c_double, ctypes.c_double, ctypes.c_int,
    ]  # fmt: skip
    lib.cf_advance.restype = ctypes.c_int
    _LIB = lib
    return lib


class Kernel:
    """The compiled stepper for one RollingBody's covered path (see module docstring)."""

    def __init__(self, lib: Any, constants: dict[str, float], quasistationary: bool) -> None:
        self._advance = lib.cf_advance
        self._constants = constants
        self._qs = int(quasistationary)
        self._law: Any = None
        self._params = Params()
        self._state = State()

    def params(self, rb: Any, body: Any, law: Any) -> Params:
        """The parameter block for this body and law (rebuilt when the law changes)."""
        if law is not self._law:
            p = self._params
            for k, v in self._constants.items():
                setattr(p, k, v)
            p.M, p.Rx, p.A1, p.A2, p.m_slip = body.M, body.Rx, body.A1, body.A2, body.m_slip
            p.mu, p.P, p.a1 = law.mu, law.P, law.a1
            p.creep_full_slip = law.creep_full_slip
            p.beta_per_creep = law._beta_per_creep
            p.ry = rb.lateral.vy_ratio
            p.quasistationary = self._qs
            self._law = law
        return self._params

    def advance(self, rb: Any, h: float, Fx_ex: float, My_ex: float, n: int) -> tuple | None:
        """Advance rb's state by h in n steps; the new (Vx, vx, t, dv, Tx, Ty, Mz,
        out_sliding, sliding), or None where the Python path must take the step."""
        s = self._state
        s.Vx, s.vx, s.t, s.dv = float(rb.y[0]), float(rb.y[1]), rb.t, rb._dv
        s.Tx, s.Ty, s.Mz = rb.out.Tx, rb.out.Ty, rb.out.Mz
        s.out_sliding, s.sliding = int(rb.out.sliding), int(rb.sliding)
        params = self.params(rb, rb.body, rb.law)
        if self._advance(ctypes.byref(params), ctypes.byref(s), h, Fx_ex, My_ex, n) != OK:
            return None
        return (s.Vx, s.vx, s.t, s.dv, s.Tx, s.Ty, s.Mz, bool(s.out_sliding), bool(s.sliding))
