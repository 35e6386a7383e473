"""The transient field in C (contact_fmu/native/field.c) against the Python reference it
mirrors: the field's stage (thin_layer_field.LayerField.stage, _weights: cf_field_stage,
cf_field_weights) and the body's steps on it (TransientRollingBody.advance, _step,
_stage, _solve_scalar: cf_field_advance), and their hostile inputs.

Tolerances. field.c repeats the Python arithmetic in its order and sums as numpy does
(pairwise); what differs is numpy's z**3 (its own SIMD power) against the C's z z z,
an ulp or so in the antiderivative of mu p inside the quadrature weights. A
stage's force is a sum over the ny nx = 512 nodes of terms each below mu p w, so the
two stages agree to a few ulp times the cell count relative to mu P: 512 x 4 x 2.2e-16
= 4.5e-13 (STAGE_RTOL = 1e-12 of mu P). Along a trajectory the stage solves stop within
SOLVE_RTOL = 1e-13 of their scale, and the L-stable step does not amplify a difference
(each stage is a contraction of the previous state's), so a run of hundreds of steps
stays within 1e-9 of mu P (TRAJ_RTOL: about 2000 times the stage bound; measured:
below 1e-15 on fig12_transient).
"""

from __future__ import annotations

import ctypes
import math
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

from contact_fmu import examples as ex
from contact_fmu import native
from contact_fmu._validate import InputError
from contact_fmu.dynamics.body import Body, Lateral, Loads
from contact_fmu.dynamics.integrator import StageSolveError
from contact_fmu.dynamics.thin_layer_field import LayerField, TransientRollingBody
from contact_fmu.fmu import body_transient
from contact_fmu.laws.thin_layer import LayerContact
from contact_fmu.native import field as native_field
from contact_fmu.scenario import load

ROOT = Path(__file__).resolve().parents[1]
SCENE = load(ROOT / "scenarios" / "fig12_transient.toml")
# what runs the library (the compile and sanitizer tests at the end need only a compiler)
needs_library = pytest.mark.skipif(
    native_field.library() is None, reason="no compiled library (no C compiler, or disabled)"
)

STAGE_RTOL = 1e-12  # of mu P (forces), mu p0 (tractions): see the module docstring
TRAJ_RTOL = 1e-9  # of mu P, over a trajectory
P = SCENE.config.starts["P"]
LAW = LayerContact(P, *(SCENE.config.starts[k] for k in ("Rx", "Ry", "k1", "k2", "kb", "ks", "mu")))
MU_P = LAW.mu * LAW.P
V = SCENE.config.starts["Vx0"]


def _count(monkeypatch) -> dict[str, int]:
    """Counts the stages served by the C (so that agreement is not with Python itself)."""
    counts = {"stage": 0, "advance": 0}
    for name in counts:
        method = getattr(native_field.CompiledField, name)

        def counted(self, *a, _m=method, _n=name, **k):
            r = _m(self, *a, **k)
            counts[_n] += r is not None
            return r

        monkeypatch.setattr(native_field.CompiledField, name, counted)
    return counts


def _model(case, native_on: bool, **inputs: float):
    """The transient body FMU's model (body_transient.build) for a case of the scene."""
    params = {**SCENE.config.starts, **case.parameters, "field_file": "", "field_times": ""}
    ins = {"P": P, "Fx_ex": SCENE.config.starts["Fx_ex"], **inputs}
    model = body_transient.build(SCENE.config, params, ins, 0.0)
    model.stepper.field.native = native_on
    if not native_on:  # build's outputs ran compiled weights: from here on, Python
        model.stepper.field.__dict__.pop("_cf", None)
    return model, ins


