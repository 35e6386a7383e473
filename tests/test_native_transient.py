"""The native FMU of phase "transient" (fig12_transient: the body on the thin-layer
traction field, field.c's cf_field_advance in the instance layer) against the pythonfmu
FMU, the scene's references and hostile calls.

Both FMUs step the body with the same C (cf_field_advance, cf_field_summary), the
pythonfmu FMU through thin_layer_field.py's ctypes binding. They differ only where the field's
geometry is laid: numpy computes the strips' y = a2 sin(phi), l(y)^3 and the pressure
scale sum(dy (4/3) p0 l^3/a1^2) with its own power and BLAS dot, the native FMU with the C
library's pow and a running sum; these agree to an ulp or two, a relative 1e-16 that the
dissipative field carries as at most ~1e-13 of each output's scale over the scene
(measured: Tx within 2e-13 N, tau_peak within 2e-8 Pa of 1.6e7). The tolerance, 1e-9 of
each output's scale (mu P for the forces), is far above that and far below any change of
the model (a constant off by 1e-6 moves Tx by ~1e-4 N).
"""

from __future__ import annotations

import math
import shutil
import struct
import subprocess
import sys
from pathlib import Path

import native_c
import numpy as np
import pytest

import fmu_build
from contact_fmu.scenario import load, runner
from contact_fmu.scenario.instance import DISCARD, ERROR, FATAL, OK, WARNING, Instance
from fmu_build import native_fmu, native_fmu3

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "out" / "fmu"
SCENE = load(ROOT / "scenarios" / "fig12_transient.toml")
CASE = SCENE.case("eta = 2.92")
H = SCENE.step  # s: 0.7 to 1 cell of the 32-cell field per communication step
MU_P = SCENE.config.starts["mu"] * SCENE.config.starts["P"]  # N: the forces' scale
RTOL = 1e-9  # of each output's scale: see the module's docstring

pytestmark = pytest.mark.skipif(shutil.which("cc") is None, reason="no C compiler")


@pytest.fixture(scope="module")
def native() -> Path:
    return native_fmu.build(SCENE.config, OUT).path


@pytest.fixture(scope="module")
def python() -> Path:
    return fmu_build.build(SCENE.config, OUT).path


@pytest.fixture(scope="module", params=["pythonfmu", "native"])
def target(request, native, python) -> Path:
    return native if request.param == "native" else python


def start(path: Path, **params) -> Instance:
    """The scene's eta = 2.92 case, initialised (start values as the runner sets them)."""
    return Instance(path, "transient", {**runner.start_values(SCENE, CASE), **params})


def steps(inst: Instance, n: int, h: float = H) -> None:
    for _ in range(n):
        assert inst.step(h) == OK, inst.messages[-1:]


def _scale(name: str, column: np.ndarray) -> float:
    """An output's scale: mu P for a force, else its largest magnitude over the run."""
    return MU_P if name in ("Tx", "Ty") else float(np.max(np.abs(column)))


# ---- the scene ---------------------------------------------------------------------------
def test_fig12_transient_native_validates_and_repeats_the_pythonfmu_fmu(native, python):
    """Fig. 12's transient phase (Fx_ex = 3 mu p0 a1 a2 on a body rolling at Rx/T_c, the
    field forming over 3 to 7 contact lengths; eta = 10.9, 2.92, 1.7) through the native
    FMU: fmpy's validation finds no problem (nx and ny declared at the compiled grid,
    min = max), each output of each of the 3 x 350 steps is
    the pythonfmu FMU's within 1e-9 of its scale (the regime exactly), and the scene's
    references pass: the fine-grid transient (vx within 8.1e-4 m/s, Tx within 1.7 N) and
    Eq. (26), Tx = A2 Fx_ex, after the transient."""
    import fmpy
    from fmpy.validation import validate_fmu

    assert validate_fmu(str(native)) == []
    grid = {v.name: v for v in fmpy.read_model_description(str(native)).modelVariables}
    assert [(grid[n].min, grid[n].max, grid[n].start) for n in ("nx", "ny")] == [
        ("32", "32", "32"),
        ("16", "16", "16"),
    ]  # the grid compiled in
    got = runner.simulate(native, SCENE)
    ref = runner.simulate(python, SCENE)
    for g, r in zip(got, ref, strict=True):
        assert g.error is None and r.error is None, (g.error, r.error)
        for name in SCENE.outputs:
            a, b = np.asarray(g.columns[name]), np.asarray(r.columns[name])
            assert len(a) == len(b) == SCENE.n_steps + 1
            if name == "regime":
                assert np.array_equal(a, b), g.case
                continue
            assert np.max(np.abs(a - b)) <= RTOL * _scale(name, b), (g.case, name)
    checks = runner.compare(SCENE, got)
    assert checks and all(c.ok for c in checks), [c for c in checks if not c.ok]


