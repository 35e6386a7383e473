"""One FMU instance driven call by call through fmpy, with its log messages kept.

``simulate_fmu`` runs a whole experiment; masters that iterate (state get/set), feed
inputs step by step, or need the status of each call use this instead. Variables are
addressed by name; ``step`` returns the FMI status instead of raising.
"""

from __future__ import annotations

import math
import shutil
import tempfile
from ctypes import byref
from pathlib import Path
from typing import Any

import fmpy
import numpy as np
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import (
    FMU2Slave,
    fmi2CallbackAllocateMemoryTYPE,
    fmi2CallbackFreeMemoryTYPE,
    fmi2CallbackFunctions,
)
from fmpy.fmi3 import FMU3Slave, fmi3Boolean, fmi3Float64

from contact_fmu.scenario import fmpy_log

OK, WARNING, DISCARD, ERROR, FATAL = range(5)


class Instance:
    """An instantiated, initialised co-simulation FMU (a context manager)."""

    def __init__(
        self,
        fmu: str | Path,
        name: str = "instance",
        start_values: dict[str, Any] | None = None,
        start_time: float = 0.0,
        unzip_dir: str | Path | None = None,
        initialise: bool = True,
    ) -> None:
        """Instantiated, start values set in initialisation mode, and (``initialise``)
        initialised; otherwise ``initialise()`` ends initialisation mode."""
        self._own_dir = unzip_dir is None
        self.dir = Path(unzip_dir or tempfile.mkdtemp(prefix="fmu-"))
        if self._own_dir:
            fmpy.extract(str(fmu), str(self.dir))
        self.md = fmpy.read_model_description(str(self.dir))
        self.vars = {v.name: v for v in self.md.modelVariables}
        self.messages: list[tuple[int, str]] = []
        self._callbacks = fmi2CallbackFunctions()
        self._callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(fmpy.calloc)
        self._callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(fmpy.free)
        self._log_key = fmpy_log.attach(self._callbacks, self._log)
        self.fmu = FMU2Slave(
            guid=self.md.guid,
            unzipDirectory=str(self.dir),
            modelIdentifier=self.md.coSimulation.modelIdentifier,
            instanceName=name,
        )
        self._fmi.instantiate(callbacks=self._callbacks, loggingOn=True)
        self.initialised = False  # exitInitializationMode answered OK
        self.time = start_time
        try:
            self._fmi.setupExperiment(startTime=start_time)
            self._fmi.enterInitializationMode()
            for k, v in (start_values or {}).items():
                self.set(k, v)
            if initialise:
                self.initialise()
        except FMICallException:  # a model that cannot start: freed, then the error
            self.close()
            raise

    @property
    def _fmi(self) -> FMU2Slave:
        """The fmpy slave, with the log route claimed for the call to come (another
        object in the process may have registered fmpy's one global logger since)."""
        fmpy_log.claim()
        return self.fmu

    def initialise(self) -> None:
        """fmi2ExitInitializationMode (fmpy raises FMICallException above Warning)."""
        self._fmi.exitInitializationMode()
        self.initialised = True

    def _log(self, status: int, text: str) -> None:
        self.messages.append((status, text))

    # ---- values ----------------------------------------------------------------------
    def set(self, name: str, value: Any) -> None:
        v = self.vars[name]
        if v.type == "Real":
            self._fmi.setReal([v.valueReference], [float(value)])
        elif v.type == "Integer":
            self._fmi.setInteger([v.valueReference], [int(value)])
        elif v.type == "String":
            self._fmi.setString([v.valueReference], [str(value)])
        else:
            raise TypeError(f"{name}: type {v.type} not supported")

    def get(self, name: str) -> Any:
        v = self.vars[name]
        if v.type == "Integer":
            return self._fmi.getInteger([v.valueReference])[0]
        if v.type == "String":
            return self._fmi.getString([v.valueReference])[0].decode()
        return self._fmi.getReal([v.valueReference])[0]

    def outputs(self) -> dict[str, Any]:
        return {n: self.get(n) for n, v in self.vars.items() if v.causality == "output"}

    # ---- stepping ---------------------------------------------------------------------
    def step(self, h: float, time: float | None = None) -> int:
        """doStep from ``time`` (default: the instance's time) by h; the FMI status."""
        t = self.time if time is None else time
        try:
            self._fmi.doStep(currentCommunicationPoint=t, communicationStepSize=h)
        except FMICallException as e:
            return int(e.status)
        self.time = t + h
        return OK

    def get_state(self) -> Any:
        return (self._fmi.getFMUstate(), self.time)

    def set_state(self, state: Any) -> None:
        s, self.time = state
        self._fmi.setFMUstate(s)

    def free_state(self, state: Any) -> None:
        self._fmi.freeFMUstate(state[0])

    def serialize_state(self, state: Any) -> bytes:
        """A state of get_state as bytes (fmi2SerializeFMUstate; the master's time is
        not in them)."""
        return bytes(self._fmi.serializeFMUstate(state[0]))

    def deserialize_state(self, data: bytes, time: float) -> Any:
        """Bytes of serialize_state, from any instance of this FMU, as a state for
        set_state at the master's ``time`` (s) (fmi2DeSerializeFMUstate)."""
        return (self._fmi.deSerializeFMUstate(data), time)

    def close(self) -> None:
        try:
            if self.initialised:  # FMI 2.0: terminate ends an initialised model only
                self._fmi.terminate()
        finally:
            self._fmi.freeInstance()
            fmpy_log.detach(self._log_key)
            if self._own_dir:
                shutil.rmtree(self.dir, ignore_errors=True)

    def __enter__(self) -> Instance:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


