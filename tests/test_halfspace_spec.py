"""The half-space law's declaration as data (TableSpec) and its run-time law (TableLaw).

Small tables on coarse solver grids (8 x 8 elements): these tests check the rules
(similarity in mu, the load range of layered tables, matching a table to its
declaration), not the accuracy of the solver, which tests/test_halfspace_*.py do.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from contact_fmu import InputError
from contact_fmu.halfspace.spec import TableLaw, TableSpec

STEEL = {"E": 210.0e9, "nu": 0.28}
BASE = {
    "body": {"Rx": 0.46, "Ry": math.inf, **STEEL},
    "substrate": {"Rx": "inf", "Ry": 0.30, **STEEL},
    "mu": 0.3,
    "loads": [100.0e3],
    "grid": 8,
    "xi_max": 0.014,
    "eta_max": 0.014,
    "phi_max": 1.5,
    "nodes": [7, 3, 3],
}
# Layers with 1/20 of the half-spaces' own tangential compliance at this contact
# (c/G ~ 7.6e-14 m/Pa): the load similarity no longer holds. The box reaches 0.8 xi_ref,
# so that the nodes next to zero lie in partial slip (full slip sets in near 0.5 xi_ref).
LAYERED = {**BASE, "kb": 2e-15, "ks": 2e-15, "loads": [80.0e3, 120.0e3], "xi_max": 0.007,
           "eta_max": 0.007}  # fmt: skip
# Newton tolerance of the table's solves is 1e-6 of max mu p, the direct solves' 1e-7:
# forces agree to about 1e-6 of mu P; 1e-5 leaves room for rounding.
SOLVER_RTOL = 1e-5


@pytest.fixture(scope="module")
def layered() -> tuple[TableSpec, TableLaw]:
    spec = TableSpec.from_dict(LAYERED)
    table = spec.build()
    return spec, spec.law(table.data)


def test_spec_round_trips_through_plain_data_with_inf_as_a_string():
    spec = TableSpec.from_dict(BASE)
    d = spec.to_dict()
    assert d["body"]["Ry"] == "inf" and d["substrate"]["Rx"] == "inf"
    assert TableSpec.from_dict(d) == spec and TableSpec.from_dict(d).key == spec.key
    assert spec.key != TableSpec.from_dict({**BASE, "grid": 10}).key
    c = spec.contact()
    assert (c.Rx, c.Ry, c.Rsx, c.Rsy, c.P, c.mu, c.n) == (0.46, math.inf, math.inf, 0.3,
                                                          100e3, 0.3, 8)  # fmt: skip
    assert not c.coupling  # as the table is built (Kalker's quasi-identity)


@pytest.mark.parametrize(
    ("edit", "name", "fragment"),
    [
        ({"colour": "red"}, "halfspace", "known keys"),
        ({"grid": None}, "halfspace", "required keys"),
        ({"body": {"Rx": 0.46, "Ry": math.inf, "E": 210e9}}, "halfspace.body", "missing ['nu']"),
        ({"body": {"Rx": -0.46, "Ry": math.inf, **STEEL}}, "halfspace.body.Rx", "> 0"),
        ({"substrate": {"Rx": "inf", "Ry": 0.3, "E": 210e9, "nu": 0.6}}, "halfspace.substrate.nu",
         "in (-1, 0.5]"),
        ({"body": {"Rx": "inf", "Ry": "inf", **STEEL}, "substrate": {"Rx": "inf", "Ry": "inf",
          **STEEL}}, "halfspace.body/substrate", "closed contact ellipse"),
        ({"kb": -1e-13}, "halfspace.kb", ">= 0"),
        ({"kb": 1e-13}, "halfspace.loads", "at least two load nodes"),
        ({"loads": [1e5, 1e5]}, "halfspace.loads", "distinct"),
        ({"nodes": [7, 4, 3]}, "halfspace.nodes", "odd"),
        ({"grid": 4}, "halfspace.grid", ">= 8"),
        ({"xi_max": 0.0}, "halfspace.xi_max", "> 0"),
        ({"mu": "high"}, "halfspace.mu", "a number"),
    ],
)  # fmt: skip
def test_bad_declaration_is_refused_naming_the_key(edit, name, fragment):
    d = {**BASE, **edit}
    d = {k: v for k, v in d.items() if v is not None}
    with pytest.raises(InputError) as e:
        TableSpec.from_dict(d)
    assert e.value.name == name and fragment in str(e.value), str(e.value)


def test_table_does_not_depend_on_mu_even_with_layers(layered):
    """The discrete steady-rolling problem is homogeneous of degree one in (traction,
    creepages, mu p), so the table built at mu = 0.3 evaluated at mu = 0.2 equals direct
    solves at mu = 0.2: checked at table nodes (no interpolation error) in partial and
    full slip, at a load node."""
    spec, law = layered
    law2 = law.with_mu(0.2)
    assert law2.mu == 0.2 and law2.data is law.data and law.mu == 0.3
    direct = spec.contact(mu=0.2)
    muP = 0.2 * direct.P
    ax = law.data.axes
    partial = 0
    for i, j in ((4, 1), (5, 1), (6, 1), (4, 2)):  # x1 > 0; x2 = 0 or the last node
        xi, eta = ax[0][i] * law2.xi_ref, ax[1][j] * law2.xi_ref
        s = direct.solve(xi, eta)
        T = law2.forces(xi, eta, 0.0, 1.0)
        if math.hypot(s.Tx, s.Ty) < 0.97 * muP:  # below the table's radial saturation
            partial += 1
            assert abs(T[0] - s.Tx) <= SOLVER_RTOL * muP and abs(T[1] - s.Ty) <= SOLVER_RTOL * muP
        assert law2.adhesion_fraction(xi, eta, 1.0) == pytest.approx(s.adhesion_fraction,
                                                                     abs=1e-9)  # fmt: skip
    assert partial >= 2  # the force check did run in partial slip
    # the onset of full slip and the creepage unit scale with mu, the ellipse does not
    assert law2.creep_full_slip == pytest.approx(law.creep_full_slip * 2 / 3, rel=1e-12)
    assert (law2.a1, law2.a2, law2.p0) == (law.a1, law.a2, law.p0)


def test_layered_table_refuses_loads_outside_its_nodes(layered):
    _, law = layered
    assert law.load_range == (80e3, 120e3)
    assert law.with_load(100e3).P == 100e3
    for P in (79e3, 121e3):
        with pytest.raises(InputError) as e:
            law.with_load(P)
        assert e.value.name == "P" and "load range [80000, 120000] N" in str(e.value)
    with pytest.raises(InputError, match="mu = -0.1 is invalid"):
        law.with_mu(-0.1)


def test_table_without_layers_takes_any_load_by_similarity():
    spec = TableSpec.from_dict({**BASE, "nodes": [5, 3, 3]})
    law = spec.law(spec.build().data)
    assert law.load_range == (0.0, math.inf)
    small, large = law.with_load(1e3), law.with_load(1e6)
    # normalised forces are the same at the same normalised creepage (Kalker's similarity)
    for lw in (small, large):
        Tx = lw.forces(0.2 * lw.xi_ref, 0.0, 0.0, 1.0)[0]
        assert Tx / (lw.mu * lw.P) == pytest.approx(
            law.forces(0.2 * law.xi_ref, 0.0, 0.0, 1.0)[0] / (law.mu * law.P), rel=1e-12
        )


def test_table_file_is_matched_to_its_declaration(layered, tmp_path):
    spec, law = layered
    path = law.save(tmp_path / "t.npz")
    loaded = spec.load_law(path, P=100e3, mu=0.25)
    assert (loaded.P, loaded.mu) == (100e3, 0.25)
    assert np.array_equal(loaded.data.values, law.data.values)
    other = TableSpec.from_dict({**LAYERED, "grid": 10})
    with pytest.raises(InputError, match="built for this FMU's contact"):
        other.load_law(path)
    with pytest.raises(InputError, match="an existing file"):
        spec.load_law(tmp_path / "missing.npz")