def test_contact_fmu_run_native_passes_fig12_transient(tmp_path):
    """`contact-fmu run --native scenarios/fig12_transient.toml` builds the native FMU,
    runs the three cases through fmpy and passes every reference (exit status 0, PASS);
    the FMU writes each case's field file (5 captures of the 32 x 16 nodes)."""
    cmd = [sys.executable, "-m", "contact_fmu.cli", "run", "--native", "--no-plot",
           "--out", str(tmp_path), str(ROOT / "scenarios" / "fig12_transient.toml")]  # fmt: skip
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
    assert "PASS" in proc.stdout and "MISMATCH" not in proc.stdout
    for case in SCENE.cases:
        path = SCENE.field.path(tmp_path / "scenes" / SCENE.name / "fields", case.name)
        assert len(path.read_text().splitlines()) == 1 + 5 * 32 * 16, path


def test_fmi3_native_fmu_runs_the_same_core_to_the_same_doubles(native, tmp_path):
    """The FMI 3.0 native FMU (fmi3.c on the same instance layer and field.c) validates and
    steps the eta = 2.92 case to the FMI 2.0 native FMU's doubles, output for output: one
    core, two front ends, the same compiled arithmetic."""
    from fmpy.validation import validate_fmu

    path3 = native_fmu3.build(SCENE.config, OUT).path
    assert validate_fmu(str(path3)) == []
    got3 = runner.simulate_case(_extracted(path3, tmp_path), SCENE, CASE)
    got2 = runner.simulate_case(_extracted(native, tmp_path), SCENE, CASE)
    assert got3.error is None and got2.error is None
    for name in SCENE.outputs:
        assert np.array_equal(got3.columns[name], got2.columns[name]), name


def _extracted(path: Path, where: Path) -> Path:
    import fmpy

    fmpy.extract(str(path), str(where / path.stem))
    return where / path.stem


# ---- FMU states ------------------------------------------------------------------------------
def test_fmu_state_get_step_set_step_is_bit_identical(target):
    """The field is the FMU state's (tau on 32 x 16 nodes, the lattice's offset, the
    body): get a state while the field forms, step, set it back, step again: the same
    doubles, every output (the field's summary too)."""
    with start(target) as b:
        steps(b, 20)
        state = b.get_state()
        steps(b, 15)
        first = b.outputs()
        b.set_state(state)
        steps(b, 15)
        assert b.outputs() == first
        b.free_state(state)


def _payload_replaced(data: bytes, old: float, new: float) -> bytes:
    """Native state bytes with every occurrence of the double ``old`` replaced by ``new``
    and the checksum (FNV-1a 64 of all before it, instance.c) made whole again."""
    body = data[:-8].replace(struct.pack("=d", old), struct.pack("=d", new))
    assert body != data[:-8]
    h = 1469598103934665603
    for byte in body:
        h = ((h ^ byte) * 1099511628211) % 2**64
    return body + struct.pack("=Q", h)


