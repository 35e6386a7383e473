"""Input signals of a scene: sums of constant, step, ramp, sine and tabulated pieces.

A signal is written in TOML as a number (a constant), one piece, or a list of pieces
that are added:

    P     = 1000.0
    Fx_ex = { constant = 190.98 }
    My_ex = [ { sine = { amplitude = 1.9, period = 0.0557 } },
              { step = { time = 0.01, height = -0.5 } } ]

Pieces (times in s, values in the unit of the input):
    constant = c
    step  = { time, height }                    height for t >= time, else 0
    ramp  = { start, duration, height }         0 before start, linear to height, held
    sine  = { amplitude, period, phase = 0, start = 0 }
                                                amplitude sin(2 pi (t - start)/period + phase)
                                                for t >= start, else 0
    table = { time = [...], value = [...], hold = false }
                                                linear (or held, hold = true) between
                                                points, end values held outside

No expression is evaluated: every piece is data.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

FloatArray = NDArray[np.float64]


class SignalError(ValueError):
    """A signal in a scene file is malformed; the message names it."""


def _number(where: str, d: dict[str, Any], key: str, default: float | None = None) -> float:
    if key not in d:
        if default is None:
            raise SignalError(f"{where}: missing '{key}'")
        return default
    v = d[key]
    if isinstance(v, bool) or not isinstance(v, int | float) or not math.isfinite(v):
        raise SignalError(f"{where}: '{key}' = {v!r} must be a finite number")
    return float(v)


def _keys(where: str, d: Any, allowed: set[str]) -> dict[str, Any]:
    if not isinstance(d, dict):
        raise SignalError(f"{where}: expected a table, got {d!r}")
    extra = set(d) - allowed
    if extra:
        raise SignalError(f"{where}: unknown key(s) {sorted(extra)}; allowed {sorted(allowed)}")
    return d


@dataclass(frozen=True)
class Signal:
    """A scene input as a function of time: value(t) for an array of times (s).

    ``breakpoints``: the times (s, sorted) where a piece jumps or has a kink (step
    times, ramp ends, sine starts, table points); between them the signal is smooth.
    An integrator of the continuous signal restarts there.
    """

    name: str
    pieces: tuple[Callable[[FloatArray], FloatArray], ...]
    breakpoints: tuple[float, ...] = ()

    def __call__(self, t: ArrayLike) -> FloatArray:
        t = np.asarray(t, dtype=float)
        out = np.zeros_like(t)
        for piece in self.pieces:
            out = out + piece(t)
        return out


Piece = tuple[Callable[[FloatArray], FloatArray], tuple[float, ...]]


def _piece(where: str, spec: Any) -> Piece:
    """A piece as (function of t, its breakpoints)."""
    if isinstance(spec, bool):
        raise SignalError(
            f"{where} = {spec!r} is invalid: must be a number (true/false is none) or a piece"
        )
    if isinstance(spec, int | float):
        c = _number(where, {"constant": spec}, "constant")
        return (lambda t: np.full_like(t, c)), ()
    if not isinstance(spec, dict) or len(spec) != 1:
        raise SignalError(
            f"{where} = {spec!r} is invalid: must be a number, or a piece is one of "
            "constant, step, ramp, sine, table"
            + (
                " (a string is not a number: write it without quotes)"
                if isinstance(spec, str)
                else ""
            )
        )
    ((kind, body),) = spec.items()
    w = f"{where}.{kind}"
    if kind == "constant":
        c = _number(where, spec, "constant")
        return (lambda t: np.full_like(t, c)), ()
    if kind == "step":
        d = _keys(w, body, {"time", "height"})
        t0, height = _number(w, d, "time"), _number(w, d, "height")
        return (lambda t: np.where(t >= t0, height, 0.0)), (t0,)
    if kind == "ramp":
        d = _keys(w, body, {"start", "duration", "height"})
        t0, dur, height = _number(w, d, "start"), _number(w, d, "duration"), _number(w, d, "height")
        if dur <= 0.0:
            raise SignalError(f"{w}: 'duration' = {dur!r} must be > 0")
        return (lambda t: height * np.clip((t - t0) / dur, 0.0, 1.0)), (t0, t0 + dur)
    if kind == "sine":
        d = _keys(w, body, {"amplitude", "period", "phase", "start"})
        amp, period = _number(w, d, "amplitude"), _number(w, d, "period")
        phase, t0 = _number(w, d, "phase", 0.0), _number(w, d, "start", 0.0)
        if period <= 0.0:
            raise SignalError(f"{w}: 'period' = {period!r} must be > 0")
        return (
            lambda t: np.where(t >= t0, amp * np.sin(2.0 * np.pi * (t - t0) / period + phase), 0.0)
        ), (t0,)
    if kind == "table":
        d = _keys(w, body, {"time", "value", "hold"})
        try:
            tt = np.asarray(d.get("time"), dtype=float)
            vv = np.asarray(d.get("value"), dtype=float)
        except (TypeError, ValueError) as e:
            raise SignalError(f"{w}: 'time' and 'value' must be lists of numbers") from e
        hold = d.get("hold", False)
        if tt.ndim != 1 or tt.shape != vv.shape or tt.size < 1:
            raise SignalError(f"{w}: 'time' and 'value' must be lists of the same length >= 1")
        if not (np.all(np.isfinite(tt)) and np.all(np.isfinite(vv))):
            raise SignalError(f"{w}: 'time' and 'value' must be finite")
        if np.any(np.diff(tt) <= 0.0):
            raise SignalError(f"{w}: 'time' must increase strictly")
        if not isinstance(hold, bool):
            raise SignalError(f"{w}: 'hold' = {hold!r} must be true or false")
        points = tuple(float(x) for x in tt)
        if hold:
            return (
                lambda t: vv[np.clip(np.searchsorted(tt, t, side="right") - 1, 0, None)]
            ), points
        return (lambda t: np.interp(t, tt, vv)), points
    raise SignalError(f"{where}: unknown piece '{kind}' (constant, step, ramp, sine, table)")


def parse(name: str, spec: Any, where: str | None = None) -> Signal:
    """The signal ``name`` from its TOML value (a number, a piece or a list of pieces);
    ``where``: the scene key it is written at, for errors (default ``inputs.<name>``)."""
    where = where or f"inputs.{name}"
    if isinstance(spec, list):
        if not spec:
            raise SignalError(f"{where}: an empty list is not a signal")
        pieces = [_piece(f"{where}[{i}]", s) for i, s in enumerate(spec)]
    else:
        pieces = [_piece(where, spec)]
    breaks = tuple(sorted({b for _, bs in pieces for b in bs}))
    return Signal(name, tuple(f for f, _ in pieces), breaks)


def held(values: FloatArray) -> FloatArray:
    """Inputs in effect over the step that ends at each grid point (zero-order hold).

    A master sets u(t_k) and steps from t_k to t_k+1, so the value acting on the step
    ending at t_k+1 is u(t_k); at t_0 it is u(t_0). ``values`` are u on the grid.
    """
    values = np.asarray(values, dtype=float)
    return np.concatenate([values[:1], values[:-1]])
