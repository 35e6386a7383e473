"""Input checks shared by the numerical layer: one clear error naming the variable.

Every public call of the numerical layer checks its arguments with these helpers, so
that a wrong type (None, a string, a list) answers InputError naming the argument just
as a wrong value does, never a TypeError from deep inside numpy.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np


class InputError(ValueError):
    """A parameter or input is outside its admissible range.

    ``name`` and ``value`` identify the offending variable so that callers (the
    FMU adapter in particular) can report it without parsing the message.
    """

    def __init__(self, name: str, value: object, requirement: str) -> None:
        self.name = name
        self.value = value
        super().__init__(f"{name} = {value!r} is invalid: must be {requirement}")


def real(name: str, value: object) -> float:
    """A real number (bools, strings and None are refused: they convert by accident)."""
    if isinstance(value, str | bytes | bool | np.bool_) or value is None:
        raise InputError(name, value, "a real number")
    try:
        return float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError, OverflowError):
        raise InputError(name, value, "a real number") from None


def finite(name: str, value: object) -> float:
    value = real(name, value)
    if not math.isfinite(value):
        raise InputError(name, value, "finite")
    return value


def positive(name: str, value: object) -> float:
    value = finite(name, value)
    if value <= 0.0:
        raise InputError(name, value, "> 0")
    return value


def nonnegative(name: str, value: object) -> float:
    value = finite(name, value)
    if value < 0.0:
        raise InputError(name, value, ">= 0")
    return value


def count(name: str, n: object, least: int) -> int:
    """An integer >= least (grid sizes and the like; bools are refused)."""
    if isinstance(n, bool) or not isinstance(n, int | np.integer) or n < least:
        raise InputError(name, n, f"an integer >= {least}")
    return int(n)


def counts(name: str, n: object, least: int) -> tuple[int, int]:
    """A pair of integers >= least, e.g. elements (mx, my) of a grid."""
    if isinstance(n, str | bytes) or not isinstance(n, Sequence) or len(n) != 2:
        raise InputError(name, n, f"two integers >= {least}")
    try:
        return count(name, n[0], least), count(name, n[1], least)
    except InputError:
        raise InputError(name, n, f"two integers >= {least}") from None


def flag(name: str, value: object) -> bool:
    """A bool (numpy's included); 0/1 and strings are refused."""
    if not isinstance(value, bool | np.bool_):
        raise InputError(name, value, "True or False")
    return bool(value)


def instance(name: str, value: object, kind: type, what: str) -> object:
    """An instance of ``kind`` (``what`` names it in the message)."""
    if not isinstance(value, kind):
        raise InputError(name, type(value).__name__, what)
    return value


def one_of(name: str, value: object, options: Sequence[object]) -> object:
    """One of the admissible ``options``."""
    if isinstance(value, list | dict | set) or value not in options:
        raise InputError(name, value, "one of " + ", ".join(repr(o) for o in options))
    return value


def array(name: str, value: object, shape: tuple[int, ...] | None = None) -> np.ndarray:
    """A finite float array (of ``shape`` when given): reals, lists, numpy arrays."""
    if isinstance(value, str | bytes | bool | np.bool_) or value is None:
        raise InputError(name, value, "an array of finite reals")
    try:
        out = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise InputError(name, type(value).__name__, "an array of finite reals") from None
    if np.asarray(value).dtype == bool:
        raise InputError(name, value, "an array of finite reals (not bools)")
    if shape is not None and out.shape != tuple(shape):
        raise InputError(f"{name}.shape", out.shape, f"{tuple(shape)}")
    if not np.all(np.isfinite(out)):
        raise InputError(name, "non-finite values", "finite")
    return out
