"""ctypes binding of field.c: the thin-layer transient field in C.

``transient.LayerField`` hands a stage of its step (``LayerField.stage``: the
re-indexed lattice, the load of each material point, the radial return, the slip-aware
quadrature weights of ``LayerField._weights``, the resultant and its tangent), the
weights of a field at rest (``current``) and its ``summary`` to these functions, and
``TransientRollingBody.advance`` its whole advance when vx is its only stage unknown
and the loads are held (cf_field_advance: _step, _stage, _solve_scalar), when the
kernel library is there (native.library(): field.c is built into it with stepper.c).
The C follows the Python expression by expression and sums as numpy does (pairwise),
so it agrees with the Python path to rounding (numpy's own z**3 and hypot differ from
the C's by an ulp or so). A call that the C declines (a non-finite or out-of-range
input, a result that overflows, a stage without a root) is taken by the Python path,
which stays the reference and words any error: without the library, with
CONTACT_FMU_NATIVE=0, or with ``LayerField.native = False``, nothing changes but speed.
"""

from __future__ import annotations

import ctypes
from typing import Any

import numpy as np

from . import abi
from . import library as _kernel

OK = 0  # field.h: CF_FIELD_OK; anything else: the Python path takes the call

_D = ctypes.c_double
_P = ctypes.c_void_p


class Field(ctypes.Structure):
    """cf_abi.h's cf_field (declared in abi.py): the grid and law of a LayerField."""

    _fields_ = abi.fields("cf_field")


class StageIn(ctypes.Structure):
    """cf_abi.h's cf_field_stage_in (declared in abi.py): LayerField.stage's arguments."""

    _fields_ = abi.fields("cf_field_stage_in")


class StageOut(ctypes.Structure):
    """cf_abi.h's cf_field_stage_out (declared in abi.py): a StageField's arrays and numbers."""

    _fields_ = abi.fields("cf_field_stage_out")


class Body(ctypes.Structure):
    """cf_abi.h's cf_field_body (declared in abi.py): the body of the scalar path."""

    _fields_ = abi.fields("cf_field_body")


class BodyState(ctypes.Structure):
    """cf_abi.h's cf_field_body_state (declared in abi.py): the body's and field's state."""

    _fields_ = abi.fields("cf_field_body_state")


def library() -> Any:
    """The kernel library with field.c's functions typed, or None (no library, or one
    without them)."""
    lib = _kernel()
    if lib is None or not hasattr(lib, "cf_field_stage"):
        return None
    if lib.cf_field_stage.restype is not ctypes.c_int or lib.cf_field_stage.argtypes is None:
        lib.cf_field_stage.argtypes = [
            ctypes.POINTER(Field), ctypes.POINTER(StageIn), ctypes.POINTER(StageOut)
        ]  # fmt: skip
        lib.cf_field_stage.restype = ctypes.c_int
        lib.cf_field_weights.argtypes = [ctypes.POINTER(Field), _P, _P, _P, _P, _P, _D, _P, _P]
        lib.cf_field_weights.restype = ctypes.c_int
        lib.cf_field_resultant.argtypes = [ctypes.POINTER(Field), _P, _P, _P, _P, _P, _P]
        lib.cf_field_resultant.restype = ctypes.c_int
        lib.cf_field_advance.argtypes = [
            ctypes.POINTER(Field), ctypes.POINTER(Body), ctypes.POINTER(BodyState), _D, _P,
            ctypes.c_int,
        ]  # fmt: skip
        lib.cf_field_advance.restype = ctypes.c_int
        lib.cf_field_summary.argtypes = [ctypes.POINTER(Field), _D, _P, _P, _P, _P, _P, _P]
        lib.cf_field_summary.restype = ctypes.c_int
    return lib


def _ptr(a: np.ndarray) -> int:
    return a.__array_interface__["data"][0]


