"""Summary values of a run, as a scene's [sweep] metrics name them (``schema.Metric``).

Only reductions of recorded columns: the runner knows no physics. ``per`` divides the
column sample by sample by the product of the named parameters or recorded columns
(``max |Tx|/(mu P)`` is ``of = "Tx", reduce = "max_abs", per = ["mu", "P"]``).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..scenario.schema import Metric

FloatArray = NDArray[np.float64]


def settle_time(t: FloatArray, y: FloatArray, tol: float) -> float:
    """The first time from which y stays within tol of its final value (s)."""
    outside = np.flatnonzero(np.abs(y - y[-1]) > tol)
    if outside.size == 0:
        return float(t[0])
    return float(t[min(outside[-1] + 1, t.size - 1)])


def value(m: Metric, columns: Mapping[str, FloatArray], parameters: Mapping[str, Any]) -> float:
    """The metric ``m`` of a run's recorded ``columns`` (time first) and parameters; NaN
    when the run recorded no sample at or after ``m.after``."""
    t = np.asarray(columns["time"], float)
    y = np.asarray(columns[m.of], float)
    for p in m.per:
        y = y / (np.asarray(columns[p], float) if p in columns else float(parameters[p]))
    keep = t >= m.after
    t, y = t[keep], y[keep]
    if y.size == 0:
        return math.nan
    r = m.reduce
    if r == "max":
        return float(np.max(y))
    if r == "min":
        return float(np.min(y))
    if r == "max_abs":
        return float(np.max(np.abs(y)))
    if r == "mean":
        return float(np.mean(y))
    if r == "final":
        return float(y[-1])
    if r == "settle_time":
        return settle_time(t, y, m.tol)
    if r == "any_above":
        return float(np.any(y > m.threshold))
    if r == "any_below":
        return float(np.any(y < m.threshold))
    raise ValueError(f"unknown reduction {r!r}")


def defaults(outputs: tuple[str, ...]) -> tuple[Metric, ...]:
    """Metrics of a scene that names none: each output's final value and largest |value|."""
    out = []
    for o in outputs:
        out += [Metric(f"{o}_final", o, "final"), Metric(f"{o}_max_abs", o, "max_abs")]
    return tuple(out)
