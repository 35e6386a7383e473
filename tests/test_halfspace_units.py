"""Inputs as CONTACT users give them: Material from (G, nu) or (E, nu), warnings for
values that look like another unit (N/mm^2, mm, rad/mm), InputError for every bad
input, and every public class exported from contact_fmu.halfspace."""

from __future__ import annotations

import importlib
import inspect
import warnings

import pytest

import contact_fmu.halfspace as hs
from contact_fmu import InputError
from contact_fmu.halfspace import HalfSpaceContact, Material, UnitWarning
from contact_fmu.halfspace import transient as tr
from contact_fmu.halfspace.railway import STEEL, wheel_on_rail


def test_material_from_shear_modulus_or_young():
    """Material(G=..., nu=...) is the material with E = 2 G (1 + nu) (isotropic
    elasticity): its G comes back to 1e-15, and it equals Material(E, nu) given
    positionally or by keyword (the same dataclass fields)."""
    m = Material(G=82e9, nu=0.28)
    assert m.G == pytest.approx(82e9, rel=1e-15)
    assert m.E == pytest.approx(2 * 82e9 * 1.28, rel=1e-15)
    assert Material(E=m.E, nu=0.28) == m == Material(m.E, 0.28)
    for kw, name in (
        ({"E": 210e9, "G": 80e9, "nu": 0.3}, "E, G"),
        ({"nu": 0.3}, "E, G"),
        ({"E": 210e9}, "nu"),
        ({"G": -1.0, "nu": 0.3}, "G"),
        ({"G": 80e9, "nu": 0.6}, "nu"),
        ({"G": "80e9", "nu": 0.3}, "G"),
    ):
        with pytest.raises(InputError) as err:
            Material(**kw)
        assert err.value.name == name


@pytest.mark.parametrize(
    "call",
    [
        lambda cu: Material(210e3, 0.3, check_units=cu),  # steel's E in N/mm^2
        lambda cu: Material(G=80e3, nu=0.3, check_units=cu),
        # semi-axes of 6 and 4 mm given as metres
        lambda cu: HalfSpaceContact.from_ellipse(
            6.0, 4.0, STEEL, STEEL, 0.3, P=1e5, check_units=cu
        ),
        # a tread's spin of 0.5 1/m given in CONTACT's rad/mm (5e-4)
        lambda cu: wheel_on_rail(n=12).solve(1e-4, 0.0, 5e-4, check_units=cu),
        lambda cu: wheel_on_rail(n=12).creepages_for(1e3, 0.0, 5e-4, check_units=cu),
    ],
)
def test_values_that_look_like_another_unit_warn(call):
    """A modulus below 1 MPa, a semi-axis above 0.1 m and a spin creepage |phi| c
    below 1e-5 warn (UnitWarning naming the value and the unit it looks like); the
    keyword check_units=False silences the warning, and the call goes on either way."""
    with pytest.warns(UnitWarning, match="looks like"):
        call(True)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        call(False)


def test_plausible_values_do_not_warn():
    """SI values of a wheel on rail (E = 210 GPa, semi-axes of mm, spin 0.5 1/m, no
    spin) raise no warning."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        Material(210e9, 0.28)
        Material(G=1.2e6, nu=0.49)  # rubber, above 1 MPa
        c = HalfSpaceContact.from_ellipse(6e-3, 4e-3, STEEL, STEEL, 0.3, P=1e5, n=12)
        c.solve(1e-4, 0.0, 0.5)
        c.solve(1e-4)


def test_shift_for_force_out_of_reach_answers_input_error(monkeypatch):
    """A force the static shift does not reach within its tolerance answers InputError
    naming (Fx, Fy) with the closest force, not RuntimeError (made to happen here by a
    tolerance of zero)."""
    m = Material(2 * 1.3 * 80e9, 0.3)
    c = HalfSpaceContact.from_ellipse(1e-3, 1e-3, m, m, 0.3, P=1000.0)
    f = tr.HalfSpaceField(c, 16)
    monkeypatch.setattr(tr, "SHIFT_FORCE_TOL", -1.0)
    with pytest.raises(InputError, match="closest") as err:
        f.shift_for_force(0.5 * c.mu * c.P)
    assert err.value.name == "Fx, Fy"


def test_every_public_class_is_exported():
    """Every public class defined in the half-space modules, and the conventions
    module, is an attribute of contact_fmu.halfspace listed in __all__."""
    names = set(hs.__all__)
    assert "conventions" in names and hs.conventions.creepages_to_contact
    for mod in ("contact", "hertz", "line", "normal", "rolling", "spec", "table", "transient"):
        m = importlib.import_module(f"contact_fmu.halfspace.{mod}")
        for name, obj in vars(m).items():
            if inspect.isclass(obj) and obj.__module__ == m.__name__ and name[0] != "_":
                assert name in names, f"{mod}.{name}"
                assert getattr(hs, name) is obj
