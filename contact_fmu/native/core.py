"""One instance of the native FMUs' C core (instance.c), driven from Python with ctypes.

The native FMUs' instance layer is compiled per model: its variables, GUID and model
parts come from the header ``cf_model.h`` that fmu_build/native_fmu.py generates for a
configuration. Built without an FMI front end and with ``CF_KERNEL_EXPORT`` (so that the
``cf_*`` functions of instance.h are exported), the C files ``CORE`` give a library of
that one model; ``Core`` instantiates it and calls it as fmi2.c does: value references
as in the model description (the configuration's variables in order), statuses
``CF_STATUS_*`` (FMI 2.0's numbers), every message through ``log(status, text)``.

The pythonfmu adapter delegates to it where its FMU carries the model's core
(fmu/slave_core.py); tests drive it against the adapter's Python path, the reference
implementation, in one process.
"""

from __future__ import annotations

import ctypes
from collections.abc import Callable, Sequence
from pathlib import Path

# the C files of one model's core (with cf_model.h): native_fmu.CORE's translation units
SOURCES = ("instance.c", "model.c", "stepper.c", "field.c")
FLAGS = ("-DCF_KERNEL_EXPORT",)  # export the cf_* functions (stepper.h's CF_HIDDEN)
OK, WARNING, DISCARD, ERROR, FATAL = range(5)  # cf_status
# In a pythonfmu FMU (fmu_build): the core library, its GUID (the FMU's) and the
# creep-force table it reads, next to this file
LIBRARY, GUID_FILE, TABLE = "_core.so", "_core.guid", "table.bin"

_LOG = ctypes.CFUNCTYPE(
    None, ctypes.c_void_p, ctypes.c_char_p, ctypes.c_int, ctypes.c_char_p, ctypes.c_char_p
)
_ALLOC = ctypes.CFUNCTYPE(ctypes.c_void_p, ctypes.c_void_p, ctypes.c_size_t, ctypes.c_size_t)
_RELEASE = ctypes.CFUNCTYPE(None, ctypes.c_void_p, ctypes.c_void_p)


class _Callbacks(ctypes.Structure):
    """cf_callbacks (instance.h)."""

    _fields_ = [("log", _LOG), ("alloc", _ALLOC), ("release", _RELEASE)]


def _libc() -> ctypes.CDLL:
    """The C library's calloc and free (the core's memory: instance.h's callbacks)."""
    libc = ctypes.CDLL(None)  # the process's own symbols (POSIX)
    libc.calloc.restype = ctypes.c_void_p
    libc.calloc.argtypes = [ctypes.c_size_t, ctypes.c_size_t]
    libc.free.argtypes = [ctypes.c_void_p]
    return libc