def test_serialized_state_restores_bit_for_bit_and_damaged_bytes_are_refused(native):
    """fmi2SerializeFMUstate of the forming field into a fresh instance: the same steps
    give the same doubles. Bytes with a flipped bit (checksum), cut short (length), or
    intact but holding a non-finite output (the content check) are refused with
    fmi2Error naming why; the instance is unchanged and steps on."""
    from fmpy.fmi1 import FMICallException

    with start(native) as a, start(native) as b:
        steps(a, 25)
        state = a.get_state()
        data = a.serialize_state(state)
        peak = a.get("tau_peak")  # as the bytes hold it (the output and the field's copy)
        steps(a, 10)
        b.set_state(b.deserialize_state(data, state[1]))
        steps(b, 10)
        assert b.outputs() == a.outputs()
        flipped = bytearray(data)
        flipped[len(data) // 2] ^= 0x10  # inside the field's tractions
        nan_peak = _payload_replaced(data, peak, math.nan)
        for bad, reason in ((bytes(flipped), "checksum"), (data[:-9], "length"),
                            (nan_peak, "is not a finite float")):  # fmt: skip
            before = b.outputs()
            with pytest.raises(FMICallException) as e:
                b.deserialize_state(bad, b.time)
            assert e.value.status == ERROR and reason in b.messages[-1][1], b.messages[-1:]
            assert b.outputs() == before
            steps(b, 1)
        assert all(s < FATAL for s, _ in b.messages)


# ---- hostile and unsupported inputs -------------------------------------------------------------
def test_lift_off_is_discarded_alike_and_the_instance_recovers(native, python):
    """P = 0 (lift-off) leaves the traction field without a contact: doStep answers
    fmi2Discard on both targets in the same words, naming P; the outputs stay, and with P
    restored the native instance steps to the doubles of one that never saw it."""
    words = {}
    for name, path in (("native", native), ("pythonfmu", python)):
        with start(path) as b:
            steps(b, 3)
            before = b.outputs()
            b.set("P", 0.0)
            assert b.step(H) == DISCARD
            words[name] = [m.split(": ", 1)[1] for s, m in b.messages if s == DISCARD]
            assert b.outputs() == before
            b.set("P", SCENE.config.starts["P"])
            steps(b, 2)
            if name == "native":
                with start(path) as clean:
                    steps(clean, 5)
                    assert b.outputs() == clean.outputs()
    assert words["native"] == words["pythonfmu"]
    assert "P = 0.0 is invalid: must be > 0 in the transient phase" in words["native"][0]


def test_a_budget_below_one_field_step_is_discarded_alike(native, python):
    """max_work below one internal step of the 32 x 16 field (2 nx ny = 1024 work units):
    every doStep answers fmi2Discard naming max_work and the step's cost, on both targets
    in the same words."""
    words = []
    for path in (native, python):
        with start(path, max_work=1000.0) as b:
            assert b.step(H) == DISCARD
            words.append([m.split(": ", 1)[1] for s, m in b.messages if s == DISCARD])
    assert words[0] == words[1]
    assert ("max_work = 1000.0 is invalid: must be >= 1024, the work of one internal step "
            "on the 32 x 16 field") in words[0][0]  # fmt: skip


def test_a_capped_step_warns_alike_and_takes_the_budgets_steps(native, python):
    """max_work = 2048 allows two internal steps of the field; a communication step of
    5 h needs more (cells_per_step = 0.5 at 5.6 m/s: 3.5 cells): both targets answer
    fmi2Warning in the same words (fmpy passes the step as taken), and take it in the same
    two steps (outputs within 1e-9 of their scale)."""
    outs, words = [], []
    for path in (native, python):
        with start(path, max_work=2048.0) as b:
            assert b.step(5 * H) == OK and b.time == 5 * H
            words.append([m for s, m in b.messages if s == WARNING])
            outs.append(b.outputs())
    assert words[0] == words[1] and "taken in 2 steps of" in words[0][0], words
    for k, v in outs[1].items():
        scale = MU_P if k in ("Tx", "Ty") else max(abs(v), 1e-300)
        assert abs(outs[0][k] - v) <= RTOL * scale, k


def test_a_load_drop_is_followed_and_a_load_beyond_the_field_refused(native, python):
    """A lower load (900 N), then a lower friction coefficient (mu = 0.2, tunable): both
    targets keep the field, shrink the ellipse (Eq. 34), cap the tractions at the new mu p
    and step on to the same outputs within 1e-9 of their scale (set_load within the
    lattice laid at the set-up load; set_mu). A higher load (1100 N), whose contact
    outgrows that lattice, the pythonfmu FMU follows by adding columns and strips; the
    native FMU, whose field has the scene's fixed size, answers fmi2Discard naming P, and
    steps on once P is back within it."""
    outs = []
    for path in (native, python):
        with start(path) as b:
            steps(b, 10)
            b.set("P", 900.0)
            steps(b, 10)
            b.set("mu", 0.2)  # tunable: the law's bound mu p from the next step on
            steps(b, 5)
            outs.append(b.outputs())
    for k, v in outs[1].items():
        scale = 0.2 * 900.0 if k in ("Tx", "Ty") else max(abs(v), 1e-300)
        assert abs(outs[0][k] - v) <= RTOL * scale, k
    with start(native) as b:
        steps(b, 3)
        before = b.outputs()
        b.set("P", 1100.0)
        assert b.step(H) == DISCARD
        text = b.messages[-1][1]
        assert "P = 1100.0 is invalid: must be at most the load at set-up" in text, text
        assert b.outputs() == before
        b.set("P", 1000.0)
        steps(b, 2)


@pytest.mark.parametrize(
    ("name", "value", "requirement"),
    [
        ("nx", 64, "must be 32, the field size this native FMU is compiled for"),
        ("ny", 3, "must be 16, the field size this native FMU is compiled for"),
        ("nx", 3, "must be >= 4"),
        ("field_times", "1e-3 soon", "must be times in s separated by spaces or commas"),
        ("field_times", "1e-3, nan", "must be finite times in s"),
        ("field_times", "1 2 3 4 5 6 7 8 9", "must be at most 8 times (the native FMU's"),
    ],
)
def test_a_grid_or_field_file_the_native_fmu_cannot_carry_is_refused_naming_it(
    native, name, value, requirement
):
    """The field's size is compiled in (nx = 32, ny = 16, the scene's), and the field
    file's times are parsed as body_transient.parse_times does, into at most 8 captures:
    another grid or times that are not finite numbers are refused at once with fmi2Error
    naming the variable, its value and what it must be (the pythonfmu FMU refuses such
    times at initialisation), and the model cannot start while one is held; the declared
    range is checked first (nx = 3 < 4)."""
    from fmpy.fmi1 import FMICallException

    with pytest.raises(FMICallException) as e:
        with Instance(native, "bad", {name: value}) as b:
            pass
    assert e.value.status == ERROR
    with Instance(native, "bad", initialise=False) as b:
        with pytest.raises(FMICallException):
            b.set(name, value)
        shown = repr(value) if isinstance(value, str) else str(value)
        text = f"{name} = {shown} is invalid: {requirement}"
        assert any(text in m for s, m in b.messages if s == ERROR), b.messages
        assert b.get(name) == value
    with Instance(native, "good", {"nx": 32, "ny": 16, "field_times": "1e-3; 2e-3"}) as b:
        assert (b.get("nx"), b.get("ny")) == (32, 16)
        steps(b, 1)


def _field(path: Path) -> np.ndarray:
    """A field file's rows (its header checked: body_transient.FIELD_COLUMNS)."""
    from contact_fmu.fmu.body_transient import FIELD_COLUMNS

    assert path.read_text().split("\n", 1)[0] == ",".join(FIELD_COLUMNS)
    return np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)