@needs_library
@pytest.mark.parametrize("case", SCENE.cases, ids=[c.name for c in SCENE.cases])
def test_fig12_transient_compiled_repeats_the_python_field(monkeypatch, case):
    """Fig. 12's transient phase (the field forming after Fx_ex = 3 mu p0 a1 a2, 32 x
    16 cells, half a cell per internal step) through the FMU's body step, 120
    communication steps (2.4 ms: the oscillation and the first approach to Eq. 26): the
    compiled field gives the reference's outputs within TRAJ_RTOL of mu P (forces), of
    the slip velocity scale creep_full_slip Vx (speeds), of mu p0 (peak traction) and
    of a1 (centroid); the adhesion fraction within 1e-9, the same regime."""
    counts = _count(monkeypatch)
    fast, ins = _model(case, True)
    slow, _ = _model(case, False)
    v_scale = LAW.creep_full_slip * V
    for _ in range(120):
        fast.step(SCENE.config.experiment[2], ins)
        slow.step(SCENE.config.experiment[2], ins)
        a, b = fast.stepper.outputs(), slow.stepper.outputs()
        for key, scale in (("Tx", MU_P), ("Ty", MU_P), ("Mz", MU_P * LAW.a1), ("vx", v_scale),
                           ("Vx", v_scale), ("tau_peak", LAW.mu * LAW.p0),
                           ("slip_centroid_x", LAW.a1), ("adhesion", 1.0)):  # fmt: skip
            assert abs(a[key] - b[key]) <= TRAJ_RTOL * scale, (key, a[key], b[key])
        assert a["regime"] == b["regime"]
    assert slow.stepper.field.__dict__.get("_cf") is None  # the reference ran in Python
    assert counts["advance"] == 120  # each communication step in one C call


def _developed_field(law: LayerContact = LAW) -> LayerField:
    """A field with adhesion and slip zones: rolled 40 half cells at a creepage near the
    full-slip one, with lateral creep and spin."""
    f = LayerField(law, 32, 16)
    for _ in range(40):
        f.roll(0.5 * f.dx / V, 0.6 * law.creep_full_slip * V, 0.3 * law.creep_full_slip * V,
               V, 2.0)  # fmt: skip
    return f


def _both(f: LayerField, base, hat, args: tuple, **kw):
    """The stage compiled, and in Python, of one field."""
    f.native = True
    a = f.stage(base, hat, *args, **kw)
    f.native = False
    b = f.stage(base, hat, *args, **kw)
    f.native = True
    return a, b


def _assert_stage_agrees(a, b, law: LayerContact, y: np.ndarray) -> None:
    """Two StageFields equal to rounding: the lattice exactly, masks equal, tractions
    within STAGE_RTOL mu p0, each node's force and the resultant within STAGE_RTOL mu
    P, the tangents within STAGE_RTOL of the size of their terms (a sum of the same 512
    nodes' terms)."""
    assert (a.theta, a.shift) == (b.theta, b.shift)
    assert np.array_equal(a.x, b.x)
    assert np.array_equal(a.inside, b.inside) and np.array_equal(a.slip, b.slip)
    tau = law.mu * law.p0
    assert np.max(np.abs(a.tau_x - b.tau_x)) <= STAGE_RTOL * tau
    assert np.max(np.abs(a.tau_y - b.tau_y)) <= STAGE_RTOL * tau
    # a node's weight comes from differences of the antiderivative of mu p (and the
    # square root of a discriminant that vanishes where the adhesion line touches the
    # cap): its relative rounding is not bounded, its force |tau| w is (ulps of mu p l dx)
    node_force = np.abs(a.weights - b.weights) * np.hypot(b.tau_x, b.tau_y)
    assert np.max(node_force) <= STAGE_RTOL * law.mu * law.P
    untouched = (b.tau_x == 0.0) & (b.tau_y == 0.0)  # area weights: no power, no root
    assert np.array_equal(a.weights[untouched], b.weights[untouched])
    Ta, Tb = np.array(a.resultant(y)), np.array(b.resultant(y))
    scale = np.array([1.0, 1.0, law.a1]) * law.mu * law.P
    assert np.all(np.abs(Ta - Tb) <= STAGE_RTOL * scale), (Ta, Tb)
    assert abs(a.dTx_dvx - b.dTx_dvx) <= STAGE_RTOL * max(abs(b.dTx_dvx), 1e-300)
    if b.jacobian is not None:
        # the terms' size: sum g (the force block) times a1 for a moment (row Mz) and
        # for a spin (column Omega_z): x, y <= a1 on the contact
        L = np.array([1.0, 1.0, law.a1])
        scale = np.max(np.abs(b.jacobian[:2, :2])) * np.outer(L, L) + 1e-300
        assert np.all(np.abs(a.jacobian - b.jacobian) <= STAGE_RTOL * scale)


