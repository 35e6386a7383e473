"""The pythonfmu adapter's delegation to its model's C core, where the FMU carries it.

A pythonfmu FMU built for a model the native FMU covers carries that model's core
(``native/_core.so``: instance.c, model.c, stepper.c, field.c with the model's
cf_model.h; fmu_build ``_compile_core``). An instance of ContactSlave (slave.py) that
finds it forwards every FMI call to one instance of it (``native.core.Core``):
phases, the checks of a value, of a step's time and size and its admission, String
parameters, the messages and the FMU states are then instance.c's, as in the native
FMUs; pythonfmu, its binary and the status shim stay the FMU's FMI 2.0 front end.

- Statuses: the core's status of each call goes into the shim's cell (the FMU answers
  the worse of pythonfmu's and the cell's, pythonfmu_shim.c); doStep answers False from
  Discard on. Without a cell (pythonfmu's binary alone) a call the core answers with
  fmi2Error raises, which pythonfmu answers with fmi2Fatal: never fmi2OK.
- Messages: the core's, each logged through the slave's ``log`` with its status and
  category (logStatusWarning ... logAll). Only slave.py imports pythonfmu: its statuses
  are given here as numbers (``_log_status``).
- Value references: the model description's, the configuration's variables in order
  (both the adapter's registration and the core's cf_model.h follow ``cfg.variables``).
- FMU state: the core's bytes (instance.c's format: its magic, version, GUID, checksum);
  serialisation is the identity, the bytes are checked at fmi2DeSerializeFMUstate. A
  state of the Python path (``state_bytes``) is refused naming it, as the Python path
  refuses the core's.
- Per step: do_step, set_real and get_real go through native/fmi.c's CoreBinding (one C
  call each, at the core's function addresses) where the extension is built and the
  shim's cell is known; otherwise through ctypes.
- Freed: at fmi2FreeInstance and fmi2Reset the shim tells the adapter (``RELEASE`` through
  the cell's value reference) and the core instance is freed then, not at the Python
  object's collection.

Not used (the adapter's Python path, the reference implementation, instead) where the
FMU carries no core, off Linux, or with CONTACT_FMU_CORE=0 or CONTACT_FMU_NATIVE=0 in
the environment when the instance is made.
"""

from __future__ import annotations

import ctypes
import os
import sys
import weakref
from pathlib import Path
from typing import Any

from .. import native
from ..native import core
from . import messages as words
from .package_loader import PACKAGE

# the environment variable that turns the core off (the Python path runs)
CORE_ENV = "CONTACT_FMU_CORE"
# the text the shim sends through the cell's value reference when the instance goes
# (fmi2FreeInstance, fmi2Reset): the core instance is freed then
RELEASE = "release"
# the FMI calls forwarded to the core (the slave's methods by these names)
CALLS = (
    "setup_experiment", "enter_initialization_mode", "exit_initialization_mode",
    "terminate", "do_step", "get_real", "set_real", "get_integer", "set_integer",
    "get_boolean", "set_boolean", "get_string", "set_string", "_get_fmu_state",
    "_set_fmu_state",
)  # fmt: skip
_LIBRARIES: dict[str, ctypes.CDLL] = {}


def enabled() -> bool:
    """Whether an instance made now may use a core (Linux; neither variable 0)."""
    off = ("0",)
    return (
        sys.platform.startswith("linux")
        and os.environ.get(CORE_ENV, "1") not in off
        and os.environ.get("CONTACT_FMU_NATIVE", "1") not in off
    )


def find(resources: str | None) -> tuple[ctypes.CDLL, str, Path] | None:
    """(library, GUID, folder of its files) of this FMU's core for an instance whose
    resources are ``resources`` (this instance's copy of the package: the table is read
    from there), or None (no core carried, disabled, not loadable: a file that does not
    load is reported among ``native.PROBLEMS`` and the Python path runs). One library per
    FMU (its GUID) in a process: it stays loaded when the folder it came from is gone."""
    if not resources or not enabled():
        return None
    where = Path(resources) / PACKAGE / "native"
    lib_path, guid_path = where / core.LIBRARY, where / core.GUID_FILE
    if not (lib_path.is_file() and guid_path.is_file()):
        return None
    guid = guid_path.read_text().strip()
    if guid not in _LIBRARIES:
        lib = native._load(lib_path, core.load)
        if lib is None:
            return None
        _LIBRARIES[guid] = lib
    return _LIBRARIES[guid], guid, where


