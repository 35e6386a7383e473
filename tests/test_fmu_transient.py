"""The FMU with phase = "transient": the thin-layer traction field as state.

Built from the fig12_transient scene and driven call by call through fmpy (the scene
itself runs against its stored references in tests/test_scenarios.py). Checked here:
what the FMU carries and declares, FMU state with the field (bit for bit), the field
file against the stepper outside the FMU, and bad input (fmi2Discard with a message
naming the variable, the instance usable afterwards).
"""

from __future__ import annotations

import csv
import math
import zipfile
from pathlib import Path

import fmpy
import numpy as np
import pytest
from fmpy.fmi1 import FMICallException
from fmpy.validation import validate_fmu

import fmu_build
from contact_fmu import examples as ex
from contact_fmu.dynamics.body import Lateral, Loads
from contact_fmu.dynamics.thin_layer_field import TransientRollingBody
from contact_fmu.fmu.body_model import substeps
from contact_fmu.fmu.body_transient import FIELD_COLUMNS
from contact_fmu.scenario import load
from contact_fmu.scenario.instance import DISCARD, ERROR, FATAL, OK, Instance

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "out" / "fmu"
SCENE = load(ROOT / "scenarios" / "fig12_transient.toml")
F3 = 3.0 * ex.force_unit()
H = 2.0e-5  # the scene's communication step (s)
# A small field keeps these call-by-call tests fast (the scene runs 32 x 16).
SMALL = {"nx": 16, "ny": 8, "cells_per_step": 1.0, "Iy": ex.M * ex.Rx**2 / 10.9}


@pytest.fixture(scope="module")
def fmu() -> Path:
    return fmu_build.build(SCENE.config, OUT).path


def start(fmu: Path, **extra) -> Instance:
    params = {**SCENE.cases[0].parameters, **SMALL, **extra}
    inst = Instance(fmu, "transient", params)
    inst.set("P", ex.P)
    inst.set("Fx_ex", F3)
    return inst


def read_field(path: Path) -> dict[float, dict[str, np.ndarray]]:
    """The field file by requested time: {requested: {column: values}}."""
    with path.open(newline="") as f:
        rows = list(csv.DictReader(f))
    out: dict[float, dict[str, list[float]]] = {}
    for r in rows:
        d = out.setdefault(float(r["requested"]), {c: [] for c in FIELD_COLUMNS})
        for c in FIELD_COLUMNS:
            d[c].append(float(r[c]))
    return {k: {c: np.asarray(v) for c, v in d.items()} for k, d in out.items()}


def test_transient_fmu_validates_declares_the_field_and_carries_its_module(fmu):
    """fmpy validate passes; the grid and the field file are parameters (Integer grid
    sizes with their minimum), the field summary outputs carry units; only this FMU
    carries the transient field (the steady fig12 FMU does not)."""
    assert validate_fmu(str(fmu)) == []
    md = fmpy.read_model_description(str(fmu), validate=False)
    v = {x.name: x for x in md.modelVariables}
    assert (v["nx"].type, v["nx"].causality, int(v["nx"].min)) == ("Integer", "parameter", 4)
    assert (v["ny"].type, int(v["ny"].min)) == ("Integer", 2)
    assert v["field_file"].type == "String" and v["field_times"].type == "String"
    assert (v["slip_centroid_x"].unit, v["tau_peak"].unit) == ("m", "Pa")
    assert "method" not in v and "scheme" not in v  # the steady steppers do not apply

    def vendored(path: Path) -> set[str]:
        with zipfile.ZipFile(path) as z:
            return {n.split("/", 2)[-1] for n in z.namelist() if n.startswith("resources/cfmu_")}

    steady = fmu_build.build(load(ROOT / "scenarios" / "fig12.toml").config, OUT).path
    assert {"dynamics/thin_layer_field.py", "fmu/body_transient.py"} <= vendored(fmu)
    assert not {"dynamics/thin_layer_field.py", "fmu/body_transient.py"} & vendored(steady)


