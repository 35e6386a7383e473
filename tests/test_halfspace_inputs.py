"""Bad arguments to the public calls of contact_fmu.halfspace answer InputError naming
the argument, never a TypeError from inside numpy, a NaN in the outputs or a
changed state. Randomised over wrong types and values with hypothesis."""

from __future__ import annotations

import math
import re
from functools import cache

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from contact_fmu import InputError
from contact_fmu.halfspace import (
    Fastsim,
    HalfSpaceContact,
    Hertz,
    Material,
    build_table,
    ellipse_patch,
    solve_rolling,
    wheel_on_rail,
)
from contact_fmu.halfspace.line import LineContact
from contact_fmu.halfspace.railway import STEEL
from contact_fmu.halfspace.transient import HalfSpaceField, TransientHalfSpaceBody

NOT_A_NUMBER = st.one_of(
    st.none(),
    st.text(max_size=3),
    st.booleans(),
    st.lists(st.floats(allow_nan=False), min_size=2, max_size=3),
    st.builds(object),
)
NOT_FINITE = st.sampled_from([math.nan, math.inf, -math.inf])
NOT_AN_OBJECT = st.one_of(NOT_A_NUMBER, st.floats(), st.integers())
BAD = {
    "finite": st.one_of(NOT_A_NUMBER, NOT_FINITE),
    "positive": st.one_of(NOT_A_NUMBER, NOT_FINITE, st.floats(max_value=0.0)),
    "count": st.one_of(NOT_A_NUMBER, NOT_FINITE, st.integers(max_value=7), st.floats(8.5, 99)),
    # a radius: inf is a flat surface, a negative one concave; 0 and NaN are not radii
    "radius": st.one_of(
        NOT_A_NUMBER.filter(lambda v: v is not True), st.just(0.0), st.just(math.nan)
    ),
    "material": NOT_AN_OBJECT,
    "callable": NOT_AN_OBJECT,
    "bool": st.one_of(st.none(), st.text(max_size=3), st.floats(), st.integers()),
    # scalars or arrays (forces broadcasts its inputs)
    "arraylike": st.one_of(
        st.none(),
        st.text(max_size=3),
        st.booleans(),
        st.builds(object),
        NOT_FINITE,
        st.lists(NOT_FINITE, min_size=2, max_size=2),
    ),
    "given": st.one_of(NOT_A_NUMBER.filter(lambda v: v is not None), NOT_FINITE),
    "array": st.one_of(
        st.text(max_size=3),
        st.builds(object),
        st.floats(),
        NOT_FINITE.map(lambda v: np.full((2, 16, 16), v)),
    ),  # fmt: skip
    "nodes": st.one_of(
        NOT_A_NUMBER,
        st.lists(st.integers(3, 9), min_size=0, max_size=2),
        st.tuples(st.integers(-3, 2), st.just(3), st.just(3)),
        st.tuples(st.just(3), st.sampled_from([4, 6]), st.just(3)),
    ),
}


@cache
def contact() -> HalfSpaceContact:
    return wheel_on_rail(n=16)


@cache
def field() -> HalfSpaceField:
    return HalfSpaceField(contact(), 16)


BASE = dict(P=1e5, Rx=0.46, Ry=math.inf, body=STEEL, substrate=STEEL, mu=0.3, Rsy=0.3, n=16)


def _hsc(**kw):
    return HalfSpaceContact(**{**BASE, **kw})


def _pressure(X, Y):
    return 1.0 + 0.0 * X


