"""The interface between the FMU adapter and a model (body, force element, rigid body).

A model is built from the FMU's parameters and current inputs, advanced over a
communication step with the inputs held (zero-order hold), and saved/restored whole.
Errors are raised as ``InputError`` (or the stepper's own exceptions); the adapter
turns them into fmi2Discard with a logged message and restores the snapshot it took.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, Protocol


class Model(Protocol):
    # True when outputs depend directly on inputs (recomputed when an input changes).
    feedthrough: bool

    def step(self, h: float, inputs: Mapping[str, float]) -> str | None:
        """Advance by h (s) with ``inputs`` held; returns a note to log, or None."""
        ...

    def evaluate(self, inputs: Mapping[str, float]) -> None:
        """Recompute the outputs at the current time for new inputs (feedthrough only)."""
        ...

    def outputs(self) -> dict[str, float]: ...

    def tune(self, params: Mapping[str, Any]) -> None:
        """New values of tunable parameters (``variables.Var.tunable``: mu), between
        steps; only models whose FMUs have such parameters implement it."""
        ...

    def snapshot(self) -> Any: ...

    def restore(self, snap: Any) -> None: ...