class Instance3:
    """An FMI 3.0 co-simulation FMU through fmpy's FMU3Slave, the shape of ``Instance``
    (which drives FMI 2.0): values set and got by name, ``step`` answering the FMI
    status, FMU states, the log messages kept; ``do_step(t, h)`` the raw status of
    fmi3DoStep (Warning included, which fmpy does not raise); ``array(name)`` an array
    output's values."""

    def __init__(
        self,
        path: str | Path,
        name: str = "instance3",
        start_values: dict[str, Any] | None = None,
        initialise: bool = True,
    ) -> None:
        self.dir = Path(tempfile.mkdtemp(prefix="fmu3-"))
        fmpy.extract(str(path), str(self.dir))
        self.md = fmpy.read_model_description(str(self.dir))
        self.vars = {v.name: v for v in self.md.modelVariables}
        self.messages: list[tuple[int, str]] = []
        self.fmu = FMU3Slave(
            guid=self.md.guid,
            unzipDirectory=str(self.dir),
            modelIdentifier=self.md.coSimulation.modelIdentifier,
            instanceName=name,
        )
        self.fmu.instantiate(loggingOn=True, logMessage=self._log)
        self.time = 0.0
        self.initialised = False
        try:
            self.fmu.enterInitializationMode(startTime=0.0)
            for k, v in (start_values or {}).items():
                self.set(k, v)
            if initialise:
                self.initialise()
        except FMICallException:
            self.close()
            raise

    def _log(self, env, status, category, message) -> None:
        self.messages.append((int(status), message.decode(errors="replace")))

    def initialise(self) -> None:
        self.fmu.exitInitializationMode()
        self.initialised = True

    def set(self, name: str, value: Any) -> None:
        v = self.vars[name]
        if v.type == "Int32":
            self.fmu.setInt32([v.valueReference], [int(value)])
        elif v.type == "String":
            self.fmu.setString([v.valueReference], [str(value)])
        else:
            self.fmu.setFloat64([v.valueReference], [float(value)])

    def get(self, name: str) -> Any:
        v = self.vars[name]
        if v.type == "Int32":
            return self.fmu.getInt32([v.valueReference])[0]
        if v.type == "String":
            return self.fmu.getString([v.valueReference])[0]
        return self.fmu.getFloat64([v.valueReference])[0]

    def outputs(self) -> dict[str, Any]:
        """The scalar outputs (an array output: ``array``)."""
        return {
            n: self.get(n)
            for n, v in self.vars.items()
            if v.causality == "output" and not v.dimensions
        }

    def array(self, name: str) -> np.ndarray:
        """An array output, its values in one call."""
        v = self.vars[name]
        n = math.prod(int(d.start) for d in v.dimensions)
        return np.array(self.fmu.getFloat64([v.valueReference], nValues=n))

    def do_step(self, t: float, h: float) -> int:
        """fmi3DoStep from t by h: its status (fmpy raises above Warning: caught)."""
        flags = [fmi3Boolean() for _ in range(3)]
        last = fmi3Float64()
        try:
            status = self.fmu.fmi3DoStep(
                self.fmu.component, t, h, fmi3Boolean(True), *map(byref, flags), byref(last)
            )
        except FMICallException as e:
            return int(e.status)
        return int(status)

    def step(self, h: float, time: float | None = None) -> int:
        """doStep from ``time`` (default: the instance's time) by h; the FMI status."""
        t = self.time if time is None else time
        status = self.do_step(t, h)
        if status <= 1:
            self.time = t + h
        return status

    def get_state(self) -> Any:
        return (self.fmu.getFMUState(), self.time)

    def set_state(self, state: Any) -> None:
        s, self.time = state
        self.fmu.setFMUState(s)

    def free_state(self, state: Any) -> None:
        self.fmu.freeFMUState(state[0])

    def close(self) -> None:
        try:
            if self.initialised:  # terminate ends an initialised model only
                self.fmu.terminate()
        finally:
            self.fmu.freeInstance()
            shutil.rmtree(self.dir, ignore_errors=True)

    def __enter__(self) -> Instance3:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
