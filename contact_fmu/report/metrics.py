"""Error norms, observed convergence orders and the step-to-step oscillation measure."""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

FloatArray = NDArray[np.float64]


def norms(error: ArrayLike, scale: float) -> tuple[float, float]:
    """(max, RMS) of |error| / scale over the finite entries (NaN marks "not compared")."""
    e = np.abs(np.asarray(error, float))
    e = e[np.isfinite(e)]
    if e.size == 0:
        return math.nan, math.nan
    return float(np.max(e)) / scale, float(np.sqrt(np.mean(e * e))) / scale


def observed_order(h: ArrayLike, e: ArrayLike, floor: float = 0.0) -> float:
    """Least-squares slope of log e against log h over the points with e > floor.

    NaN with fewer than two such points. The order of a method whose error behaves like
    C h^p; at the rounding floor the slope means nothing, hence ``floor``.
    """
    h, e = np.asarray(h, float), np.asarray(e, float)
    keep = np.isfinite(e) & (e > floor) & (h > 0)
    if np.count_nonzero(keep) < 2:
        return math.nan
    return float(np.polyfit(np.log(h[keep]), np.log(e[keep]), 1)[0])


def pairwise_orders(h: ArrayLike, e: ArrayLike) -> FloatArray:
    """log(e_i-1 / e_i) / log(h_i-1 / h_i) for consecutive points (NaN for the first)."""
    h, e = np.asarray(h, float), np.asarray(e, float)
    out = np.full(h.size, np.nan)
    with np.errstate(divide="ignore", invalid="ignore"):
        out[1:] = np.log(e[:-1] / e[1:]) / np.log(h[:-1] / h[1:])
    out[~np.isfinite(out)] = np.nan
    return out


def oscillation(y: ArrayLike, floor: float | ArrayLike) -> tuple[float, int]:
    """Step-to-step oscillation of a sampled output above its own variation.

    With the differences d_k = y_k+1 - y_k, a zig-zag at k is three consecutive
    differences of alternating sign (up, down, up or down, up, down): a smooth solution
    sampled on its grid changes direction at most once within three steps unless it
    varies on the scale of the step itself. Its amplitude is

        a_k = min(|d_k-1|, |d_k|, |d_k+1|),

    and the solution's own variation there is

        s_k = |y_k+3 - y_k-1| / 4,

    the mean change per step over the four steps that contain the zig-zag (shifted back
    at the end of the record), in which a component that alternates from step to step
    cancels exactly. The returned excess is
    max_k (a_k - s_k - floor), with the index k; <= 0 means no step-to-step
    oscillation above the solution's own variation and the noise ``floor`` (the
    rounding and solver tolerance of the output, in its units; or an array over the
    differences, floor[k] for the zig-zag centred on difference k). Without zig-zags it
    is -min(floor), index -1.
    """
    y = np.asarray(y, float)
    f = np.broadcast_to(np.asarray(floor, float), (max(y.size - 1, 1),))
    if y.size < 5:
        return -float(np.min(f)), -1
    d = np.diff(y)
    s = np.sign(d)
    # zig-zag centred on difference k (1 <= k <= n-3): s[k-1] = -s[k] = s[k+1] != 0
    k = np.arange(1, d.size - 1)
    zig = (s[k - 1] != 0) & (s[k - 1] == -s[k]) & (s[k] == -s[k + 1])
    if not np.any(zig):
        return -float(np.min(f)), -1
    a = np.minimum(np.minimum(np.abs(d[k - 1]), np.abs(d[k])), np.abs(d[k + 1]))
    # the zig-zag of differences k-1, k, k+1 spans y[k-1] .. y[k+2]; four steps hold it
    lo = np.minimum(k - 1, y.size - 5)
    own = np.abs(y[lo + 4] - y[lo]) / 4.0
    excess = np.where(zig, a - own - f[k], -np.inf)
    i = int(np.argmax(excess))
    return float(excess[i]), int(k[i])
