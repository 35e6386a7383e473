"""FMUs with the exact half-space law: declaration, build, shipped table, errors, two tables.

The rail scenes (scenarios/rail_creep.toml, contact mode; rail_traction.toml, body mode)
declare the railway wheel on rail of contact_fmu.halfspace.railway; their FMUs carry the
creep-force table the build computed (one table, about 30 s once, cached under
out/tables). Every status and message here is the one fmpy receives from the FMU.
The scenes against their references: tests/test_scenarios.py; the references
reproduced from their source: tests/test_scenarios_references.py.
"""

from __future__ import annotations

import math
import shutil
import zipfile
from pathlib import Path

import fmpy
import numpy as np
import pytest
from fmpy.fmi1 import FMICallException
from fmpy.validation import validate_fmu

import fmu_build
from contact_fmu import InputError
from contact_fmu.fmu import variables as fv
from contact_fmu.fmu.config import GENERATED_DATA, ModelConfig
from contact_fmu.halfspace.railway import wheel_on_rail
from contact_fmu.scenario import ScenarioError, load, runner
from contact_fmu.scenario.instance import DISCARD, ERROR, FATAL, OK, Instance

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "out" / "fmu"
SCENES = {n: load(ROOT / "scenarios" / f"{n}.toml") for n in ("rail_creep", "rail_traction")}
TABLE = GENERATED_DATA["halfspace"]
V = 30.0  # m/s, the rail scenes' speed
W = V / 0.46  # rad/s, pure rolling of the 0.46 m wheel

# A second, small declaration: another rail head radius (0.6 m), layers as compliant as
# a quarter of the steel half-spaces at this contact (c/G ~ 8e-14 m/Pa; so a load range
# of two nodes), a coarse solver grid and few nodes, built in about a second.
SMALL = {
    "body": {"Rx": 0.46, "Ry": "inf", "E": 210.0e9, "nu": 0.28},
    "substrate": {"Rx": "inf", "Ry": 0.6, "E": 210.0e9, "nu": 0.28},
    "kb": 1e-14,
    "ks": 1e-14,
    "mu": 0.3,
    "loads": [80.0e3, 120.0e3],
    "grid": 8,
    "xi_max": 0.014,
    "eta_max": 0.014,
    "phi_max": 1.5,
    "nodes": [7, 5, 3],
}


def small_config() -> ModelConfig:
    return ModelConfig(
        name="small_halfspace",
        mode="contact",
        inputs=("P", "Vx", "Vy", "Omega_y"),
        outputs=("Tx", "Ty", "Mz", "a1", "adhesion"),
        contact_law="halfspace",
        law_spec=SMALL,
        starts={"P": 100e3, "Vx": V, "Omega_y": W},
    )


@pytest.fixture(scope="session")
def built() -> dict[str, fmu_build.Built]:
    cfgs = {n: s.config for n, s in SCENES.items()} | {"small": small_config()}
    return {n: fmu_build.build(cfg, OUT) for n, cfg in cfgs.items()}


def shipped_law(b: fmu_build.Built, cfg: ModelConfig, tmp: Path):
    """The run-time law read from the table inside the FMU file."""
    with zipfile.ZipFile(b.path) as z:
        data = z.read(f"resources/{b.package}/{TABLE}")
    path = tmp / f"{b.package}.npz"
    path.write_bytes(data)
    return cfg.table_spec.load_law(path)


def set_creepage(inst: Instance, xi: float, eta: float = 0.0, P: float = 100e3) -> None:
    """Contact-mode inputs for creepages xi = vx/Vx, eta = vy/Vx at Vx = 30 m/s."""
    inst.set("P", P)
    inst.set("Vx", V)
    inst.set("Omega_y", W * (1.0 - xi))
    inst.set("Vy", eta * V)


