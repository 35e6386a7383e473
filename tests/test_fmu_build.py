"""Building the FMUs: validation, model description, what each FMU holds, the cache."""

from __future__ import annotations

import subprocess
import sys
import zipfile
from pathlib import Path

import fmpy
import pytest
from fmpy.validation import validate_fmu

import fmu_build
from contact_fmu import native
from contact_fmu.fmu.config import ModelConfig
from contact_fmu.scenario import discover, load

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "out" / "fmu"
SCENES = {p.stem: load(p) for p in discover(ROOT / "scenarios")}
FULL = {f"full_{m}": ModelConfig.full(m) for m in ("body", "contact", "rigid_body")}
CONFIGS = {**{k: s.config for k, s in SCENES.items()}, **FULL}


@pytest.fixture(scope="session")
def built() -> dict[str, fmu_build.Built]:
    """Every FMU the project builds (cached under out/fmu by content)."""
    return {name: fmu_build.build(cfg, OUT) for name, cfg in CONFIGS.items()}


def test_scene_set_is_the_one_the_issue_asks_for():
    assert set(SCENES) == {"fig13", "fig12", "railway", "brake", "sweep", "rail_creep",
                           "rail_traction", "fig12_transient", "cornering", "liftoff",
                           "liftoff_contact"}  # fmt: skip


def test_every_built_fmu_passes_fmpy_validate(built):
    for name, b in built.items():
        assert validate_fmu(str(b.path)) == [], name
        # the command line a user runs: `fmpy validate X.fmu`
        proc = subprocess.run(
            [sys.executable, "-m", "fmpy", "validate", str(b.path)],
            capture_output=True, text=True,
        )  # fmt: skip
        assert proc.returncode == 0 and "No problems found" in proc.stdout, (name, proc.stdout)


def test_model_description_has_units_ranges_and_complete_structure(built):
    for name, b in built.items():
        cfg = CONFIGS[name]
        md = fmpy.read_model_description(str(b.path), validate=False)
        units = {u.name for u in md.unitDefinitions}
        variables = {v.name: v for v in md.modelVariables}
        assert list(variables) == [v.name for v in cfg.variables], name
        for decl in cfg.variables:
            v = variables[decl.name]
            assert v.description == decl.description
            if decl.type == "Real":
                assert v.unit == decl.unit and v.unit in units, (name, v.name)
            lo, hi = cfg.bounds(decl)  # the declared range, or min = max for a fixed value
            if lo is not None:
                assert float(v.min) == lo, (name, v.name)
            if hi is not None:
                assert float(v.max) == hi, (name, v.name)
        assert md.coSimulation.canGetAndSetFMUstate and md.coSimulation.canSerializeFMUstate
        outputs = [v for v in md.modelVariables if v.causality == "output"]
        assert [u.variable for u in md.outputs] == outputs
        assert [u.variable for u in md.initialUnknowns] == outputs
        inputs = {v.name for v in md.modelVariables if v.causality == "input"}
        for u in md.outputs:
            deps = {d.name for d in u.dependencies}
            if cfg.mode == "contact":  # force element: direct feedthrough from the kinematics
                assert deps and deps <= inputs, (name, u.variable.name)
            else:  # outputs are states
                assert deps == set(), (name, u.variable.name)


def test_exact_start_values_in_the_model_description(built):
    md = fmpy.read_model_description(str(built["fig13"].path), validate=False)
    starts = {v.name: v.start for v in md.modelVariables}
    assert float(starts["Vx0"]) == 5.6418958354775635  # 17 digits survive
    assert float(starts["Fx_ex"]) == 190.98593171027443


def _vendored(b: fmu_build.Built) -> set[str]:
    with zipfile.ZipFile(b.path) as z:
        prefix = f"resources/{b.package}/"
        return {  # files (the archive also holds an entry per folder)
            n[len(prefix) :] for n in z.namelist() if n.startswith(prefix) and not n.endswith("/")
        }


def test_scene_fmu_holds_only_the_variables_it_uses(built):
    fig13 = {v.name for v in CONFIGS["fig13"].variables}
    full = {v.name for v in CONFIGS["full_body"].variables}
    lateral = {"Vy", "Omega_z", "Fy_ex", "Mz_ex", "Ty", "Mz", "vy", "xi_y", "xi_sp", "Iz",
               "Vy0", "Omega_z0", "method"}  # fmt: skip
    assert not fig13 & lateral
    assert lateral <= full
    assert len(fig13) < len(full)
    # fig12 holds vy/Vx: the ratio and the lateral force, but not Eq. (10)'s input
    fig12 = {v.name for v in CONFIGS["fig12"].variables}
    assert {"vy_ratio", "Ty", "vy"} <= fig12 and not fig12 & {"Fy_ex", "Vy0", "Iz"}
    # only the railway scenes switch steppers, so only they have the method parameter
    assert [n for n, c in CONFIGS.items() if any(v.name == "method" for v in c.variables)] == [
        "rail_traction", "railway", "full_body"
    ]  # fmt: skip