class CompiledField:
    """field.c for one LayerField's grid and law: the struct and the arrays it points
    into (kept here), scratch, and the calls. Built by ``LayerField`` and rebuilt when
    its law, strips or lattice change."""

    def __init__(self, lib: Any, f: Any, min_speed_fraction: float) -> None:
        law = f.law
        self.lib = lib
        self.arrays = tuple(
            np.ascontiguousarray(a, float) for a in (f.y, f.ell, f._p_strip, f._dy_w)
        )
        self.key = (law, f.y, f._dy_w, f.nx, f.ny, f.X, f.dx)
        c0 = law.mu * law.p0 / law.a1**2
        self.struct = Field(f.ny, f.nx, f.dx, f.X, law.a1, law.p0, law.mu, law.k, c0,
                            min_speed_fraction, *(_ptr(a) for a in self.arrays))  # fmt: skip
        self.shape = (f.ny, f.nx)
        self.work = np.empty(5 * f.ny * f.nx + 3 * f.nx)
        self.sin, self.sout = StageIn(), StageOut()
        self.sin_ref = ctypes.byref(self.sin)
        self.sout_ref = ctypes.byref(self.sout)
        self.struct_ref = ctypes.byref(self.struct)
        self.sout.work = _ptr(self.work)
        n = f.ny * f.nx
        self.step_work = np.empty(10 * n + 4 * f.nx)  # field.h: CF_FIELD_ADVANCE_WORK
        self.step_bytes = np.empty(3 * n, np.uint8)
        self.body, self.state = Body(), BodyState()
        self.loads = (_D * 4)()
        self.state.work, self.state.bytes = _ptr(self.step_work), _ptr(self.step_bytes)
        self.summary_out = (_D * 4)()

    def matches(self, f: Any) -> bool:
        """Whether this was built for f's present law, strips and lattice."""
        k = self.key
        return (k[0] is f.law and k[1] is f.y and k[2] is f._dy_w
                and k[3:] == (f.nx, f.ny, f.X, f.dx))  # fmt: skip

    def stage(
        self,
        theta: float,
        inside: np.ndarray,
        hat_x: np.ndarray,
        hat_y: np.ndarray,
        args: tuple[float, ...],
        midpath: bool,
        jacobian: bool,
    ) -> tuple | None:
        """cf_field_stage: (theta, shift, x, tau_x, tau_y, slip, inside, w, T, dTx_dvx, J)
        or None where the C declines. args: (ds, elapsed, h_own, vx, vy, phi, Vx)."""
        ny, nx = self.shape
        keep = (np.ascontiguousarray(inside, np.bool_), np.ascontiguousarray(hat_x, float),
                np.ascontiguousarray(hat_y, float))  # fmt: skip
        if any(a.shape != (ny, nx) for a in keep):
            return None
        s = self.sin
        s.theta = theta
        s.inside, s.hat_x, s.hat_y = (_ptr(a) for a in keep)
        s.ds, s.elapsed, s.h_own, s.vx, s.vy, s.phi, s.Vx = args
        s.midpath, s.jacobian = int(midpath), int(jacobian)
        x = np.empty(nx)
        tau_x, tau_y, w = np.empty((ny, nx)), np.empty((ny, nx)), np.empty((ny, nx))
        slip, ins = np.empty((ny, nx), np.bool_), np.empty((ny, nx), np.bool_)
        o = self.sout
        o.x, o.tau_x, o.tau_y, o.w, o.slip, o.inside = (
            _ptr(a) for a in (x, tau_x, tau_y, w, slip, ins)
        )
        rc = self.lib.cf_field_stage(self.struct_ref, self.sin_ref, self.sout_ref)
        # no pointer into arrays this call does not keep survives it
        s.inside = s.hat_x = s.hat_y = o.x = o.tau_x = o.tau_y = o.w = o.slip = o.inside = None
        if rc != OK:
            return None
        J = np.array(o.J[:]).reshape(3, 3) if jacobian else None
        return (o.theta, o.shift, x, tau_x, tau_y, slip, ins, w, tuple(o.T[:]), o.dTx_dvx, J)

    def weights(
        self,
        x: np.ndarray,
        inside: np.ndarray,
        tau_x: np.ndarray | None,
        tau_y: np.ndarray | None,
        slip: np.ndarray | None,
        sign: float,
    ) -> np.ndarray | None:
        """cf_field_weights (LayerField._weights), or None where the C declines."""
        ny, nx = self.shape
        x = np.ascontiguousarray(x, float)
        inside = np.ascontiguousarray(inside, np.bool_)
        if x.shape != (nx,) or inside.shape != (ny, nx):
            return None
        arrays = [None, None, None]
        if tau_x is not None:
            arrays = [np.ascontiguousarray(tau_x, float), np.ascontiguousarray(tau_y, float),
                      np.ascontiguousarray(np.zeros((ny, nx), np.bool_) if slip is None else slip,
                                           np.bool_)]  # fmt: skip
            if any(a.shape != (ny, nx) for a in arrays):
                return None
        w = np.empty((ny, nx))
        ptrs = [None if a is None else _ptr(a) for a in arrays]
        rc = self.lib.cf_field_weights(self.struct_ref, _ptr(x), _ptr(inside), *ptrs,
                                       float(sign), _ptr(w), _ptr(self.work))  # fmt: skip
        return w if rc == OK else None

    def advance(
        self,
        body: dict[str, float],
        y: np.ndarray,
        t: float,
        impulse: np.ndarray,
        field: tuple[float, np.ndarray, np.ndarray, np.ndarray],
        h: float,
        loads: tuple[float, float, float, float],
        substeps: int,
    ) -> tuple | None:
        """cf_field_advance: TransientRollingBody.advance on its scalar path. body: the
        fields of ``Body``; field: (theta, tau_x, tau_y, slip) at the start. Returns (y,
        t, impulse, (theta, direction, tau_x, tau_y, slip), T, sliding), new arrays, or
        None where the C declines (the caller's state is untouched either way)."""
        ny, nx = self.shape
        theta, tau_x, tau_y, slip = field
        if any(np.shape(a) != (ny, nx) for a in (tau_x, tau_y, slip)):
            return None
        b = self.body = Body()  # the fields ``body`` leaves out at 0 (dyn_vy ...: the scalar path)
        for k, v in body.items():
            setattr(b, k, v)
        st = self.state
        st.y[:] = [float(v) for v in y]
        st.t = t
        st.impulse[:] = [float(v) for v in impulse]
        st.theta = theta
        tx, ty = np.array(tau_x, float, order="C"), np.array(tau_y, float, order="C")
        sl = np.array(slip, np.bool_, order="C")
        st.tau_x, st.tau_y, st.slip = _ptr(tx), _ptr(ty), _ptr(sl)
        self.loads[:] = [float(v) for v in loads]
        rc = self.lib.cf_field_advance(self.struct_ref, ctypes.byref(b), ctypes.byref(st), h,
                                       ctypes.addressof(self.loads), substeps)  # fmt: skip
        st.tau_x = st.tau_y = st.slip = None
        if rc != OK:
            return None
        fstate = (st.theta, st.direction, tx, ty, sl)
        return (
            np.array(st.y[:]),
            st.t,
            np.array(st.impulse[:]),
            fstate,
            tuple(st.T[:]),
            bool(st.sliding),
        )

    def summary(
        self, theta: float, tau_x: np.ndarray, tau_y: np.ndarray, slip: np.ndarray
    ) -> tuple[float, float, float, float] | None:
        """cf_field_summary (LayerField.summary): (adhesion, slip_centroid_x,
        slip_centroid_y, tau_peak), or None where the C declines."""
        ny, nx = self.shape
        arrays = (np.ascontiguousarray(tau_x, float), np.ascontiguousarray(tau_y, float),
                  np.ascontiguousarray(slip, np.bool_))  # fmt: skip
        if any(a.shape != (ny, nx) for a in arrays):
            return None
        # scratch: the step's (2 ny nx + 4 nx doubles, ny nx bytes fit in it)
        rc = self.lib.cf_field_summary(self.struct_ref, theta, *(_ptr(a) for a in arrays),
                                       ctypes.addressof(self.summary_out),
                                       _ptr(self.step_work), _ptr(self.step_bytes))  # fmt: skip
        if rc != OK:
            return None
        a, cx, cy, peak = self.summary_out[:]
        return a, cx, cy, peak