def test_the_field_file_is_the_pythonfmu_ones(native, python, tmp_path):
    """The scene's field file (5 captures of the 32 x 16 nodes at 0.2 to 7 ms, each case)
    written by the native FMU: the same rows as the pythonfmu FMU's file, the requested
    and reached times, indices, x, y, p and the slip and inside flags identical, the
    tractions and weights within 1e-9 of each column's largest magnitude (the field's
    geometry laid in C: an ulp apart, as the outputs)."""
    got = runner.simulate(native, SCENE, field_dir=tmp_path / "native")
    ref = runner.simulate(python, SCENE, field_dir=tmp_path / "pythonfmu")
    assert all(r.error is None for r in got + ref)
    for case in SCENE.cases:
        a = _field(SCENE.field.path(tmp_path / "native", case.name))
        b = _field(SCENE.field.path(tmp_path / "pythonfmu", case.name))
        assert a.shape == b.shape == (5 * 32 * 16, 12)
        exact = [0, 1, 2, 3, 4, 5, 8, 9, 10]  # requested, time, i, j, x, y, p, slip, inside
        assert np.array_equal(a[:, exact], b[:, exact]), case.name
        for col in (6, 7, 11):  # tau_x, tau_y, weight
            assert np.max(np.abs(a[:, col] - b[:, col])) <= RTOL * np.max(np.abs(b[:, col]))