# ---- declaration and variables (no build) -------------------------------------------------
def test_rail_scenes_declare_the_railway_wheel_on_rail():
    """The scenes write contact_fmu.halfspace.railway's parameter set as data."""
    ref = wheel_on_rail(n=32)
    for scene in SCENES.values():
        c = scene.config.table_spec.contact()
        for name in ("P", "Rx", "Ry", "Rsx", "Rsy", "body", "substrate", "mu", "kb", "ks", "n"):
            assert getattr(c, name) == getattr(ref, name), (scene.name, name)
        for case in scene.cases:
            assert case.parameters["Rx"] == ref.Rx and case.parameters["mu"] == ref.mu
    assert SCENES["rail_creep"].config.law_spec == SCENES["rail_traction"].config.law_spec


def test_halfspace_fmu_has_no_layer_parameters_and_a_fixed_rolling_radius():
    for scene in SCENES.values():
        cfg = scene.config
        names = {v.name for v in cfg.variables}
        assert not names & {"Ry", "k1", "k2", "kb", "ks"}  # structural: the [halfspace] table
        assert {"mu", "Rx"} <= names
        assert cfg.fixed == {"Rx": 0.46}
        rx = fv.BY_NAME["Rx"]
        assert cfg.bounds(rx) == (0.46, 0.46) and cfg.start(rx) == 0.46
        assert cfg.bounds(fv.BY_NAME["mu"]) == (fv.MU_MIN, None)  # mu stays free
        assert cfg.check("Rx", 0.46) is None and cfg.check("mu", 0.2) is None
        assert "the value this FMU's creep-force table was built for" in cfg.check("Rx", 0.5)


@pytest.mark.parametrize(
    ("old", "new", "fragment"),
    [
        (
            "mu = 0.3\nRx = 0.46",
            "mu = 0.3\nRy = 0.1\nRx = 0.46",
            "takes its contact from [halfspace]",
        ),
        ("grid = 32 ", "grid = 4 ", "halfspace.grid = 4 is invalid: must be an integer >= 8"),
        ("nodes = [25, 21, 3]", "nodes = [25, 21]", "halfspace.nodes = [25, 21] is invalid"),
        ("[halfspace]", "[halfspac]", "unknown key(s) ['halfspac']"),
    ],
)
def test_malformed_halfspace_scene_is_refused_naming_the_file_and_key(tmp_path, old, new, fragment):
    """A layer-law parameter, a bad or missing [halfspace] entry: the file and key named."""
    text = (ROOT / "scenarios" / "rail_creep.toml").read_text()
    assert old in text
    path = tmp_path / "rail.toml"
    path.write_text(text.replace(old, new, 1))
    with pytest.raises(ScenarioError) as e:
        load(path)
    assert str(path) in str(e.value) and fragment in str(e.value), str(e.value)


def test_config_refuses_a_scene_rx_other_than_the_tables():
    cfg = SCENES["rail_creep"].config
    d = cfg.to_dict()
    d["starts"] = {**cfg.starts, "Rx": 0.45}
    with pytest.raises(InputError) as e:
        ModelConfig.from_dict(d)
    assert e.value.name == "Rx" and "0.46, the value this FMU's creep-force table" in str(e.value)
    assert ModelConfig.from_dict(cfg.to_dict()) == cfg  # round trip through plain data


# ---- built FMUs ----------------------------------------------------------------------------
def test_halfspace_fmus_validate_and_describe_the_fixed_radius(built):
    for name, b in built.items():
        assert validate_fmu(str(b.path)) == [], name
        md = fmpy.read_model_description(str(b.path))
        rx = next(v for v in md.modelVariables if v.name == "Rx")
        assert float(rx.min) == float(rx.max) == float(rx.start) == 0.46, name


def test_fmu_ships_its_table_tagged_with_its_declaration(built, tmp_path):
    for name in ("rail_creep", "rail_traction"):
        b, cfg = built[name], SCENES[name].config
        law = shipped_law(b, cfg, tmp_path)  # refuses a table of another declaration
        assert law.data.nodes == (25, 21, 3) and law.data.n == 32
        assert law.a1 == pytest.approx(wheel_on_rail().a1, rel=1e-12)
        # the build's table (cached) and the shipped one are the same bytes
        with zipfile.ZipFile(b.path) as z:
            shipped = z.read(f"resources/{b.package}/{TABLE}")
        assert shipped == fmu_build.tables.ensure(cfg).read_bytes()


