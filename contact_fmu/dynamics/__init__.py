"""The rolling body: its equations of motion, Eqs. (8)-(11), integrated with a contact law.

- ``body.py``: the body's parameters and loads (``Body``, ``Lateral``, ``Loads``),
  Eqs. (8)-(11), (20)-(23), (27);
- ``kinematics.py``: rigid slip (Eq. 3), creepages, the contact outputs;
- ``integrator.py``: ``RollingBody``, the body on a steady law (Lobatto IIIC / SDIRK2,
  quasistationary Eqs. 26-30); ``body_state.py``: the state and outputs it shares with
  the transient bodies; ``solvers.py``: the stage solves (Newton, bracketed Newton);
- ``transient_body.py``: ``TransientBody``, the body on a traction field carried as
  state; ``thin_layer_field.py``: the thin-layer transient field (``LayerField``, Eq.
  15 with its time derivative) and the body on it (``TransientRollingBody``); the
  half-space's is ``contact_fmu.halfspace.transient``;
- ``simulate.py``: ``simulate``, a trajectory under a load history;
  ``coupling.py``: the slip relaxation time of an explicit co-simulation.

The laws come through ``contact_fmu.laws.protocol.ContactLaw``; nothing here imports an
FMU.
"""

from .body import ROLLING_STRAIGHT, Body, Lateral, Loads, load_utilisation

__all__ = ["ROLLING_STRAIGHT", "Body", "Lateral", "Loads", "load_utilisation"]