def test_the_field_file_follows_a_restored_state_and_an_unwritable_one_is_refused(
    native, python, tmp_path
):
    """FieldRecorder's rules: a state set back before a capture rewrites the file with the
    captures of that state (one, here, then both again after stepping on); a file that
    cannot be written discards the step that reaches a requested time on both targets,
    naming field_file and its value, the state unchanged."""
    path = tmp_path / "deep" / "field.csv"  # its folder made by the FMU
    with start(native, field_file=str(path), field_times=f"{2 * H!r} {6 * H!r}") as b:
        steps(b, 3)
        assert len(_field(path)) == 512
        state = b.get_state()
        steps(b, 4)
        both = _field(path)
        assert len(both) == 1024
        b.set_state(state)
        assert np.array_equal(_field(path), both[:512])
        b.time = 3 * H
        steps(b, 4)
        assert np.array_equal(_field(path), both)
    said = []
    for fmu in (native, python):
        bad = "/dev/null/field.csv"  # under a file: no folder can be made there
        with start(fmu, field_file=bad, field_times=repr(2 * H)) as b:
            steps(b, 1)
            before = b.outputs()
            assert b.step(H) == DISCARD
            said.append(b.messages[-1][1].split(" (", 1)[0])
            assert b.outputs() == before
    assert said[0] == said[1]
    assert said[0].endswith(f"field_file = '{bad}' is invalid: must be a writable file"), said


def test_a_non_finite_load_is_refused_and_the_instance_recovers(native):
    """Fx_ex = NaN: fmi2Error at setReal naming it, fmi2Discard at doStep with the same
    words, the outputs kept; corrected, the instance steps to the doubles of one that
    never saw it."""
    from fmpy.fmi1 import FMICallException

    with start(native) as clean:
        steps(clean, 4)
        expected = clean.outputs()
    with start(native) as b:
        steps(b, 2)
        good, before = b.get("Fx_ex"), b.outputs()
        with pytest.raises(FMICallException):
            b.set("Fx_ex", math.nan)
        assert b.step(H) == DISCARD
        assert "Fx_ex = nan is invalid: must be finite" in b.messages[-1][1]
        assert b.outputs() == before
        b.set("Fx_ex", good)
        steps(b, 2)
        assert b.outputs() == expected


@pytest.mark.parametrize(
    ("Fx_ex", "words"),
    [
        (1e12, "Vx = 20000005.65853728 is invalid: must be within abs <= 10000 (the loads"),
        (
            1e200,
            "FloatingPointError: the step would roll the traction field's lattice by more than "
            "1e+09 columns",
        ),
    ],
)
def test_a_step_the_field_cannot_take_is_discarded_and_the_instance_recovers(
    native, python, Fx_ex, words
):
    """A finite load far beyond mu P: at 1e12 N the body leaves the speed range within
    the step (both targets: fmi2Discard, the same words, naming Vx); at 1e200 N the stage
    would roll the lattice by more columns than the field indexes (thin_layer_field.
    SHIFT_MAX, field.c's CF_FIELD_RANGE): fmi2Discard with that reason on both targets,
    in the same words. The state is unchanged: with the load restored the
    native instance steps to the doubles of one that never saw it."""
    with start(native) as clean:
        steps(clean, 4)
        expected = clean.outputs()
    said = []
    for path in (native, python):
        with start(path) as b:
            steps(b, 2)
            good, before = b.get("Fx_ex"), b.outputs()
            b.set("Fx_ex", Fx_ex)
            assert b.step(H) == DISCARD
            said.append(b.messages[-1][1])
            assert b.outputs() == before
            b.set("Fx_ex", good)
            steps(b, 2)
            if path == native:
                assert b.outputs() == expected
    assert "discarded, state unchanged: " + words in said[0], said
    assert said[0] == said[1]


# ---- C importers ---------------------------------------------------------------------------------
def _spec(md, rows: bool = True) -> str:
    """The importers' input for the eta = 2.92 case: its Real parameters (nx and ny are
    Integers at their fixed starts), the inputs per step."""
    real = {v.valueReference for v in md.modelVariables if v.type == "Real"}
    lines = native_c.spec(md, SCENE, CASE, rows).split("\n")
    pairs = lines[2].split()[1:]
    kept = [(a, b) for a, b in zip(pairs[::2], pairs[1::2], strict=True) if int(a) in real]
    lines[2] = f"{len(kept)} " + " ".join(f"{a} {b}" for a, b in kept)
    return "\n".join(lines)