def _stage_inputs(rng: np.random.Generator, f: LayerField) -> tuple:
    """(ds, elapsed, h_own, vx, vy, phi, Vx) of a stage: forward and backward rolling,
    standstill, several cells and beyond the grid, sliding (10 x the full-slip creep),
    Vx of the other sign than ds or 0 (a reversal within the step), spin."""
    cells = rng.choice([0.0, 0.3, 1.7, 5.5, 40.0])
    ds = rng.choice([-1.0, 1.0]) * cells * f.dx
    h = abs(ds) / V if ds else 1e-5
    slip = LAW.creep_full_slip * V * rng.choice([0.0, 0.2, 1.0, 10.0])
    vx, vy = slip * rng.standard_normal(2)
    phi = rng.choice([0.0, 0.0, 5.0, -300.0])
    Vx = rng.choice([np.sign(ds) * V, -np.sign(ds) * V, 0.0, 1e-3 * V]) if ds else 0.0
    return ds, h, h * (1.0 - 0.5 * math.sqrt(2.0)), vx, vy, phi, Vx


@needs_library
@pytest.mark.parametrize("change", ["none", "load down", "load up", "mu", "cattaneo", "tiny P"])
def test_stage_agrees_with_the_python_stage_over_hostile_stages(change):
    """300 random stages of a developed field (adhesion and slip, spin) after a change
    of its contact (a load drop to 1 % and a rise to 4 times: the lattice and strips
    grow; mu halved; a Cattaneo shift at rest; P = 1e-6 N), each with and without the
    Jacobian and the mid-path spin of ``roll``: the compiled stage equals the Python one
    to rounding (see _assert_stage_agrees)."""
    rng = np.random.default_rng(12)
    f = _developed_field()
    if change == "load down":
        f.set_load(0.01 * P)
    elif change == "load up":
        f.set_load(4.0 * P)
    elif change == "mu":
        f.law = f.law.with_mu(0.15)
    elif change == "cattaneo":
        f.set_shift(0.5 * LAW.mu * LAW.p0 * LAW.k, -0.2 * LAW.mu * LAW.p0 * LAW.k)
    elif change == "tiny P":
        f.set_load(1e-6)
    law = f.law
    base = f.begin()
    served = 0
    for _ in range(300):
        args = _stage_inputs(rng, f)
        c = 0.3 + rng.random()
        hat = (base.tau_x * c, base.tau_y * (1.0 - c))
        kw = {"jacobian": bool(rng.integers(2)), "midpath": bool(rng.integers(2))}
        a, b = _both(f, base, hat, args, **kw)
        served += a.T is not None
        _assert_stage_agrees(a, b, law, f.y)
    assert served == 300  # every one of these stages ran in C


@needs_library
def test_weights_of_the_field_at_rest_agree():
    """LayerField.current and summary (the FMU's outputs each step): the compiled
    weights, area weights and summary (cf_field_summary: adhesion fraction, slip-area
    centroid, peak traction; sums of the same weights) equal the Python ones to
    rounding, after rolling either way."""
    for direction in (1.0, -1.0):
        f = _developed_field()
        f.roll(2.5 * f.dx / V, 0.3 * LAW.creep_full_slip * V, 0.0, direction * V)
        x = f.positions()
        inside, _ = f._geometry(x)
        for tau in ((f.tau_x, f.tau_y), (None, None)):
            f.native = True
            a = f._weights(x, inside, *tau, f.direction, f.slip)
            f.native = False
            b = f._weights(x, inside, *tau, f.direction, f.slip)
            assert np.max(np.abs(a - b)) <= STAGE_RTOL * np.max(b)
        f.native = True
        s_c = f.summary()
        f.native = False
        s_p = f.summary()
        assert abs(s_c["adhesion"] - s_p["adhesion"]) <= 1e-12
        for key in ("slip_centroid_x", "slip_centroid_y"):
            assert abs(s_c[key] - s_p[key]) <= 1e-12 * LAW.a1
        assert abs(s_c["tau_peak"] - s_p["tau_peak"]) <= STAGE_RTOL * LAW.mu * LAW.p0
        assert 0.0 < s_c["adhesion"] < 1.0 and s_c["tau_peak"] > 0.0  # slip and adhesion


