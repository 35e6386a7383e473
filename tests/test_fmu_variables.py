"""The variable declarations and model configurations of the FMU (pure Python, fast)."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from contact_fmu import InputError
from contact_fmu import examples as ex
from contact_fmu.fmu import variables as fv
from contact_fmu.fmu.config import ModelConfig

LATERAL = {
    "Vy",
    "Omega_z",
    "Fy_ex",
    "Mz_ex",
    "Ty",
    "Mz",
    "vy",
    "xi_y",
    "xi_sp",
    "Iz",
    "Vy0",
    "Omega_z0",
    "vy_ratio",
    "spin_ratio",
}


def body(**kw) -> ModelConfig:
    base = dict(name="t", mode="body", inputs=("P", "Fx_ex", "My_ex"), outputs=("Tx",))
    base.update(kw)
    return ModelConfig(**base)


def test_each_variable_is_declared_once_with_a_defined_unit():
    names = [v.name for v in fv.VARIABLES]
    assert len(names) == len(set(names))
    for v in fv.VARIABLES:
        assert v.causality and set(v.causality) <= set(fv.MODES), v.name
        if v.type == "Real":
            assert v.unit in fv.UNITS, v.name
        else:
            assert v.unit is None, v.name
        assert v.description, v.name


def test_defaults_are_the_parameter_set_of_the_papers_figures():
    c = ex.contact()
    d = {v.name: v.start for v in fv.VARIABLES}
    for name in ("mu", "Rx", "Ry", "k1", "k2", "kb", "ks", "P"):
        assert d[name] == getattr(c, name), name
    assert d["M"] == ex.M
    assert d["Iy"] == pytest.approx(ex.M * ex.Rx**2 / 3.0, rel=1e-15)  # eta = 3
    assert d["Vx0"] == ex.speed_unit()
    assert d["vx0"] == 0.0  # pure rolling


def test_var_check_names_the_requirement():
    mu, P, k1 = fv.BY_NAME["mu"], fv.BY_NAME["P"], fv.BY_NAME["k1"]
    assert mu.check(0.3) is None
    assert mu.check(0.0) == f">= {fv.MU_MIN:g}" and mu.check(fv.MU_MIN) is None
    assert mu.check(math.nan) == "finite"
    assert P.check(math.inf) == "finite"
    assert P.check(0.0) is None  # lift-off
    assert P.check(-1.0) == ">= 0 (lift-off, no contact, is P = 0)"
    assert k1.check(0.0) is None and k1.check(-1e-13) == ">= 0"
    assert fv.BY_NAME["method"].check("full") is None


def test_straight_rolling_body_has_no_lateral_variables():
    """Fig. 13 rolls straight (vy = 0, no spin): no lateral degree of freedom is declared."""
    names = {v.name for v in body().variables}
    assert not names & LATERAL
    assert {"mu", "Rx", "M", "Iy", "Vx0", "vx0", "h_max", "P", "Tx"} <= names


def test_full_body_fmu_declares_every_body_variable():
    full = ModelConfig.full("body")
    names = {v.name for v in full.variables}
    body_vars = {v.name for v in fv.VARIABLES if "body" in v.causality}
    # held-ratio parameters belong to the ratio variants; the full FMU integrates Eqs. (10)-(11);
    # the traction field's variables belong to phase "transient"
    field = {v.name for v in fv.VARIABLES if v.needs == "transient"}
    assert field == {"nx", "ny", "cells_per_step", "field_file", "field_times",
                     "slip_centroid_x", "slip_centroid_y", "tau_peak"}  # fmt: skip
    assert names == body_vars - {"vy_ratio", "spin_ratio"} - field
    assert full.methods == ("full", "quasistationary") and "method" in names


def test_held_lateral_ratio_declares_the_ratio_not_eq10():
    names = {v.name for v in body(vy="ratio", outputs=("Tx", "Ty", "vy")).variables}
    assert {"vy_ratio", "Ty", "vy"} <= names
    assert not names & {"Fy_ex", "Vy0", "Iz", "Omega_z0", "spin_ratio"}


def test_contact_outputs_declare_their_direct_dependencies():
    cfg = ModelConfig.full("contact")
    inputs = set(cfg.inputs)
    assert inputs == {"P", "Vx", "Vy", "Omega_y", "Omega_z"}
    for v in cfg.variables:
        if v.causality["contact"] == fv.OUTPUT:
            assert v.feedthrough and set(v.feedthrough) <= inputs, v.name


@pytest.mark.parametrize(
    ("kw", "name", "fragment"),
    [
        ({"contact_law": "halfspace"}, "halfspace", "required keys of the table"),
        ({"law_spec": {"grid": 16}}, "halfspace", 'only with contact_law = "halfspace"'),
        ({"phase": "unsteady"}, "phase", "one of ('steady', 'transient')"),
        ({"phase": "transient", "contact_law": "halfspace"}, "halfspace", "required keys"),
        ({"phase": "transient", "methods": ("quasistationary",)}, "method", "left out"),
        ({"contact_law": "hertz"}, "contact_law", "one of"),
        ({"methods": ("implicit",)}, "method", "one of"),
        ({"outputs": ("Vy",)}, "outputs", "one of"),  # no lateral dof without vy
        ({"inputs": ("Fx_ex",)}, "inputs", "to include P"),
        ({"starts": {"mu": -0.3}}, "mu", f">= {fv.MU_MIN:g}"),
        ({"starts": {"Iz": 1e-3}}, "Iz", "a variable of this body-mode model"),
    ],
)
def test_config_refuses_what_it_cannot_build_naming_the_key(kw, name, fragment):
    with pytest.raises(InputError) as e:
        body(**kw)
    assert e.value.name == name
    assert fragment in str(e.value)


def test_config_round_trips_through_plain_data():
    cfg = body(
        vy="ratio",
        methods=("full", "quasistationary"),
        outputs=("Tx", "vy"),
        starts={"vy_ratio": 0.002, "method": "quasistationary"},
        experiment=(0.0, 1.0, 0.01),
    )
    assert ModelConfig.from_dict(cfg.to_dict()) == cfg


def test_docs_list_the_declared_variables():
    """docs/variables.md's table is generated from the declarations (kept in sync:
    python -m contact_fmu.fmu.variables --write-docs)."""
    page = (Path(__file__).resolve().parents[1] / "docs" / "variables.md").read_text()
    assert fv.write_docs(page) == page
    assert fv.markdown_table() in page
    assert len(fv.markdown_table().split("\n")) == len(fv.VARIABLES) + 2