# (name of the argument in the error, kind of bad value, the call)
CASES = {
    "HalfSpaceContact.P": ("P", "positive", lambda v: _hsc(P=v)),
    "HalfSpaceContact.Ry": ("Ry", "radius", lambda v: _hsc(Ry=v)),
    "HalfSpaceContact.mu": ("mu", "positive", lambda v: _hsc(mu=v)),
    "HalfSpaceContact.kb": ("kb", "finite", lambda v: _hsc(kb=v)),
    "HalfSpaceContact.n": ("n", "count", lambda v: _hsc(n=v)),
    "HalfSpaceContact.n=(mx, v)": ("n", "count", lambda v: _hsc(n=(48, v))),
    "HalfSpaceContact.body": ("body", "material", lambda v: _hsc(body=v)),
    "HalfSpaceContact.coupling": ("coupling", "bool", lambda v: _hsc(coupling=v)),
    "from_ellipse.a1": (
        "a1",
        "positive",
        lambda v: HalfSpaceContact.from_ellipse(v, 1e-3, STEEL, STEEL, 0.3, P=1.0),
    ),  # fmt: skip
    "from_ellipse.delta": (
        "delta",
        "positive",
        lambda v: HalfSpaceContact.from_ellipse(1e-3, 1e-3, STEEL, STEEL, 0.3, delta=v),
    ),  # fmt: skip
    "from_curvatures.B": (
        "B",
        "positive",
        lambda v: HalfSpaceContact.from_curvatures(1.0, v, STEEL, STEEL, 0.3, 1.0),
    ),  # fmt: skip
    "solve.xi": ("xi", "finite", lambda v: contact().solve(v)),
    "solve.phi": ("phi", "finite", lambda v: contact().solve(1e-4, 0.0, v)),
    "solve.tau0": ("tau0", "array", lambda v: contact().solve(1e-4, tau0=v)),
    "solve.tol": ("tol", "positive", lambda v: contact().solve(1e-4, tol=v)),
    "traction.Vx": ("Vx", "finite", lambda v: contact().traction(0.0, 0.0, 0.0, v)),
    "forces.vy": ("vy", "arraylike", lambda v: contact().forces(0.0, v, 0.0, 1.0)),
    "onset.angle": ("angle", "finite", lambda v: contact().onset(v)),
    "with_load.P": ("P", "positive", lambda v: contact().with_load(v)),
    "creepages_for.Fx": ("Fx", "finite", lambda v: contact().creepages_for(v, 0.0)),
    "creepages_for.phi": ("phi", "finite", lambda v: contact().creepages_for(1.0, 0.0, v)),
    "Hertz.Estar": ("Estar", "positive", lambda v: Hertz(1.0, 1.0, 1.0, v)),
    "Material.nu": ("nu", "finite", lambda v: Material(1.0, v)),
    "wheel_on_rail.n": ("n", "count", lambda v: wheel_on_rail(n=v)),
    "ellipse_patch.a2": (
        "a2",
        "positive",
        lambda v: ellipse_patch(1.0, v, 16, _pressure, 0.3, 1.0, 0.3),
    ),  # fmt: skip
    "ellipse_patch.pressure": (
        "pressure",
        "callable",
        lambda v: ellipse_patch(1.0, 1.0, 16, v, 0.3, 1.0, 0.3),
    ),  # fmt: skip
    "solve_rolling.eta": ("eta", "finite", lambda v: solve_rolling(contact().patch, 0.0, v)),
    "build_table.nodes": ("nodes", "nodes", lambda v: build_table(contact(), nodes=v)),
    "build_table.xi_max": (
        "xi_max",
        "given",
        lambda v: build_table(contact(), xi_max=v, nodes=(3, 3, 3)),
    ),  # fmt: skip
    "field.roll.h": ("h", "positive", lambda v: field().roll(v, 0.0, 0.0, 1.0)),
    "field.roll.vx": ("vx", "finite", lambda v: field().roll(1.0, v, 0.0, 1e-4)),
    "field.set_shift": ("delta_x", "finite", lambda v: field().set_shift(v)),
    "field.shift_for_force": ("Fx", "finite", lambda v: field().shift_for_force(v)),
    "field.set_load": ("P", "positive", lambda v: field().set_load(v)),
    "HalfSpaceField.n": ("n", "count", lambda v: HalfSpaceField(contact(), v)),
    "TransientHalfSpaceBody.body": (
        "body",
        "material",
        lambda v: TransientHalfSpaceBody(contact(), v),
    ),  # fmt: skip
    "LineContact.N": ("N", "positive", lambda v: LineContact(v, 0.1, STEEL, STEEL, 0.3)),
    "LineContact.n": ("n", "count", lambda v: LineContact(1e5, 0.1, STEEL, STEEL, 0.3, n=v)),
    "LineContact.solve": (
        "xi",
        "finite",
        lambda v: LineContact(1e5, 0.1, STEEL, STEEL, 0.3).solve(v),
    ),  # fmt: skip
}