_U = ctypes.POINTER(ctypes.c_uint)
_D = ctypes.POINTER(ctypes.c_double)
_I = ctypes.POINTER(ctypes.c_int)
_S = ctypes.POINTER(ctypes.c_char_p)
_P = ctypes.POINTER(ctypes.c_void_p)
_SIGNATURES = {
    "cf_instantiate": (
        ctypes.c_void_p,
        [
            ctypes.c_char_p,
            ctypes.c_char_p,
            ctypes.c_char_p,
            ctypes.c_char_p,
            ctypes.c_int,
            ctypes.POINTER(_Callbacks),
            ctypes.c_void_p,
            ctypes.c_size_t,
        ],
    ),  # fmt: skip
    "cf_free_instance": (None, [ctypes.c_void_p]),
    "cf_setup_experiment": (ctypes.c_int, [ctypes.c_void_p, ctypes.c_double]),
    "cf_enter_initialization_mode": (ctypes.c_int, [ctypes.c_void_p]),
    "cf_exit_initialization_mode": (ctypes.c_int, [ctypes.c_void_p]),
    "cf_terminate": (ctypes.c_int, [ctypes.c_void_p]),
    "cf_reset": (ctypes.c_int, [ctypes.c_void_p]),
    "cf_get_real": (ctypes.c_int, [ctypes.c_void_p, _U, ctypes.c_size_t, _D]),
    "cf_set_real": (ctypes.c_int, [ctypes.c_void_p, _U, ctypes.c_size_t, _D]),
    "cf_get_integer": (ctypes.c_int, [ctypes.c_void_p, _U, ctypes.c_size_t, _I]),
    "cf_set_integer": (ctypes.c_int, [ctypes.c_void_p, _U, ctypes.c_size_t, _I]),
    "cf_get_string": (ctypes.c_int, [ctypes.c_void_p, _U, ctypes.c_size_t, _S]),
    "cf_get_boolean": (ctypes.c_int, [ctypes.c_void_p, _U, ctypes.c_size_t]),
    "cf_set_boolean": (ctypes.c_int, [ctypes.c_void_p, _U, ctypes.c_size_t]),
    "cf_set_string": (ctypes.c_int, [ctypes.c_void_p, _U, ctypes.c_size_t, _S]),
    "cf_do_step": (ctypes.c_int, [ctypes.c_void_p, ctypes.c_double, ctypes.c_double]),
    "cf_time": (ctypes.c_double, [ctypes.c_void_p]),
    "cf_get_state": (ctypes.c_int, [ctypes.c_void_p, _P]),
    "cf_set_state": (ctypes.c_int, [ctypes.c_void_p, ctypes.c_void_p]),
    "cf_free_state": (ctypes.c_int, [ctypes.c_void_p, _P]),
    "cf_serialized_size": (
        ctypes.c_int,
        [ctypes.c_void_p, ctypes.c_void_p, ctypes.POINTER(ctypes.c_size_t)],
    ),  # fmt: skip
    "cf_serialize": (
        ctypes.c_int,
        [ctypes.c_void_p, ctypes.c_void_p, ctypes.c_char_p, ctypes.c_size_t],
    ),  # fmt: skip
    "cf_deserialize": (ctypes.c_int, [ctypes.c_void_p, ctypes.c_char_p, ctypes.c_size_t, _P]),
}


def load(path: str | Path) -> ctypes.CDLL:
    """A core library (SOURCES with its cf_model.h, built with FLAGS), its functions typed."""
    lib = ctypes.CDLL(str(path))
    for name, (restype, argtypes) in _SIGNATURES.items():
        fn = getattr(lib, name)
        fn.restype, fn.argtypes = restype, argtypes
    return lib