def _stage_rc(f: LayerField, base, ds: float, vx: float) -> int:
    """cf_field_stage's answer for a stage (ds, vx) of f, called directly."""
    c = f._compiled()
    n = f.ny * f.nx
    out = [np.empty(f.nx)] + [np.empty(n) for _ in range(3)]
    masks = [np.empty(n, np.uint8) for _ in range(2)]
    keep = [np.ascontiguousarray(a) for a in (base.inside, base.tau_x, base.tau_y)]
    s = native_field.StageIn(base.theta, *(a.ctypes.data for a in keep),
                             ds, 1e-5, 3e-6, vx, 0.0, 0.0, V, 0, 1)  # fmt: skip
    o = native_field.StageOut()
    o.x, o.tau_x, o.tau_y, o.w = (a.ctypes.data for a in out)
    o.slip, o.inside = (a.ctypes.data for a in masks)
    o.work = c.work.ctypes.data
    return c.lib.cf_field_stage(ctypes.byref(c.struct), ctypes.byref(s), ctypes.byref(o))


@needs_library
@pytest.mark.filterwarnings("ignore:overflow:RuntimeWarning", "ignore:invalid:RuntimeWarning")
@pytest.mark.parametrize(
    ("ds_cells", "vx", "code"),
    [
        (0.5, math.nan, 1),  # a NaN slip velocity: CF_FIELD_BAD_INPUT
        (math.inf, 0.0, 1),  # an infinite distance rolled
        (3e9, 0.0, 2),  # 3e9 columns in one stage: CF_FIELD_RANGE (Python's int takes it)
        (-2e300, 0.0, 2),
        (0.5, 1e304, 3),  # a huge finite slip overflows the trial traction: NONFINITE
    ],
)
def test_inputs_the_c_declines_are_taken_by_the_python_path(ds_cells, vx, code):
    """What field.c does not serve it answers with a code (no NaN served, no UB: the
    sanitizer test below), and LayerField.stage then gives the Python path's field:
    the same arrays (NaN where the reference has NaN)."""
    f = _developed_field()
    base = f.begin()
    ds = ds_cells * f.dx
    assert _stage_rc(f, base, ds, vx) == code
    args = (ds, 1e-5, 3e-6, vx, 0.0, 0.0, V)
    outcomes = []
    for native_on in (True, False):
        f.native = native_on
        try:
            outcomes.append(f.stage(base, (base.tau_x, base.tau_y), *args))
        except (ArithmeticError, ValueError) as e:  # the reference's own answer
            outcomes.append((type(e), str(e)))
    a, b = outcomes
    if isinstance(b, tuple):
        assert a == b
        return
    assert a.T is None  # not served by the C
    for name in ("x", "tau_x", "tau_y", "weights", "slip", "inside"):
        assert np.array_equal(getattr(a, name), getattr(b, name), equal_nan=name != "slip")


def _body(native_on: bool, Vx0: float = V) -> TransientRollingBody:
    body = Body(M=1.0, Rx=0.05, Iy=8.56e-4)  # eta = 2.92
    rb = TransientRollingBody(LAW, body, Lateral(vy_ratio=0.002, spin_ratio=0.0), Vx0=Vx0,
                              Omega_y0=Vx0 / body.Rx, nx=32, ny=16)  # fmt: skip
    rb.field.native = native_on
    return rb