@pytest.mark.parametrize("case", sorted(CASES))
@settings(max_examples=15, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(data=st.data())
def test_bad_argument_answers_input_error_naming_it(case, data):
    name, kind, call = CASES[case]
    value = data.draw(BAD[kind])
    with pytest.raises(InputError) as err:
        call(value)
    assert err.value.name.split(".")[0] == name or name in err.value.name, err.value


def test_a_refused_step_leaves_the_field_unchanged():
    """No corrupted state: the traction field after refused calls is the one before."""
    f = HalfSpaceField(contact(), 16)
    f.roll(1e-4, 1e-4 * 5.0, 0.0, 5.0)
    before = f.tau.copy()
    for bad in (None, math.nan, "1"):
        with pytest.raises(InputError):
            f.roll(1e-4, bad, 0.0, 5.0)
        with pytest.raises(InputError):
            f.set_shift(bad)
    assert np.array_equal(f.tau, before)


def test_the_issue_examples():
    """Two calls that once raised a raw TypeError."""
    with pytest.raises(InputError, match="n = "):
        _hsc(n=(48, 44.0))
    assert _hsc(n=(48, 44)).patch.grid.shape == (44, 48)
    with pytest.raises(InputError, match="vx = None"):
        field().roll(1.0, None, 0.0, 1e-4)


@pytest.mark.parametrize(
    "make, name",
    [
        (lambda: Material(E=5e-324, nu=0.28), "E"),
        (lambda: Material(E=1.7e308, nu=0.28), "E"),
        (lambda: Material(G=1e-300, nu=0.28), "G"),
        (lambda: HalfSpaceContact.from_ellipse(6e-3, 6e-10, STEEL, STEEL, 0.3, P=1e5), "a1/a2"),
        (lambda: HalfSpaceContact.from_curvatures(1.0, 1e20, STEEL, STEEL, 0.3, 1e5), "A/B"),
        (lambda: HalfSpaceContact.from_ellipse(6e-3, 4e-3, STEEL, STEEL, 1e300, P=1e5), "mu"),
        (lambda: HalfSpaceContact.from_ellipse(6e-3, 4e-3, STEEL, STEEL, 5e-324, P=1e5), "mu"),
        (lambda: HalfSpaceContact(1e-300, 0.46, math.inf, STEEL, STEEL, 0.3, Rsy=0.3), "a1"),
        (lambda: Fastsim(6e-3, 4e-3, 8e10, 0.28, 1e300, P=1e5), "mu"),
        (lambda: Fastsim(1e-300, 4e-3, 8e10, 0.28, 0.3, P=1e5), "a1"),
        (lambda: LineContact(N=1e5, R=0.06, body=STEEL, substrate=STEEL, mu=1e300), "mu"),
        (lambda: LineContact(N=1e-300, R=0.06, body=STEEL, substrate=STEEL, mu=0.3), "a"),
        (
            lambda: HalfSpaceContact.from_ellipse(6e-3, 4e-3, STEEL, STEEL, 0.3, P=1e5, kb=1e300),
            "kb + ks",
        ),
    ],
)
def test_scales_beyond_the_solvers_range_are_refused_by_name(make, name):
    """Inputs that give a modulus, a semi-axis, a peak pressure or a traction bound mu p0
    outside hertz.SCALE_MIN .. SCALE_MAX (1e-100 .. 1e100, SI), layers whose displacement
    under p0 exceeds SCALE_MAX m, or an ellipse beyond a semi-axis ratio of 1e6:
    InputError naming the input or the scale (before: a
    ZeroDivisionError, scipy's ValueError from the eccentricity's bracket, NaN forces,
    or a Newton iteration stalled in subnormal tractions)."""
    with pytest.raises(InputError, match=rf"^{re.escape(name)} = "):
        make()