class Core:
    """One instance of a core library: the FMI calls by value reference, their statuses,
    the messages to ``log(status, text)`` (all of them, whatever the status; with
    ``categories``, ``log(status, text, category)``: the model description's
    LogCategories, instance.c's)."""

    def __init__(
        self,
        lib: ctypes.CDLL,
        guid: str,
        log: Callable[..., None],
        name: str = "core",
        resources: str = "",
        api: str = "fmi2",
        categories: bool = False,
    ) -> None:
        self._inst = None
        self._lib = lib
        self._api = ctypes.c_char_p(api.encode())  # outlives the instance (instance.h)
        libc = _libc()

        def on_log(env: int, instance: bytes, status: int, category: bytes, text: bytes) -> None:
            if categories:
                log(status, text.decode(errors="replace"), category.decode(errors="replace"))
            else:
                log(status, text.decode(errors="replace"))

        # the callbacks live as long as this object (ctypes calls them from C)
        self._callbacks = _Callbacks(
            _LOG(on_log),
            _ALLOC(lambda env, n, size: libc.calloc(n, size)),
            _RELEASE(lambda env, p: libc.free(p)),
        )
        self._inst = lib.cf_instantiate(
            self._api, name.encode(), guid.encode(), resources.encode(), 0,
            ctypes.byref(self._callbacks), None, 0,
        )  # fmt: skip
        if not self._inst:
            raise RuntimeError(f"cf_instantiate refused instance {name!r} (see the log)")

    def close(self) -> None:
        if self._inst:
            self._lib.cf_free_instance(self._inst)
            self._inst = None

    def __del__(self) -> None:
        self.close()

    # ---- phases and stepping -------------------------------------------------------------
    def setup_experiment(self, start: float) -> int:
        return self._lib.cf_setup_experiment(self._inst, start)

    def enter_initialization_mode(self) -> int:
        return self._lib.cf_enter_initialization_mode(self._inst)

    def exit_initialization_mode(self) -> int:
        return self._lib.cf_exit_initialization_mode(self._inst)

    def terminate(self) -> int:
        return self._lib.cf_terminate(self._inst)

    def reset(self) -> int:
        return self._lib.cf_reset(self._inst)

    def do_step(self, t: float, h: float) -> int:
        return self._lib.cf_do_step(self._inst, t, h)

    @property
    def time(self) -> float:
        return self._lib.cf_time(self._inst)

    # ---- variables -----------------------------------------------------------------------
    def set_real(self, vrs: Sequence[int], values: Sequence[float]) -> int:
        n = len(vrs)
        return self._lib.cf_set_real(
            self._inst, (ctypes.c_uint * n)(*vrs), n, (ctypes.c_double * n)(*values)
        )

    def get_real(self, vrs: Sequence[int]) -> tuple[int, list[float]]:
        n = len(vrs)
        out = (ctypes.c_double * n)()
        status = self._lib.cf_get_real(self._inst, (ctypes.c_uint * n)(*vrs), n, out)
        return status, list(out)

    def set_integer(self, vrs: Sequence[int], values: Sequence[int]) -> int:
        n = len(vrs)
        return self._lib.cf_set_integer(
            self._inst, (ctypes.c_uint * n)(*vrs), n, (ctypes.c_int * n)(*values)
        )

    def get_integer(self, vrs: Sequence[int]) -> tuple[int, list[int]]:
        n = len(vrs)
        out = (ctypes.c_int * n)()
        status = self._lib.cf_get_integer(self._inst, (ctypes.c_uint * n)(*vrs), n, out)
        return status, list(out)

    def set_string(self, vrs: Sequence[int], values: Sequence[str]) -> int:
        n = len(vrs)
        texts = (ctypes.c_char_p * n)(*(v.encode() for v in values))
        return self._lib.cf_set_string(self._inst, (ctypes.c_uint * n)(*vrs), n, texts)

    def get_boolean(self, vrs: Sequence[int]) -> int:
        """The model has no Boolean: every value reference is refused (logged)."""
        n = len(vrs)
        return self._lib.cf_get_boolean(self._inst, (ctypes.c_uint * n)(*vrs), n)

    def set_boolean(self, vrs: Sequence[int]) -> int:
        n = len(vrs)
        return self._lib.cf_set_boolean(self._inst, (ctypes.c_uint * n)(*vrs), n)

    def get_string(self, vrs: Sequence[int]) -> tuple[int, list[str]]:
        n = len(vrs)
        out = (ctypes.c_char_p * n)()
        status = self._lib.cf_get_string(self._inst, (ctypes.c_uint * n)(*vrs), n, out)
        return status, [(v or b"").decode() for v in out]

    # ---- FMU state: instance.c's one format, as bytes --------------------------------------
    def get_state(self) -> tuple[int, bytes]:
        """The instance's state serialized (cf_get_state, cf_serialize, cf_free_state)."""
        st = ctypes.c_void_p()
        status = self._lib.cf_get_state(self._inst, ctypes.byref(st))
        if status > WARNING:
            return status, b""
        try:
            size = ctypes.c_size_t()
            status = max(status, self._lib.cf_serialized_size(self._inst, st, ctypes.byref(size)))
            buf = ctypes.create_string_buffer(size.value)
            status = max(status, self._lib.cf_serialize(self._inst, st, buf, size.value))
            return status, buf.raw
        finally:
            self._lib.cf_free_state(self._inst, ctypes.byref(st))

    @property
    def address(self) -> int:
        """The instance's address (cf_inst *), for a binding that calls it from C."""
        return self._inst or 0

    def set_state(self, data: bytes) -> int:
        """The state of ``data`` (cf_deserialize, cf_set_state): refused bytes change
        nothing (an error, logged)."""
        st = ctypes.c_void_p()
        status = self._lib.cf_deserialize(self._inst, data, len(data), ctypes.byref(st))
        if status > WARNING:
            return status
        try:
            return self._lib.cf_set_state(self._inst, st)
        finally:
            self._lib.cf_free_state(self._inst, ctypes.byref(st))