def test_fmu_reads_its_own_table_not_the_build_cache(built, tmp_path):
    """An FMU of the rail declaration under a name of its own (its own content key, so
    nothing of it is imported yet in this process), built with a table cache that is
    deleted afterwards. An extraction whose tables are removed from the resources (the C
    core's and the Python path's) refuses to initialise (fmi2Error, the files named); a
    second, intact extraction of the same FMU then runs, reading its own table (not the
    first extraction's, not the cache), and gives the outputs of the rail_creep FMU."""
    base = SCENES["rail_creep"].config
    cfg = ModelConfig.from_dict({**base.to_dict(), "name": "rail_creep_own_table"})
    cache = tmp_path / "tables"
    cache.mkdir()
    shutil.copy(fmu_build.tables.ensure(base), cache)  # seed: no table build here
    own = fmu_build.build(cfg, tmp_path / "fmu", table_cache=cache)
    shutil.rmtree(cache)
    assert not own.cached and own.package != built["rail_creep"].package

    unzipped = tmp_path / "unzipped"
    fmpy.extract(str(own.path), str(unzipped))
    (unzipped / "resources" / own.package / TABLE).unlink()
    (unzipped / "resources" / own.package / "native" / "table.bin").unlink()  # the core's
    inst = Instance(own.path, "no_table", unzip_dir=unzipped, initialise=False)
    try:
        set_creepage(inst, 0.002)
        with pytest.raises(FMICallException) as e:
            inst.initialise()
        assert e.value.status == ERROR
        text = " ".join(m for _, m in inst.messages)
        # the C core cannot read its table (a warning: the Python path runs), nor then
        # can the Python path its own
        assert "C core cannot start" in text and "table.bin" in text, text
        assert "cannot initialise the model" in text and "creep_table.npz" in text, text
        assert all(s < FATAL for s, _ in inst.messages)
    finally:
        inst.close()

    outputs = []
    for path in (own.path, built["rail_creep"].path):
        with Instance(path, "own") as inst:
            set_creepage(inst, 0.002, 0.001)
            assert inst.step(1e-3) == OK, inst.messages
            outputs.append(inst.outputs())
    assert outputs[0] == outputs[1] and outputs[0]["Tx"] > 0.5 * 0.3 * 100e3


def test_two_fmus_with_different_tables_in_one_process_each_use_their_own(built, tmp_path):
    """The rail FMU (rail head 0.3 m, no layers) and the small FMU (0.6 m, layers, 8 x 8
    grid), stepped interleaved with the same inputs: each gives its own table's forces
    and contact ellipse (to rounding), and the two differ by far more than that."""
    laws = {n: shipped_law(built[n], c, tmp_path) for n, c in
            (("rail_creep", SCENES["rail_creep"].config), ("small", small_config()))}  # fmt: skip
    insts = {n: Instance(built[n].path, n) for n in laws}
    diff = 0.0
    try:
        for xi, eta, P in ((0.001, 0.0, 100e3), (0.003, 0.002, 90e3), (-0.002, 0.001, 110e3)):
            for inst in insts.values():
                set_creepage(inst, xi, eta, P)
                assert inst.step(1e-3) == OK, inst.messages
            got = {n: inst.outputs() for n, inst in insts.items()}
            for n, law in laws.items():
                lw = law.with_load(P)
                vx, vy = V - W * (1.0 - xi) * 0.46, eta * V
                Tx, Ty, _ = lw.forces(vx, vy, 0.0, V)
                # the same floats through the same code: equal to rounding
                assert got[n]["Tx"] == pytest.approx(Tx, rel=1e-12, abs=1e-9), (n, xi)
                assert got[n]["Ty"] == pytest.approx(Ty, rel=1e-12, abs=1e-9), (n, xi)
                assert got[n]["a1"] == pytest.approx(lw.a1, rel=1e-12), n
            diff = max(diff, abs(got["rail_creep"]["Tx"] - got["small"]["Tx"]) / (0.3 * P))
            assert abs(got["rail_creep"]["a1"] / got["small"]["a1"] - 1.0) > 0.05
        assert diff > 0.05, diff  # the tables differ by far more than the checks resolve
    finally:
        for inst in insts.values():
            inst.close()


