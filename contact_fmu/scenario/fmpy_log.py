"""One process-wide route for FMI 2.0 log messages under fmpy.

fmpy formats an FMU's variadic log message in C (``fmpy.logging.addLoggerProxy``) and
hands the text to *one* global callback: the one registered last. A callback that is
registered by an object and freed with it leaves that global dangling, and the next
message of any FMU in the process (``fmpy.simulate_fmu``'s included) jumps into freed
memory: a segmentation fault. fmpy's own ``simulate_fmu(logger=f)`` leaves it so when it
returns.

The callback here lives as long as the module and routes each message by the
``componentEnvironment`` the instance was given; messages of other instances go to
fmpy's own printer, as they would without this module. ``claim()`` makes it the global
callback again (cheap: one C call), so an instance that calls it before each FMI call
survives whatever else in the process registered a logger in between.
"""

from __future__ import annotations

import itertools
import weakref
from collections.abc import Callable
from ctypes import byref, c_void_p

from fmpy.fmi1 import printLogMessage
from fmpy.fmi2 import fmi2CallbackFunctions, fmi2CallbackLoggerTYPE

try:
    from fmpy.logging import addLoggerProxy
except ImportError:  # pragma: no cover - fmpy without its C logger proxy
    addLoggerProxy = None

Sink = Callable[[int, str], None]
_sinks: dict[int, weakref.WeakMethod] = {}
_keys = itertools.count(1)


def _route(env, instance, status, category, message) -> None:
    ref = _sinks.get(env or 0)
    sink = ref() if ref is not None else None
    if sink is None:
        printLogMessage(env, instance, status, category, message)
    else:
        sink(int(status), message.decode(errors="replace") if message else "")


_ROUTER = fmi2CallbackLoggerTYPE(_route)  # never freed: the module holds it
_holder = fmi2CallbackFunctions()


def claim() -> None:
    """Make the module's router fmpy's global log callback (again)."""
    if addLoggerProxy is not None:
        _holder.logger = _ROUTER  # addLoggerProxy swaps it for its C formatter
        addLoggerProxy(byref(_holder))


def attach(callbacks: fmi2CallbackFunctions, sink: Sink) -> int:
    """Route the messages of an instance made with ``callbacks`` to the bound method
    ``sink(status, text)`` (held weakly); returns the key to ``detach`` it with."""
    key = next(_keys)
    _sinks[key] = weakref.WeakMethod(sink)
    callbacks.componentEnvironment = c_void_p(key)
    callbacks.logger = _ROUTER
    if addLoggerProxy is not None:
        addLoggerProxy(byref(callbacks))  # logger := fmpy's formatter, global := router
    return key


def detach(key: int) -> None:
    """Stop routing to the sink ``attach`` returned ``key`` for."""
    _sinks.pop(key, None)