def test_fmu_state_with_the_field_repeats_bit_for_bit(fmu, tmp_path):
    """get state, step, set state, step again: the outputs (which follow from the field:
    Tx, adhesion, slip centroid, peak traction) and the field file repeat bit for bit.
    Without the field in the state the repeat would start from the later field and
    differ (Tx changes by several N per step here)."""
    path = tmp_path / "field.csv"
    with start(fmu, field_file=str(path), field_times="3.0e-4 5.0e-4") as b:
        for _ in range(5):
            assert b.step(H) == OK
        state = b.get_state()
        for _ in range(25):
            assert b.step(H) == OK
        first, text = b.outputs(), path.read_text()
        assert first["Tx"] != 0.0 and len(read_field(path)) == 2
        b.set_state(state)
        assert not path.exists() or len(read_field(path)) == 0  # rewritten with the state
        for _ in range(25):
            assert b.step(H) == OK
        assert b.outputs() == first
        assert path.read_text() == text
        data = b.serialize_state(state)
        b.free_state(state)
        assert all(s < FATAL for s, _ in b.messages)
    # serialized (fmi2SerializeFMUstate), the field restores into a fresh instance
    with start(fmu) as c:
        c.set_state(c.deserialize_state(data, state[1]))
        for _ in range(25):
            assert c.step(H) == OK
        assert c.outputs() == first
        assert path.read_text() == text  # the state's parameters: the same file


def test_field_file_is_the_steppers_field_at_the_requested_times(fmu, tmp_path):
    """The file holds, per requested time, the field at the end of the communication step
    that reaches it: the same numbers as TransientRollingBody driven outside the FMU with
    the same steps; sum(weight tau) is the Tx the FMU output at that time (the resultant
    used in the dynamics); slip nodes carry mu p."""
    path = tmp_path / "field.csv"
    times = (0.0, 1.0e-4, 1.5e-4 + 1e-6, 4.0e-4)  # the third is reached at 1.6e-4 s
    p = {**SCENE.cases[0].parameters, **SMALL}
    tb = TransientRollingBody(
        ex.contact(), ex.body(10.9), Lateral(vy_ratio=0.002), Vx0=p["Vx0"],
        Omega_y0=p["Vx0"] / p["Rx"], nx=SMALL["nx"], ny=SMALL["ny"],  # vx0 = 0
    )  # fmt: skip
    expected = {0.0: (0.0, tb.field_arrays(), tb.outputs()["Tx"])}
    with start(fmu, field_file=str(path), field_times=", ".join(map(repr, times))) as b:
        for k in range(20):
            assert b.step(H) == OK
            n = max(substeps(H, p["h_max"]), tb.substeps_for(H, SMALL["cells_per_step"]))
            tb.advance(H, Loads(Fx_ex=F3), n)
            assert b.get("Tx") == tb.outputs()["Tx"]
            for t_req in times:
                if t_req not in expected and t_req <= (k + 1) * H + 1e-15:
                    expected[t_req] = ((k + 1) * H, tb.field_arrays(), b.get("Tx"))
    got = read_field(path)
    assert list(got) == list(times)
    for t_req, (t_end, arrays, Tx) in expected.items():
        g = got[t_req]
        assert np.all(g["time"] == pytest.approx(t_end, rel=1e-12))
        ny, nx = arrays["tau_x"].shape
        assert g["tau_x"].size == nx * ny
        for name in ("tau_x", "tau_y", "p", "weights"):
            col = "weight" if name == "weights" else name
            assert np.array_equal(g[col].reshape(ny, nx), arrays[name]), (t_req, name)
        assert np.array_equal(g["x"].reshape(ny, nx)[0], arrays["x"])
        assert float(np.sum(g["weight"] * g["tau_x"])) == pytest.approx(Tx, rel=1e-12, abs=1e-9)
        slip = g["slip"] == 1
        mag = np.hypot(g["tau_x"], g["tau_y"])
        assert np.allclose(mag[slip], ex.mu * g["p"][slip], rtol=1e-12)
    assert got[0.0]["tau_x"].max() == 0.0  # the field starts at rest
    assert got[1.5e-4 + 1e-6]["time"][0] == pytest.approx(1.6e-4, rel=1e-12)


