"""What one instance's FMI calls share with their compiled fast path.

The pythonfmu adapter (slave.py) keeps here what every FMI call of an instance reads or
changes; the CPython binding of the per-step calls (native/fmi.c) reads and writes the
same object, by these attribute names, on every call: the adapter may replace a
dictionary whole, and both then see the new one. This class is the whole contract
between the two; nothing else of the adapter is read from C.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

# Relative tolerance between doStep's currentCommunicationPoint and the FMU's time: a
# master that accumulates steps, multiplies or converts integer nanoseconds differs
# from t + h by a few units in the last place of t, never by more (64 ulp).
TIME_RTOL = 1.4210854715202004e-14  # 64 * 2**-52 (C: cf_abi.h's CF_TIME_RTOL)


@dataclass(slots=True)
class CallState:
    """time: the FMU's time (s), the end of the last step; values: every parameter's and
    input's value by name; inputs: the inputs' values, the argument of every step (kept
    in step with values); bad: the values refused and held, name -> why; dirty: inputs
    set since the outputs were computed; out_stale: the outputs behind the compiled
    step's struct (compiled steps taken since Python last read them)."""

    values: dict[str, Any]
    inputs: dict[str, Any] = field(default_factory=dict)
    bad: dict[str, str] = field(default_factory=dict)
    time: float = 0.0
    dirty: bool = True
    out_stale: bool = False