@pytest.mark.parametrize("name", ["rail_creep", "rail_traction"])
def test_fmu_state_get_step_set_step_is_bit_identical(built, name):
    scene = SCENES[name]
    case = scene.cases[0]
    table = runner.input_table(scene, case)
    with Instance(built[name].path, "state", runner.start_values(scene, case)) as inst:

        def step(k: int) -> None:
            for n in scene.inputs:
                inst.set(n, float(table[n][k]))
            assert inst.step(scene.step) == OK, inst.messages[-1:]

        for k in range(60):  # rail_traction: into the traction ramp
            step(k)
        state = inst.get_state()
        for k in range(60, 64):
            step(k)
        first = inst.outputs()
        inst.set_state(state)
        for k in range(60, 64):
            step(k)
        assert inst.outputs() == first
        data = inst.serialize_state(state)
        inst.free_state(state)
    # through bytes (fmi2SerializeFMUstate) into a fresh instance: the same doubles
    with Instance(built[name].path, "restored") as inst:
        inst.set_state(inst.deserialize_state(data, state[1]))
        for k in range(60, 64):
            step(k)
        assert inst.outputs() == first


# ---- bad input ------------------------------------------------------------------------------
@pytest.mark.parametrize("name", ["rail_creep", "rail_traction"])
def test_other_rolling_radius_is_refused_until_corrected(built, name):
    scene = SCENES[name]
    starts = runner.start_values(scene, scene.cases[0])
    with Instance(built[name].path, "rx", starts, initialise=False) as inst:
        if scene.config.mode == "contact":
            set_creepage(inst, 0.001)
        for call in (lambda: inst.set("Rx", 0.5), inst.initialise):
            with pytest.raises(FMICallException) as e:
                call()
            assert e.value.status == ERROR
        assert inst.step(1e-3) == ERROR
        text = "Rx = 0.5 is invalid: must be 0.46, the value this FMU's creep-force table"
        assert any(text in m for _, m in inst.messages), inst.messages  # logged at setReal
        inst.set("Rx", 0.46)  # not initialised yet: a parameter may still be corrected
        inst.initialise()
        assert inst.step(1e-3) == OK, inst.messages[-1:]
        with pytest.raises(FMICallException):  # initialised: a fixed parameter is ignored
            inst.set("Rx", 0.5)
        assert inst.get("Rx") == 0.46 and inst.step(1e-3) == OK
        assert any("Rx = 0.5 is ignored" in m for _, m in inst.messages)
        assert all(s < FATAL for s, _ in inst.messages)


@pytest.mark.parametrize(
    ("name", "value", "fragment"),
    [
        ("P", 150e3, "P = 150000.0 is invalid: must be within the load range [80000, 120000] N"),
        ("P", -1.0, "P = -1.0 is invalid: must be >= 0 (lift-off, no contact, is P = 0)"),
        ("Vy", math.nan, "Vy = nan is invalid: must be finite"),
    ],
)
def test_bad_input_gives_discard_a_named_message_and_recovery(built, name, value, fragment):
    with Instance(built["small"].path, "bad") as inst:
        set_creepage(inst, 0.002)
        assert inst.step(1e-3) == OK
        before = inst.outputs()
        try:  # out of its declared range: fmi2Error here already (else at the step)
            inst.set(name, value)
        except FMICallException as e:
            assert e.status == ERROR
        assert inst.step(1e-3) == DISCARD
        assert any(fragment in m for s, m in inst.messages if s == DISCARD), inst.messages
        with pytest.raises(FMICallException):  # no outputs for the held input: an error
            inst.get("Tx")
        set_creepage(inst, 0.002)
        assert inst.step(1e-3) == OK and inst.outputs() == before
        assert all(s < FATAL for s, _ in inst.messages)


