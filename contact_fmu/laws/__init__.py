"""Contact laws: the forces of a contact from its creepages and spin, with no state.

- ``protocol.py``: ``ContactLaw``, what the rolling body, the FMU and the outputs need of
  a law;
- ``thin_layer.py``: the thin-layer law of Section 4 (``LayerContact``, Eqs. 31-43) and
  its traction field (``TractionField``).

The half-space law (Boussinesq-Cerruti, FASTSIM, creep-force tables) is the package
``contact_fmu.halfspace``, which also holds its transient field; the thin-layer transient
field is ``contact_fmu.dynamics.thin_layer_field`` (both build on the rolling body).
"""