@needs_library
@pytest.mark.parametrize(
    ("what", "Vx0", "Fx", "steps"),
    [
        ("gross sliding", V, 10.0, 40),  # Fx_ex = 10 mu P: no adhesion left
        ("reversal", 0.05, -1.0, 80),  # braking through Vx = 0 into backward rolling
        ("from standstill", 0.0, 0.5, 60),  # the field at Vx = 0, then rolling
    ],
)
def test_bodies_in_sliding_reversal_and_standstill_agree(monkeypatch, what, Vx0, Fx, steps):
    """The body on the field (SDIRK2 with the field's stage, cf_field_advance) through
    gross sliding, a reversal of the rolling direction (Vx through 0: the entering
    material's time from the elapsed time) and a start from standstill: the compiled
    body within TRAJ_RTOL of mu P of the reference, speeds within TRAJ_RTOL of the slip
    scale, same regime; every step taken in C."""
    counts = _count(monkeypatch)
    a, b = _body(True, Vx0), _body(False, Vx0)
    loads = Loads(Fx_ex=Fx * MU_P)
    v_scale = LAW.creep_full_slip * V
    crossed = False
    for _ in range(steps):
        a.advance(2e-5, loads, 4)
        b.advance(2e-5, loads, 4)
        oa, ob = a.outputs(), b.outputs()
        for key, scale in (("Tx", MU_P), ("Ty", MU_P), ("vx", v_scale), ("Vx", v_scale)):
            assert abs(oa[key] - ob[key]) <= TRAJ_RTOL * scale, (key, oa[key], ob[key])
        assert oa["regime"] == ob["regime"]
        crossed |= oa["Vx"] < 0.0
    assert counts["advance"] == steps  # every step of a in C
    if what == "reversal":
        assert crossed
    if what == "gross sliding":
        assert oa["adhesion"] == 0.0 and abs(abs(oa["Tx"]) - MU_P) < 1e-3 * MU_P


@needs_library
@pytest.mark.parametrize(
    ("call", "error", "words"),
    [
        (lambda rb: rb.set_load(0.0), InputError, "P = 0.0"),  # lift-off: not transient
        (lambda rb: rb.advance(2e-5, Loads(Fx_ex=math.nan)), InputError, "Fx_ex = nan"),
        (lambda rb: rb.advance(2e-5, Loads(Fx_ex=1e300)), FloatingPointError, "more than 1e+09"),
    ],
)
def test_refusals_are_the_python_paths(call, error, words):
    """The compiled field changes no refusal: lift-off (P = 0, the steady phase's), a
    NaN load and a load beyond any grid (the lattice would move by more columns than an
    index holds, thin_layer_field.SHIFT_MAX: the C declines it, the reference raises)
    raise the same error with the same words either way, and leave the state unchanged."""
    messages = []
    for native_on in (True, False):
        rb = _body(native_on)
        before = rb.snapshot()
        with pytest.raises(error) as e:
            call(rb)
        messages.append(str(e.value))
        assert np.array_equal(rb.y, before[0]) and rb.t == before[1]
    assert messages[0] == messages[1] and words in messages[0]


@needs_library
def test_no_stage_root_is_refused_the_same_way():
    """eta = inf (Iy = 0): Tx = -My/Rx is algebraic (Eq. 26), a moment beyond mu P Rx
    has no root: StageSolveError with the same message on both paths."""
    messages = []
    for native_on in (True, False):
        body = ex.body(math.inf)
        rb = TransientRollingBody(LAW, body, Vx0=V, Omega_y0=V / body.Rx, nx=32, ny=16)
        rb.field.native = native_on
        h = 2.0 * LAW.a1 / V / 16  # a sixteenth of the transit
        rb.advance(h, Loads(My_ex=-0.5 * MU_P * body.Rx))
        with pytest.raises(StageSolveError) as e:
            rb.advance(h, Loads(My_ex=-1.5 * MU_P * body.Rx))
        messages.append(str(e.value))
    assert messages[0] == messages[1] and "stage equation" in messages[0]


def test_without_the_library_the_field_runs_in_python(monkeypatch):
    """CONTACT_FMU_NATIVE=0 (as for the rest of native): no compiled field, the same
    stepping in Python."""
    monkeypatch.setenv("CONTACT_FMU_NATIVE", "0")
    monkeypatch.setattr(native, "_LOADED", {})
    f = LayerField(LAW, 16, 8)
    assert f._compiled() is None
    f.roll(f.dx / V, 0.5 * LAW.creep_full_slip * V, 0.0, V)
    assert f.current().T is None and abs(f.resultant()[0]) > 0.0


