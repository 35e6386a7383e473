"""Input checks shared by the numerical layer: one clear error naming the variable."""

from __future__ import annotations

import math

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


def finite(name: str, value: float) -> float:
    value = float(value)
    if not math.isfinite(value):
        raise InputError(name, value, "finite")
    return value


def positive(name: str, value: float) -> float:
    value = finite(name, value)
    if value <= 0.0:
        raise InputError(name, value, "> 0")
    return value


def nonnegative(name: str, value: float) -> float:
    value = finite(name, value)
    if value < 0.0:
        raise InputError(name, value, ">= 0")
    return value


def count(name: str, n: object, least: int) -> int:
    """An integer >= least (grid sizes and the like; bools are refused)."""
    if isinstance(n, bool) or not isinstance(n, int | np.integer) or n < least:
        raise InputError(name, n, f"an integer >= {least}")
    return int(n)