def test_sanitized_importer_runs_the_transient_fmu_and_random_calls_cleanly(native, tmp_path):
    """The transient FMU's sources (field.c included) and the C importer in one program
    under AddressSanitizer and UBSan (no recovery): the eta = 2.92 case to the doubles
    the plain importer gets from the shipped binary (dlopened), then 2 x 600 random calls
    (extreme and non-finite values of inputs and parameters, huge, zero and non-finite
    steps, steps at the wrong time, FMU states got, set, serialized, damaged and refused,
    resets) with no sanitizer report, no fmi2Fatal and no non-finite output served with
    fmi2OK."""
    import fmpy

    unzip = tmp_path / "fmu"
    fmpy.extract(str(native), str(unzip))
    md = fmpy.read_model_description(str(unzip))
    spec = tmp_path / "spec.txt"
    spec.write_text(_spec(md))
    try:
        exe = native_c.sanitized(tmp_path / "importer_asan", native_c.IMPORTER2, unzip)
    except subprocess.CalledProcessError as e:  # pragma: no cover - gcc without libasan
        pytest.skip(f"no sanitizer runtime: {e.stderr[-300:]}")
    ident = md.coSimulation.modelIdentifier
    plain = native_c.compile_c(tmp_path / "importer", str(native_c.IMPORTER2), "-ldl")
    lib = unzip / "binaries" / "linux64" / f"{ident}.so"
    runs = []
    for program, library in ((exe, "-"), (plain, str(lib))):
        args = [str(program), library, md.guid, ident, "run", str(spec)]
        proc = subprocess.run(args, capture_output=True, text=True, timeout=600)
        assert proc.returncode == 0, proc.stderr[-3000:]
        lines = [ln for ln in proc.stdout.split("\n") if ln]
        runs.append(np.array([[float.fromhex(x) for x in ln.split()] for ln in lines]))
    assert runs[0].shape == (SCENE.n_steps, len(SCENE.outputs) - 1)  # the Reals, each step
    assert np.array_equal(runs[0], runs[1])
    short = tmp_path / "params.txt"
    short.write_text(_spec(md, rows=False))
    counts: dict[str, int] = {}
    for seed in range(2):
        args = [str(exe), "-", md.guid, "fuzz", "fuzz", str(short), str(seed), "600"]
        proc = subprocess.run(args, capture_output=True, text=True, timeout=600)
        assert proc.returncode == 0, proc.stderr[-3000:]
        assert "runtime error" not in proc.stderr and "Sanitizer" not in proc.stderr
        for k, v in dict(zip(*[iter(proc.stdout.split())] * 2, strict=True)).items():
            counts[k] = counts.get(k, 0) + int(v)
    assert counts["ok"] > 300 and counts["discard"] > 20, counts


@pytest.mark.skipif(not native_c.HAS_VALGRIND, reason="no valgrind")
def test_memcheck_finds_no_error_in_the_shipped_transient_binary(native, tmp_path):
    """The shipped binary (optimised, dlopened by the plain C importer) under valgrind's
    memcheck, which sees what the sanitizers' rebuild cannot (the field's scratch and
    trial copy read before written, a leak of them at free): the eta = 2.92 case to the
    plain run's doubles, 300 random calls and 100 FMU states held, set and freed in
    shuffled orders, with no invalid read or write, no use of an undefined value and no
    definite leak."""
    import fmpy

    unzip = tmp_path / "fmu"
    fmpy.extract(str(native), str(unzip))
    md = fmpy.read_model_description(str(unzip))
    spec = tmp_path / "spec.txt"
    spec.write_text(_spec(md))
    exe = str(native_c.compile_c(tmp_path / "importer", str(native_c.IMPORTER2), "-ldl"))
    ident = md.coSimulation.modelIdentifier
    head = (exe, str(unzip / "binaries" / "linux64" / f"{ident}.so"), md.guid, ident)
    plain = subprocess.run([*head, "run", str(spec)], capture_output=True, text=True, check=True)
    assert native_c.memcheck(*head, "run", str(spec)) == plain.stdout
    assert len(plain.stdout.split("\n")) == SCENE.n_steps + 1
    short = tmp_path / "params.txt"
    short.write_text(_spec(md, rows=False))
    out = native_c.memcheck(*head, "fuzz", str(short), "0", "300").split()
    counts = {k: int(v) for k, v in zip(out[::2], out[1::2], strict=True)}
    assert counts["ok"] > 60 and counts["discard"] + counts["refused"] > 10, counts
    native_c.memcheck(*head, "states", str(short), "100")
