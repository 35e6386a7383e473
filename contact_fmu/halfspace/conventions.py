"""Mapping to CONTACT's conventions (Kalker's CONTACT, Vollebregt), for comparing runs.

quantity            here (Spector & Batra 1995, SI)       CONTACT
force, moment       the body's on the substrate (T, Mz),  on body 1, against the creepage
                    along the slip                        (Fx = -G c^2 C11 xi)
creepages xi, eta   rigid slip of the body / rolling      the same, body 1 over body 2 (-)
                    speed (-)
spin                phi = Omega_z/Vx (rad/m)              rad/mm
lengths             m                                     mm
forces, moments     N, N m                                N, N mm
stresses, moduli    Pa                                    N/mm^2 (MPa)

With the body as CONTACT's body 1, the creepages are the same numbers, the forces
change sign, the spin and the moments change units. The rolling direction: here +x
(Vx > 0, material entering the contact at x = +a); compare with CONTACT runs that roll
the same way (its rolling direction angle chi). ``tests/test_halfspace_conventions.py``
checks the mapping against Kalker's linear theory in CONTACT's units.
"""

from __future__ import annotations

from .._validate import finite

# m per mm
MM = 1e-3


def creepages_to_contact(xi: float, eta: float, phi: float) -> tuple[float, float, float]:
    """(xi, eta, phi in 1/m) -> CONTACT's (cksi, ceta, cphi in rad/mm)."""
    return finite("xi", xi), finite("eta", eta), finite("phi", phi) * MM


def creepages_from_contact(cksi: float, ceta: float, cphi: float) -> tuple[float, float, float]:
    """CONTACT's (cksi, ceta, cphi in rad/mm) -> (xi, eta, phi in 1/m)."""
    return finite("cksi", cksi), finite("ceta", ceta), finite("cphi", cphi) / MM


def forces_to_contact(Tx: float, Ty: float, Mz: float) -> tuple[float, float, float]:
    """(Tx, Ty in N, Mz in N m) on the substrate -> CONTACT's (Fx, Fy in N, Mz in N mm)
    on body 1 (the body)."""
    return -finite("Tx", Tx), -finite("Ty", Ty), -finite("Mz", Mz) / MM


def forces_from_contact(Fx: float, Fy: float, Mz: float) -> tuple[float, float, float]:
    """CONTACT's (Fx, Fy in N, Mz in N mm) on body 1 -> (Tx, Ty in N, Mz in N m) on the
    substrate."""
    return -finite("Fx", Fx), -finite("Fy", Fy), -finite("Mz", Mz) * MM


def length_to_contact(x: float) -> float:
    """m -> mm."""
    return finite("x", x) / MM


def modulus_to_contact(G: float) -> float:
    """Pa -> N/mm^2."""
    return finite("G", G) * MM * MM
