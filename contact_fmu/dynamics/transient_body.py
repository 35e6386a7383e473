"""What the two transient rolling bodies share: a body whose contact is a traction
field carried as state (thin_layer_field.py: thin layers; halfspace/transient.py: the
half-space).

A subclass holds ``field`` (its ``dx``, ``set_shift``, ``summary``, ``traction_field``
and ``arrays``), ``out`` (the ContactOutputs of the field now) and ``law`` (the contact
law at the present load: a1, a2, p0), and defines ``_outputs_now``.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from .._validate import positive
from ..laws.thin_layer import FloatArray, TractionField
from .body_state import BodyState, ContactOutputs
from .kinematics import ROLLING, SLIDING, creepage


class TransientBody(BodyState):
    """The rolling body of Eqs. (8)-(11) on a traction field that is state: its step,
    the cell it rolls per step, and its outputs (RollingBody's keys, the forces,
    adhesion and regime from the field, and the field's summary)."""

    field: Any
    out: ContactOutputs

    @property
    def law(self) -> Any:
        raise NotImplementedError

    def _outputs_now(self) -> ContactOutputs:
        raise NotImplementedError

    def cell_time(self) -> float:
        """dx/|Vx| (s): the step that rolls one grid cell (inf at Vx = 0)."""
        return self.field.dx / abs(self.Vx) if self.Vx != 0.0 else math.inf

    def substeps_for(self, h: float, cells: float = 1.0) -> int:
        """Substeps that keep each step within ``cells`` grid cells rolled at the
        present speed: a suggestion for accuracy (any step is stable)."""
        h = positive("h", h)
        cells = positive("cells", cells)
        return max(1, math.ceil(h * abs(self.Vx) / (cells * self.field.dx) - 1e-9))

    def set_shift(self, delta_x: float, delta_y: float = 0.0) -> None:
        """Field after a static tangential shift (m) at Vx = 0 (Cattaneo): see the
        field's ``set_shift``."""
        self.field.set_shift(delta_x, delta_y)
        self.out = self._outputs_now()

    def outputs(self) -> dict[str, float]:
        """The keys of RollingBody.outputs() (from the field where they describe it:
        forces, adhesion, regime) and summary quantities of the field: slip-area
        centroid (m) and peak traction (Pa)."""
        s = self.field.summary()
        law = self.law
        o = self.kinematics()
        o.update(
            Tx=self.out.Tx,
            Ty=self.out.Ty,
            Mz=self.out.Mz,
            xi_x=creepage(self.vx, self.Vx),
            xi_y=creepage(self.vy, self.Vx),
            xi_sp=creepage(self.Omega_z, self.Vx),
            a1=law.a1,
            a2=law.a2,
            p0=law.p0,
            adhesion=s["adhesion"],
            regime=SLIDING if self.out.sliding else ROLLING,
        )
        o.update({k: v for k, v in s.items() if k != "adhesion"})
        return o

    def traction_field(self) -> TractionField:
        """The traction field at the current time (see the field's ``traction_field``)."""
        return self.field.traction_field()

    def field_arrays(self) -> dict[str, FloatArray]:
        """The field at the current time as arrays, plus t (s): for ``numpy.savez``."""
        a = self.field.arrays()
        a["t"] = np.array(self.t)
        return a