def test_bad_mu_is_refused_until_corrected(built):
    with Instance(built["rail_creep"].path, "mu", initialise=False) as inst:
        set_creepage(inst, 0.001)
        for call in (lambda: inst.set("mu", -0.3), inst.initialise):
            with pytest.raises(FMICallException):
                call()
        assert any("mu = -0.3 is invalid: must be >= 1e-09" in m for _, m in inst.messages)
        inst.set("mu", 0.3)
        inst.initialise()
        assert inst.step(1e-3) == OK


# ---- accuracy ---------------------------------------------------------------------------------
def test_fmu_at_another_mu_matches_direct_solves(built):
    """mu = 0.2 at run time in the FMU built for mu = 0.3 (exact similarity) against
    direct solves at mu = 0.2. Tolerance: the scene's, scaled to this mu P (the
    table's error in units of mu P does not depend on mu): 125 N x 0.2/0.3."""
    contact = SCENES["rail_creep"].config.table_spec.contact(mu=0.2)
    tol = 125.0 * 0.2 / 0.3
    with Instance(built["rail_creep"].path, "mu", {"mu": 0.2}) as inst:
        for xi, eta in ((0.0007, 0.0), (0.0021, 0.0), (0.0015, 0.0015), (-0.004, 0.001)):
            set_creepage(inst, xi, eta)
            assert inst.step(1e-3) == OK
            vx = V - W * (1.0 - xi) * 0.46
            s = contact.traction(vx, eta * V, 0.0, V)
            assert abs(inst.get("Tx") - s.Tx) <= tol and abs(inst.get("Ty") - s.Ty) <= tol
            assert 0.0 < abs(s.Tx) < 0.2 * 100e3  # partial slip: mu matters


def test_scene_tolerance_is_twice_the_tables_error_at_independent_points(built, tmp_path):
    """The rail_creep tolerances are twice the table's error measured by
    benchmarks/bench_halfspace_fmu.py; re-measured here at points other than the scene's:
    the midpoints of the table's cells along xi at eta = 0 and eta = 0.002/xi_ref (where
    cubic interpolation errs most), and the benchmark's first 16 random points."""
    scene = SCENES["rail_creep"]
    spec = scene.config.table_spec
    law = shipped_law(built["rail_creep"], scene.config, tmp_path)
    contact = spec.contact()
    xr, X = law.xi_ref, law.data.extent
    axis = law.data.axes[0]
    mids = 0.5 * (axis[:-1] + axis[1:])
    points = [(m, e) for e in (0.0, 0.002 / xr) for m in mids[np.abs(mids) <= 0.98 * X[0]]]
    rng = np.random.default_rng(1)  # the benchmark's sample (same seed and order)
    points += [tuple(x) for x in (rng.uniform(-0.98, 0.98, (200, 2)) * X[:2])[:16]]
    tol = scene.references[0].tolerance
    worst = dict.fromkeys(tol, 0.0)
    for x1, x2 in points:
        s = contact.solve(x1 * xr, x2 * xr)
        T = law.forces(x1 * xr, x2 * xr, 0.0, 1.0)
        a = law.adhesion_fraction(x1 * xr, x2 * xr, 1.0)
        for k, got, ref in zip(tol, (*T, a), (s.Tx, s.Ty, s.Mz, s.adhesion_fraction),
                               strict=True):  # fmt: skip
            worst[k] = max(worst[k], abs(got - ref))
    for k, t in tol.items():
        assert 2.0 * worst[k] <= t, (k, worst[k], t)
    assert worst["Tx"] > 0.2 * tol["Tx"] / 2  # the measurement is not vacuous