@needs_library
def test_field_pickles_and_deepcopies_without_its_ctypes_struct():
    """A LayerField that ran compiled keeps its struct out of pickle and deepcopy (FMU
    state, multiprocessing studies) and rebuilds it on use."""
    import copy
    import pickle

    f = _developed_field()
    assert f.__dict__.get("_cf") is not None
    for g in (copy.deepcopy(f), pickle.loads(pickle.dumps(f))):
        assert "_cf" not in g.__dict__
        g.roll(f.dx / V, 0.1 * LAW.creep_full_slip * V, 0.0, V)
        assert g.__dict__.get("_cf") is not None


def _cc() -> str | None:
    return shutil.which("gcc") or shutil.which("cc")


def test_field_c_compiles_cleanly_as_c99_with_all_warnings(tmp_path):
    """field.c with stepper.h: -std=c99 -Wall -Wextra -pedantic -Werror."""
    if _cc() is None:
        pytest.skip("no C compiler")
    src = Path(native.__file__).with_name("field.c")
    flags = ["-std=c99", "-Wall", "-Wextra", "-pedantic", "-Werror", "-c", "-o"]
    subprocess.run([_cc(), *flags, str(tmp_path / "field.o"), str(src)], check=True)


def test_sanitized_driver_runs_random_and_extreme_inputs_cleanly(tmp_path):
    """field.c and tests/native_field_driver.c in one program with AddressSanitizer and
    UBSan (float-to-int overflow included, no recovery): 2 x 3000 random stages on the
    fig12_transient grid with extreme values (NaN, inf, +-DBL_MAX, subnormals) in
    every input, damaged structs, NULL pointers; each call answers a field.h code, an OK
    stage serves finite numbers; every code occurs."""
    native_dir = Path(native.__file__).parent
    flags = ["-std=c99", "-fsanitize=address,undefined,float-cast-overflow",
             "-fno-sanitize-recover=all", "-fno-omit-frame-pointer", "-ffp-contract=off",
             f"-I{native_dir}"]  # fmt: skip
    exe = tmp_path / "field_asan"
    sources = [str(ROOT / "tests" / "native_field_driver.c"), str(native_dir / "field.c")]
    try:
        subprocess.run([_cc() or "cc", *flags, "-o", str(exe), *sources, "-lm"], check=True,
                       capture_output=True, text=True)  # fmt: skip
    except (subprocess.CalledProcessError, TypeError) as e:  # pragma: no cover
        pytest.skip(f"no sanitizer runtime: {getattr(e, 'stderr', '')[-300:]}")
    totals: dict[str, int] = {}
    for seed in (1, 2):
        proc = subprocess.run([str(exe), str(seed), "3000"], capture_output=True, text=True,
                              timeout=300)  # fmt: skip
        assert proc.returncode == 0, proc.stdout[-2000:] + proc.stderr[-3000:]
        assert "runtime error" not in proc.stderr and "Sanitizer" not in proc.stderr
        words = proc.stdout.split()
        for k, v in zip(words[::2], words[1::2], strict=True):
            totals[k] = totals.get(k, 0) + int(v)
    assert totals["ok"] > 3000 and min(totals.values()) > 50, totals


@needs_library
def test_the_transient_fmu_carries_the_field_in_its_compiled_library(tmp_path):
    """The pythonfmu FMU of fig12_transient vendors field.c, field.h and the binding with
    the kernel library, and that library (built from stepper.c and field.c) has the
    field's functions: inside the FMU the field steps compiled."""
    import zipfile

    import fmu_build

    path = fmu_build.build(SCENE.config, ROOT / "out" / "fmu").path
    with zipfile.ZipFile(path) as z:
        names = z.namelist()
        native_files = {n.rsplit("/native/", 1)[1] for n in names if "/native/" in n}
        assert {"field.c", "field.h", "field.py", native.library_name()} <= native_files
        lib = z.read(next(n for n in names if n.endswith("/native/" + native.library_name())))
    copy = tmp_path / native.library_name()
    copy.write_bytes(lib)
    loaded = ctypes.CDLL(str(copy))
    assert all(hasattr(loaded, f) for f in ("cf_field_stage", "cf_field_advance"))