def test_fmu_carries_only_the_model_parts_it_imports(built):
    body, contact, rigid = (_vendored(built[n]) for n in ("fig13", "sweep", "full_rigid_body"))
    assert {
        "dynamics/integrator.py",
        "dynamics/body.py",
        "laws/thin_layer.py",
        "fmu/body_model.py",
    } <= body
    assert "fmu/contact_model.py" not in body and "fmu/rigid_body.py" not in body
    assert {"laws/thin_layer.py", "dynamics/kinematics.py", "fmu/contact_model.py"} <= contact
    # the contact FMU has the body's parameter types (dynamics/body.py, through the
    # package), not its steppers
    assert not contact & {"dynamics/integrator.py", "dynamics/solvers.py", "fmu/body_model.py"}
    assert "laws/thin_layer.py" not in rigid and "dynamics/integrator.py" not in rigid
    for files in (body, contact, rigid):
        assert "dynamics/simulate.py" not in files and "examples.py" not in files
        assert "fmu/slave.py" in files


@pytest.mark.skipif(native.library() is None, reason="no C compiler")
def test_body_fmu_carries_the_compiled_stepper_and_loads_it(built, tmp_path):
    """The build compiles contact_fmu/native into the body FMU next to its sources (the
    stepper, and the FMI calls' extension for this interpreter); the vendored loader
    finds both (and would compile nothing on the target); the full contact FMU, whose law
    marches its spin input's grid in the stepper's library, carries the library but not
    the extension (its FMI calls go to the C core by ctypes); a contact FMU without spin
    and the rigid-body FMU, which step no compiled kernel, carry the loaders' Python and
    their C core alone, no kernel and no C source. Every one of them carries its model's
    C core (instance.c for its cf_model.h: native/_core.so and its GUID, the native FMU's
    models all), to which the adapter delegates (tests/test_pythonfmu_core.py)."""
    lib, ext = f"native/{native.library_name()}", f"native/{native.fmi_name()}"
    carried = {"native/stepper.c", "native/fmi.c", "native/cf_core.h", "native/cf_abi.h"}
    the_core = {"native/core.py", "native/_core.so", "native/_core.guid"}
    assert carried | the_core | {"native/abi.py", lib, ext} <= _vendored(built["fig13"])
    contact = _vendored(built["full_contact"])
    assert {"native/stepper.c", lib} | the_core <= contact and ext not in contact
    loaders = {"native/__init__.py", "native/abi.py"}  # the loader's structs
    for name in ("sweep", "full_rigid_body"):
        assert {f for f in _vendored(built[name]) if f.startswith("native/")} == loaders | the_core
    fmpy.extract(str(built["fig13"].path), str(tmp_path))
    code = (
        f"import sys; sys.path.insert(0, {str(tmp_path / 'resources')!r}); "
        f"from {built['fig13'].package} import native; "
        "print(native.VENDORED, native.library() is not None, native.fmi_module() is not None)"
    )
    env = {"PATH": "/usr/bin:/bin", "HOME": str(tmp_path / "home")}  # no user cache
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env)
    assert out.stdout.split() == ["True", "True", "True"], out.stderr
    assert not (tmp_path / "home").exists()


def test_every_fmu_has_its_own_module_class_and_package(built):
    modules, classes, packages = set(), set(), set()
    for b in built.values():
        with zipfile.ZipFile(b.path) as z:
            module = z.read("resources/slavemodule.txt").decode().strip()
            assert f"resources/{module}.py" in z.namelist()
            script = z.read(f"resources/{module}.py").decode()
        assert f"class {b.class_name}(ContactSlave)" in script
        assert f"from {b.package}.fmu.slave import" in script
        modules.add(module)
        classes.add(b.class_name)
        packages.add(b.package)
    assert len(modules) == len(classes) == len(packages) == len(built)


def test_build_is_cached_by_content(built, tmp_path):
    cfg = CONFIGS["sweep"]
    first = fmu_build.build(cfg, tmp_path)
    assert not first.cached
    mtime = first.path.stat().st_mtime_ns
    again = fmu_build.build(cfg, tmp_path)
    assert again.cached and again.path == first.path
    assert again.path.stat().st_mtime_ns == mtime
    changed = ModelConfig.from_dict({**cfg.to_dict(), "starts": {**cfg.starts, "mu": 0.25}})
    other = fmu_build.build(changed, tmp_path)
    assert other.key != first.key and other.class_name != first.class_name


def test_build_command_line(built, tmp_path):
    proc = subprocess.run(
        [sys.executable, "-m", "fmu_build", str(ROOT / "scenarios" / "sweep.toml"),
         "--full", "rigid_body", "--out", str(tmp_path)],
        capture_output=True, text=True, cwd=ROOT,
    )  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    assert len(list(tmp_path.glob("*.fmu"))) == 2
    bad = subprocess.run(
        [sys.executable, "-m", "fmu_build", str(tmp_path / "missing.toml")],
        capture_output=True, text=True, cwd=ROOT,
    )  # fmt: skip
    assert bad.returncode == 2 and "missing.toml" in bad.stderr


def test_law_data_files_travel_in_the_fmu_and_in_its_key(tmp_path, monkeypatch):
    """The hook for table-based laws: a law's data files are vendored."""
    from contact_fmu.fmu import config

    cfg = CONFIGS["sweep"]
    plain = fmu_build.identity(cfg)[0]
    monkeypatch.setitem(config.LAW_DATA, "layer", ("figures/__init__.py",))
    built = fmu_build.build(cfg, tmp_path)
    assert built.key != plain
    assert "figures/__init__.py" in _vendored(built)
