"""The physical ranges of the body's speeds and rates (the declared ranges of their
initial values, variables.SPEED_MAX and RATE_MAX), checked on a state: every step of the
body and rigid_body modes, and their initial state. Kept apart from body_model so that a
rigid_body FMU carries no law or integrator for it; stepper.c's range table (CF_SPEED_MAX,
CF_RATE_MAX) and instance.c's messages are the C side, in the same words."""

from __future__ import annotations

from collections.abc import Mapping

from .._validate import InputError
from . import messages as words
from .variables import RATE_MAX, SPEED_MAX


def within_range(out: Mapping[str, float], start: bool = False) -> None:
    """InputError where a step took a speed or rate beyond its physical range (the
    declared range of its initial value): there the (Vx, vx) state no longer resolves
    Omega_y to one step's change (docs/reliability.md); the adapter discards the step.
    ``start``: ``out`` is the initial state, named Vx0, Omega_y0, ...: every step from it
    would be discarded, so the model refuses to start (exitInitializationMode)."""
    for name, bound in (("Vx", SPEED_MAX), ("Vy", SPEED_MAX), ("Omega_y", RATE_MAX),
                        ("Omega_z", RATE_MAX)):  # fmt: skip
        value = out.get(name, 0.0)
        if not abs(value) <= bound:
            # the initial state can be beyond: Rx, not range-checked against the speeds,
            # is free to be small
            why = words.RANGE_START() if start else words.RANGE_STEP()
            raise InputError(
                name + "0" if start else name, value, words.WITHIN_RANGE(bound=bound, why=why)
            )