@pytest.mark.parametrize(
    ("name", "value", "fragment"),
    [
        ("nx", 2, "nx = 2 is invalid: must be >= 4"),
        ("cells_per_step", 0.0, "cells_per_step = 0.0 is invalid: must be > 0"),
        ("field_times", "1e-4, soon", "must be times in s separated by spaces or commas"),
    ],
)
def test_bad_parameter_fails_initialisation_naming_it_until_corrected(fmu, name, value, fragment):
    """A bad grid, step or list of field times: fmi2Error (at its setter where its range
    says so, at exitInitializationMode in any case) with a logged message naming the
    parameter and its value; corrected, the model starts and steps."""
    params = {**SCENE.cases[0].parameters, **SMALL}
    with Instance(fmu, "transient", params, initialise=False) as b:
        try:
            b.set(name, value)
        except FMICallException as e:
            assert e.status == ERROR
        with pytest.raises(FMICallException) as e:
            b.initialise()
        assert e.value.status == ERROR
        assert any(fragment in m for _, m in b.messages), b.messages
        assert b.step(H) == ERROR
        b.set(name, {**params, "field_times": ""}[name])
        b.initialise()
        b.set("Fx_ex", F3)
        assert b.step(H) == OK and b.get("Tx") > 0.0
        assert all(s < FATAL for s, _ in b.messages)


def test_bad_input_and_unwritable_field_file_give_discard_and_keep_the_state(fmu, tmp_path):
    """A NaN input, and a field file that cannot be written (a folder), answer
    fmi2Discard naming the variable; the outputs (and the field) stay those before the
    step, and the instance steps on once the input is corrected."""
    folder = tmp_path / "a_folder"
    folder.mkdir()
    with start(fmu) as b:
        for _ in range(3):
            assert b.step(H) == OK
        before = b.outputs()
        with pytest.raises(FMICallException):
            b.set("Fx_ex", math.nan)
        assert b.step(H) == DISCARD
        assert any("Fx_ex = nan is invalid: must be finite" in m for _, m in b.messages)
        assert b.outputs() == before
        b.set("Fx_ex", F3)
        assert b.step(H) == OK
    with start(fmu, field_file=str(folder), field_times="1e-4") as b:
        for _ in range(4):
            assert b.step(H) == OK
        before = b.outputs()
        assert b.step(H) == DISCARD  # the step that reaches 1e-4 s must write the file
        assert any(f"field_file = '{folder}' is invalid" in m for _, m in b.messages)
        assert b.outputs() == before and all(math.isfinite(x) for x in before.values())


def test_a_start_spinning_beyond_rate_max_is_refused_naming_omega_y0(fmu):
    """Omega_y0 = (Vx0 - vx0)/Rx (Eq. 3 solved): Vx0 = 10 m/s on Rx = 1e-7 m gives 1e8
    rad/s, beyond RATE_MAX = 1e7 rad/s, from which every step would be discarded:
    fmi2Error at exitInitializationMode naming Omega_y0 and its value (1e8 to a few
    roundings: the state holds vx, whence Omega_y is read back), as the steady body;
    with Rx = 1e-6 (Omega_y0 = 1e7, on the bound) the instance starts and steps."""
    params = {**SCENE.cases[0].parameters, **SMALL, "Rx": 1e-7, "Vx0": 10.0, "vx0": 0.0}
    with Instance(fmu, "transient", params, initialise=False) as b:
        with pytest.raises(FMICallException) as e:
            b.initialise()
        assert e.value.status == ERROR
        found = [m for s, m in b.messages if "Omega_y0 = " in m]
        assert len(found) == 1, b.messages
        value = float(found[0].split("Omega_y0 = ")[1].split()[0])
        assert value == pytest.approx(1e8, rel=1e-12)
        assert found[0].endswith(
            "is invalid: must be within abs <= 1e+07 "
            "(Omega_y0 = (Vx0 - vx0)/Rx: the model cannot start there)"
        )
        assert b.step(H) == ERROR
        b.set("Rx", 1e-6)
        b.initialise()  # on the bound: starts; held there without loads (pure rolling)
        b.set("Fx_ex", 0.0)
        assert b.step(H) == OK, b.messages[-1]