class CoreCalls:
    """The FMI calls of one ContactSlave, forwarded to its core instance. It holds the
    slave weakly: the slave's own attributes name these methods. RuntimeError with the
    core's reason where the core refuses to instantiate (its table unreadable)."""

    def __init__(self, slave: Any, lib: ctypes.CDLL, guid: str, where: Path) -> None:
        ref = weakref.ref(slave)
        self._slave = ref
        self._lib = lib
        self._binding: Any = None

        # what cf_instantiate logs is the reason it refuses (a table it cannot read):
        # kept for the RuntimeError, after which the slave runs its Python path
        starting: list[str] | None = []

        def log(status: int, text: str, category: str) -> None:
            s = ref()
            if starting is not None:
                starting.append(text)
            elif s is not None:
                s._log_status(status, text, category or None)

        try:
            self.core: core.Core | None = core.Core(
                lib, guid, log, name=slave.instance_name, resources=where.as_uri(),
                categories=True,
            )  # fmt: skip
        except RuntimeError as e:
            raise RuntimeError("; ".join(starting) or str(e)) from None
        starting = None

    def attach(self, slave: Any) -> None:
        """The slave's FMI methods become these (on the instance, in place of the class's)."""
        for name in CALLS:
            setattr(slave, name, getattr(self, name))

    def release(self) -> None:
        """Free the core instance now (the slave is being freed or reset)."""
        if self._binding is not None:
            self._binding.close()
            self._binding = None
        if self.core is not None:
            self.core.close()
            self.core = None

    # ---- statuses -------------------------------------------------------------------------
    def _answer(self, status: int) -> int:
        """The call's status into the shim's cell; without a cell, fmi2Error raises."""
        s = self._slave()
        cell = None if s is None else s._cell
        if cell is not None:
            if status > cell.value:
                cell.value = status
        elif status >= core.ERROR:
            raise RuntimeError(words.CORE_REFUSED(status=status))
        return status

    def _core(self) -> core.Core:
        if self.core is None:
            raise RuntimeError(words.CORE_RELEASED())
        return self.core

    def _bind(self) -> None:
        """The per-step calls through fmi.c's CoreBinding, once the cell is known."""
        s = self._slave()
        fmi = native.fmi_module()
        if s is None or s._cell is None or self.core is None or fmi is None:
            return
        if self._binding is not None:  # a cell sent again: the new one
            self._binding.close()
        lib = self._lib
        self._binding = fmi.bind_core(
            self.core, self._py_do_step, self._py_set_real, self._py_get_real,
            ctypes.cast(lib.cf_do_step, ctypes.c_void_p).value,
            ctypes.cast(lib.cf_set_real, ctypes.c_void_p).value,
            ctypes.cast(lib.cf_get_real, ctypes.c_void_p).value,
            self.core.address, ctypes.addressof(s._cell),
        )  # fmt: skip
        for name in ("do_step", "set_real", "get_real"):
            setattr(s, name, getattr(self._binding, name))

    # ---- phases ---------------------------------------------------------------------------
    def setup_experiment(
        self, start_time: float, stop_time: float | None = None, tolerance: float | None = None
    ) -> None:
        self._answer(self._core().setup_experiment(float(start_time)))

    def enter_initialization_mode(self) -> None:
        self._answer(self._core().enter_initialization_mode())

    def exit_initialization_mode(self) -> None:
        self._answer(self._core().exit_initialization_mode())

    def terminate(self) -> None:
        self._answer(self._core().terminate())

    def do_step(self, current_time: float, step_size: float) -> bool:
        return self._py_do_step(current_time, step_size)

    def _py_do_step(self, current_time: float, step_size: float) -> bool:
        """True up to Warning (pythonfmu: fmi2OK, the cell raising it), else False."""
        return self._answer(self._core().do_step(float(current_time), float(step_size))) <= (
            core.WARNING
        )

    # ---- values ---------------------------------------------------------------------------
    def get_real(self, vrs: list[int]) -> list[float]:
        return self._py_get_real(vrs)

    def _py_get_real(self, vrs: list[int]) -> list[float]:
        status, out = self._core().get_real(list(vrs))
        self._answer(status)
        return out

    def set_real(self, vrs: list[int], values: list[float]) -> None:
        self._py_set_real(vrs, values)

    def _py_set_real(self, vrs: list[int], values: list[float]) -> None:
        self._answer(self._core().set_real(list(vrs), [float(v) for v in values]))

    def get_integer(self, vrs: list[int]) -> list[int]:
        status, out = self._core().get_integer(list(vrs))
        self._answer(status)
        return out

    def set_integer(self, vrs: list[int], values: list[int]) -> None:
        self._answer(self._core().set_integer(list(vrs), [int(v) for v in values]))

    def get_boolean(self, vrs: list[int]) -> list[bool]:
        self._answer(self._core().get_boolean(list(vrs)))
        return [False] * len(vrs)

    def set_boolean(self, vrs: list[int], values: list[bool]) -> None:
        self._answer(self._core().set_boolean(list(vrs)))

    def get_string(self, vrs: list[int]) -> list[str]:
        status, out = self._core().get_string(list(vrs))
        self._answer(status)
        return out

    def set_string(self, vrs: list[int], values: list[str]) -> None:
        s = self._slave()
        if s is not None and len(vrs) == 1 and vrs[0] == s.CELL_VR:  # the shim's channel
            if values[0] == RELEASE:
                self.release()
                return
            s._take_cell(values[0])
            self._bind()
            return
        self._answer(self._core().set_string(list(vrs), [str(v) for v in values]))

    # ---- FMU state: instance.c's bytes ------------------------------------------------------
    def _get_fmu_state(self) -> bytes:
        status, data = self._core().get_state()
        self._answer(status)
        return data

    def _set_fmu_state(self, state: Any) -> None:
        """The core's bytes (checked whole by cf_deserialize, refused with the reason);
        a state of the Python path (a dict, or its bytes unread) refused naming it."""
        if not isinstance(state, bytes):
            why = words.STATE_OF_PYTHON()
            s = self._slave()
            if s is not None:
                s._log_status(
                    core.ERROR, words.STATE_UNCHANGED(refused=words.STATE_REFUSED(why=why))
                )
            self._answer(core.ERROR)
            return
        self._answer(self._core().set_state(state))
