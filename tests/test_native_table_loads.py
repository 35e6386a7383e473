"""The native FMUs (FMI 2.0 and 3.0) on half-space creep-force tables of several load
nodes, with and without layers, against the pythonfmu FMU and the Python table.

Such a table holds the normalised forces at each load node and interpolates them in
log P by a spline (CreepTable._weights: make_interp_spline through the unit vectors, its
weights clamped to the nodes; CreepTable._coefficients_at: the weighted sum of the
nodes' patches). The native FMU carries every node's patches and the spline's knots and
coefficients in resources/table.bin and evaluates the weights in C (stepper.c's
load_weights: scipy's interval search and de Boor recursion) and the weighted sum for
the cell it needs; a table with layers (kb + ks > 0) refuses a load outside its nodes
(TableLaw.load_range) in the pythonfmu FMU's words. The tables here are small (an 8 x 8
solver grid, 7 x 5 x 3 nodes: seconds to build, cached under out/tables).
"""

from __future__ import annotations

import ctypes
import math
import re
import shutil
import subprocess
from pathlib import Path

import native_c
import numpy as np
import pytest
from fmpy.fmi1 import FMICallException
from fmpy.validation import validate_fmu
from test_native_fmi3 import Instance3, in_fmi3_words

import fmu_build
from contact_fmu import native
from contact_fmu.fmu.config import ModelConfig
from contact_fmu.halfspace.table import CreepTable
from contact_fmu.scenario import load
from contact_fmu.scenario.instance import DISCARD, ERROR, OK, Instance
from fmu_build import native_fmu, native_fmu3

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "out" / "fmu"
pytestmark = pytest.mark.skipif(shutil.which("cc") is None, reason="no C compiler")

V = 30.0  # m/s
W = V / 0.46  # rad/s: pure rolling of the 0.46 m wheel

# the rail wheel on a 0.6 m rail head, a coarse solver grid and few creepage nodes; four
# load nodes (a cubic spline, not-a-knot: every weight nonzero between the nodes) and
# layers as compliant as a quarter of the steel half-spaces (tests/test_fmu_halfspace.py)
LAYERED = {
    "body": {"Rx": 0.46, "Ry": "inf", "E": 210.0e9, "nu": 0.28},
    "substrate": {"Rx": "inf", "Ry": 0.6, "E": 210.0e9, "nu": 0.28},
    "kb": 1e-14,
    "ks": 1e-14,
    "mu": 0.3,
    "loads": [80.0e3, 95.0e3, 105.0e3, 120.0e3],
    "grid": 8,
    "xi_max": 0.014,
    "eta_max": 0.014,
    "phi_max": 1.5,
    "nodes": [7, 5, 3],
}
# without layers, three nodes (a quadratic spline): any P > 0 admitted, the weights
# clamped to the nodes beyond them
PLAIN = LAYERED | {"kb": 0.0, "ks": 0.0, "loads": [70.0e3, 100.0e3, 130.0e3]}
RANGE = "must be within the load range [80000, 120000] N of the FMU's creep-force table"


def body_config(spec: dict, name: str) -> ModelConfig:
    """rail_traction's body (M = 10 t, Iy = 120 kg m^2, 30 m/s) on the table of ``spec``."""
    d = load(ROOT / "scenarios" / "rail_traction.toml").config.to_dict()
    return ModelConfig.from_dict(
        d | {"name": name, "law_spec": spec, "starts": d["starts"] | {"P": 100e3}}
    )


def contact_config(spec: dict, name: str) -> ModelConfig:
    return ModelConfig(
        name=name,
        mode="contact",
        inputs=("P", "Vx", "Vy", "Omega_y", "Omega_z"),
        outputs=("Tx", "Ty", "Mz", "a1", "a2", "p0", "adhesion", "regime"),
        contact_law="halfspace",
        law_spec=spec,
        starts={"P": 100e3, "Vx": V, "Omega_y": W},
    )


@pytest.fixture(scope="module")
def fmus():
    """name -> {target: path}: body and contact FMUs on the layered table, a contact FMU
    on the plain one."""
    cfgs = {
        "body": body_config(LAYERED, "loads_body"),
        "contact": contact_config(LAYERED, "loads_contact"),
        "plain": contact_config(PLAIN, "loads_plain"),
    }
    return {
        n: {
            "pythonfmu": fmu_build.build(c, OUT).path,
            "native": native_fmu.build(c, OUT).path,
            "fmi3": native_fmu3.build(c, OUT).path,
        }
        for n, c in cfgs.items()
    }


# ---- the interpolation in P, in C against the Python table -----------------------------
def _kernel_table(cfg: ModelConfig):
    """The Python run-time law of ``cfg``'s table, and a Params of the compiled kernel
    holding every node's patches and the spline as the native FMU does (the arrays kept
    alive with it), with cf_table_law's constants from the FMU's header."""
    law = native_fmu._table_law(cfg)
    axes, coef = native_fmu._table_data(law)
    consts = {}
    for line in native_fmu._table_header(cfg):
        m = re.match(r"#define CF_T_(\w+) (\S+)$", line)
        if m:
            consts[m.group(1)] = float(m.group(2))
    p = native.Params(law=1, saturation_width=law.native_constants["saturation_width"])
    keep = [np.ascontiguousarray(a) for a in (*axes, coef)]
    p.ax1, p.ax2, p.ax3, p.coef = (a.ctypes.data for a in keep)
    p.n1, p.n2, p.n3 = (len(a) for a in axes)
    p.ext1, p.ext2, p.ext3 = (float(a[-1]) for a in axes)
    n = len(law.data.P)
    p.n_loads, p.spline_k = n, min(3, n - 1)
    p.spline = keep[-1].ctypes.data + 8 * n * int(consts["STRIDE"])
    return law, p, keep, consts


def test_load_interpolation_in_c_is_the_python_tables():
    """At loads on, between and beyond the four nodes of the layered table, the kernel's
    law (the Hertz ellipse and units of cf_table_law, the onset of full slip np.dot(w,
    onset) xi_ref, the forces of cf_table_forces from the weighted patches) equals the
    Python table's CreepTable at that load to rounding: the weights are the spline's by
    the same operations, the patch sums run in another order than numpy's (1e-12 of mu
    P, 1e-14 relative for the onset). The interpolation matters: between nodes the forces
    differ from the nearest node's table by more than 1e-4 mu P."""
    lib = native.library()
    lib.cf_table_law.argtypes = [ctypes.POINTER(native.Params)] + [ctypes.c_double] * 5 + [
        ctypes.c_int, ctypes.c_double, ctypes.c_double, ctypes.c_double,
        ctypes.POINTER(ctypes.c_double), ctypes.POINTER(ctypes.c_double)]  # fmt: skip
    lib.cf_table_forces.argtypes = [ctypes.POINTER(native.Params)] + [ctypes.c_double] * 4
    lib.cf_table_forces.argtypes += [ctypes.c_void_p]
    cfg = body_config(LAYERED, "loads_body")
    law, p, _keep, k = _kernel_table(cfg)
    rng = np.random.default_rng(5)
    moved = 0.0
    for P in (80e3, 87.5e3, 95e3, 99e3, 105e3, 111e3, 120e3, 60e3, 150e3):
        a2, p0 = ctypes.c_double(), ctypes.c_double()
        lib.cf_table_law(p, P, law.mu, k["KFAC"], k["M"], k["AMIN"], int(k["A_LE_B"]),
                         k["ESTAR"], k["G"], k["ONSET"], a2, p0)  # fmt: skip
        ref = CreepTable(law.data, P)  # the Python table at P (no range check)
        assert p.creep_full_slip == pytest.approx(ref.creep_full_slip, rel=1e-14, abs=0.0)
        assert (p.a1, a2.value) == pytest.approx((ref.a1, ref.a2), rel=1e-15)
        muP = law.mu * P
        for _ in range(20):
            xi, eta = rng.uniform(-0.02, 0.02, 2)
            phi = rng.uniform(-2.0, 2.0)
            out = np.zeros(4)
            lib.cf_table_forces(p, xi * V, eta * V, phi * V, V, out.ctypes.data)
            want = ref._scalar(xi * V, eta * V, phi * V, V)
            assert np.max(np.abs(out[:2] - want[:2])) <= 1e-12 * muP, (P, xi, eta, phi)
            assert abs(out[2] - want[2]) <= 1e-12 * muP * ref.c
            assert abs(out[3] - want[3]) <= 1e-12
        # the same load with the nearest node's patches alone
        nearest = float(min(law.data.P, key=lambda q: abs(q - P)))
        near = CreepTable(law.data, P, CreepTable(law.data, nearest)._coef)
        T = (t._scalar(0.004 * V, 0.0, 0.0, V)[0] for t in (near, ref))
        moved = max(moved, abs(next(T) - next(T)) / muP)
    assert moved > 1e-4, moved


# ---- the FMUs ------------------------------------------------------------------------------
def _drive_body(b, n: int = 120) -> dict[str, np.ndarray]:
    """n steps of 5 ms: P swept over the layered table's nodes (82 to 118 kN), a torque
    through traction and braking; each output's values."""
    rows = []
    for k in range(n):
        b.set("P", 100e3 * (1.0 + 0.18 * math.sin(k / 9)))
        b.set("My_ex", 12000.0 * math.sin(k / 23))
        assert b.step(5e-3) == OK, b.messages[-1:]
        rows.append(b.outputs())
    return {k: np.array([r[k] for r in rows]) for k in rows[0]}


def test_body_on_a_layered_table_of_four_loads_gives_the_pythonfmu_outputs(fmus):
    """The body of rail_traction on the layered four-node table, P swept across its nodes
    under a torque through traction and braking, both methods: the native FMU's outputs
    are the pythonfmu FMU's within 1e-12 of each output's scale (the same step, the table
    blended in C: rounding; measured equal), the FMI 3.0 FMU's the FMI 2.0 one's
    doubles; both FMUs validate."""
    paths = fmus["body"]
    assert validate_fmu(str(paths["native"])) == [] and validate_fmu(str(paths["fmi3"])) == []
    for method in ("full", "quasistationary"):
        runs = {}
        for target in ("native", "pythonfmu"):
            with Instance(paths[target], target, {"method": method}) as b:
                runs[target] = _drive_body(b)
        with Instance3(paths["fmi3"], start={"method": method}) as b3:
            got3 = _drive_body(b3)
        got, ref = runs["native"], runs["pythonfmu"]
        for k, r in ref.items():
            assert np.array_equal(got3[k], got[k]), (method, k)
            assert np.max(np.abs(got[k] - r)) <= 1e-12 * np.max(np.abs(r)), (method, k)
        assert np.max(np.abs(ref["Tx"])) > 0.5 * 0.3 * 82e3  # into the nonlinear range


@pytest.mark.parametrize("name", ["contact", "plain"])
def test_contact_on_tables_of_several_loads_gives_the_pythonfmu_outputs(fmus, name):
    """The contact mode on the layered table (loads within its nodes) and on the plain one
    (loads beyond its nodes too: the weights clamped, the ellipse at P): at 40 random
    kinematics and loads the native FMU's outputs are the pythonfmu FMU's within 1e-12
    of mu P (forces), 1e-12 relative (geometry) and 1e-12 (adhesion)."""
    paths = fmus[name]
    lo, hi = (80e3, 120e3) if name == "contact" else (40e3, 200e3)
    rng = np.random.default_rng(11)
    cases = [(rng.uniform(lo, hi), *rng.uniform(-0.01, 0.01, 2), rng.uniform(-1.0, 1.0))
             for _ in range(40)]  # fmt: skip
    runs = {}
    for target in ("native", "pythonfmu"):
        with Instance(paths[target], target) as b:
            rows = []
            for P, xi, eta, phi in cases:
                b.set("P", P)
                b.set("Omega_y", W * (1.0 - xi))
                b.set("Vy", eta * V)
                b.set("Omega_z", phi * V)
                assert b.step(1e-3) == OK, b.messages[-1:]
                rows.append(b.outputs())
            runs[target] = rows
    for (P, *_), a, r in zip(cases, runs["native"], runs["pythonfmu"], strict=True):
        for k in ("Tx", "Ty"):
            assert abs(a[k] - r[k]) <= 1e-12 * 0.3 * P, (k, P)
        assert abs(a["Mz"] - r["Mz"]) <= 1e-12 * 0.3 * P * r["a1"]
        for k in ("a1", "a2", "p0"):
            assert a[k] == pytest.approx(r[k], rel=1e-12), k
        assert abs(a["adhesion"] - r["adhesion"]) <= 1e-12 and a["regime"] == r["regime"]


def test_fmu_state_of_the_blended_table_repeats_bit_for_bit(fmus):
    """The layered body FMU: a state got between nodes (P = 90 kN), four steps at other
    loads, the state set and the same four steps again: the same doubles; through bytes
    into a fresh instance too (the table's arrays attached anew, the blend at the
    state's load)."""
    path = fmus["body"]["native"]

    def step(b, k: int) -> None:
        b.set("P", 85e3 + 7e3 * k)
        b.set("My_ex", 6000.0 - 2500.0 * k)
        assert b.step(5e-3) == OK, b.messages[-1:]

    with Instance(path, "state", {"P": 90e3}) as b:
        for k in range(3):
            b.set("My_ex", 3000.0 * k)
            assert b.step(5e-3) == OK
        state = b.get_state()
        for k in range(4):
            step(b, k)
        first = b.outputs()
        b.set_state(state)
        for k in range(4):
            step(b, k)
        assert b.outputs() == first
        data, t = b.serialize_state(state), state[1]
        b.free_state(state)
    with Instance(path, "restored") as b:
        b.set_state(b.deserialize_state(data, t))
        for k in range(4):
            step(b, k)
        assert b.outputs() == first


def _answers(b, calls: list) -> tuple[list[int], list[tuple[int, str]]]:
    """The statuses of ``calls`` on b and the messages logged meanwhile."""
    start, statuses = len(b.messages), []
    for kind, *args in calls:
        if kind == "step":
            statuses.append(b.step(*args))
            continue
        try:
            b.get(*args) if kind == "get" else b.set(*args)
            statuses.append(OK)
        except FMICallException as e:
            statuses.append(int(e.status))
    return statuses, b.messages[start:]


@pytest.mark.parametrize("name", ["body", "contact"])
def test_a_load_outside_a_layered_tables_range_is_refused_in_the_same_words(fmus, name):
    """P beyond the layered table's nodes: no start (fmi2Error), a step discarded with the
    state unchanged and, in the contact mode, no outputs for it (fmi2Error); P = 0
    (lift-off) and a load back in range step again. The same statuses and messages from
    the pythonfmu FMU and the native FMU, the FMI 3.0 FMU's in FMI 3.0's names."""
    paths = fmus[name]
    answers = {}
    for target in ("pythonfmu", "native", "fmi3"):
        make = Instance3 if target == "fmi3" else Instance
        kw = {"init": False} if target == "fmi3" else {"initialise": False}
        inst = make(paths[target], "range", **kw)
        try:
            inst.set("P", 150e3)
            try:
                inst.fmu.exitInitializationMode() if target == "fmi3" else inst.initialise()
                start = OK
            except FMICallException as e:
                start = int(e.status)
            start_words = list(inst.messages)
        finally:
            inst.close()
        with make(paths[target], "range") as b:
            calls = [("step", 1e-3), ("set", "P", 50e3), ("step", 1e-3), ("get", "Tx"),
                     ("set", "P", 0.0), ("step", 1e-3), ("set", "P", 119e3), ("step", 1e-3),
                     ("get", "Tx")]  # fmt: skip
            answers[target] = (start, start_words, *_answers(b, calls))
    assert answers["native"] == answers["pythonfmu"]
    py, n3 = answers["pythonfmu"], answers["fmi3"]
    assert n3[0] == py[0] and n3[2] == py[2]
    assert in_fmi3_words(py[1]) == n3[1] and in_fmi3_words(py[3]) == n3[3]
    start, start_words, statuses, words = py
    assert start == ERROR and any(f"P = 150000.0 is invalid: {RANGE}" in m for _, m in start_words)
    get = ERROR if name == "contact" else OK
    assert statuses == [OK, OK, DISCARD, get, OK, OK, OK, OK, OK]
    assert any(s == DISCARD and f"P = 50000.0 is invalid: {RANGE}" in m for s, m in words)


# ---- the sanitizers and memcheck on the blended table ---------------------------------------


@pytest.mark.parametrize("name", ["body", "contact"])
def test_sanitized_importer_runs_the_layered_table_through_random_extremes_cleanly(
    fmus, tmp_path, name
):
    """The layered four-node table's FMUs (the weights and the blend of every cell; loads
    beyond the range refused) under the sanitized importer's random calls (extreme and
    non-finite values of every input, states got, set, serialized and damaged): no
    sanitizer report, no fmi2Fatal, no non-finite output served with fmi2OK."""
    counts = native_c.sanitized_fuzz(fmus[name]["native"], tmp_path, 1500, resources=True)
    assert counts["ok"] > 500 and counts["error"] + counts["discard"] > 50, counts


@pytest.mark.skipif(not native_c.HAS_VALGRIND, reason="no valgrind")
def test_memcheck_finds_no_error_in_the_layered_tables_binary(fmus, tmp_path, monkeypatch):
    """The layered body FMU's binary as shipped, dlopened by the plain C importer under
    valgrind's memcheck: 600 random calls with no invalid read or write, no use of an
    undefined value and no definite leak."""
    import fmpy
    from test_native_fmu import IMPORTER, _compile

    unzip = tmp_path / "fmu"
    fmpy.extract(str(fmus["body"]["native"]), str(unzip))
    md, spec = native_c.fuzz_spec(unzip, tmp_path)
    monkeypatch.setenv("FMU_RESOURCES", (unzip / "resources").as_uri())
    exe = str(_compile(tmp_path / "importer", str(IMPORTER), "-ldl"))
    ident = md.coSimulation.modelIdentifier
    head = (exe, str(unzip / "binaries" / "linux64" / f"{ident}.so"), md.guid, ident)
    out = native_c.memcheck(*head, "fuzz", str(spec), "0", "600").split()
    counts = {k: int(v) for k, v in zip(out[::2], out[1::2], strict=True)}
    assert counts["ok"] > 100, counts


def strict_build(path: Path, tmp_path: Path) -> list[str]:
    """sources/*.c of the FMU at ``path`` compiled as a builder would (``cc -shared -fPIC``
    with fmpy's FMI headers, -Wall -Wextra -pedantic -Werror, no -fvisibility=hidden):
    the names its library defines."""
    import fmpy

    unzip = tmp_path / path.stem
    fmpy.extract(str(path), str(unzip))
    units = sorted(str(u) for u in (unzip / "sources").glob("*.c"))
    lib = unzip / "built.so"
    cmd = ["cc", "-shared", "-fPIC", "-Wall", "-Wextra", "-pedantic", "-Werror",
           f"-I{native_fmu.fmi_headers()}", *units, "-lm", "-o", str(lib)]  # fmt: skip
    proc = subprocess.run(cmd, capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr[-3000:]
    out = subprocess.run(["nm", "-D", "--defined-only", str(lib)], capture_output=True,
                         text=True, check=True).stdout  # fmt: skip
    return [line.split()[-1] for line in out.split("\n") if line.strip()]


@pytest.mark.parametrize("target", ["native", "fmi3"])
def test_layered_tables_sources_compile_strictly_exporting_only_fmi(fmus, tmp_path, target):
    """The layered table's FMU sources (the spline and the blend in stepper.c, the load
    range in instance.c) compile warning-free under -Wall -Wextra -pedantic -Werror and
    export the FMI functions only (FMI 2.0: 34, FMI 3.0: 75)."""
    names = strict_build(fmus["body"][target], tmp_path)
    prefix, count = ("fmi2", 34) if target == "native" else ("fmi3", 75)
    assert len(names) == count and all(n.startswith(prefix) for n in names), names


@pytest.mark.parametrize("target", ["native", "fmi3", "pythonfmu", "CONTACT_FMU_CORE=0"])
def test_a_vanishing_rolling_speed_gives_the_sliding_outputs(fmus, target, monkeypatch):
    """The contact mode on the plain table, sliding (vx = 0.92 m/s, Vy = 0.5 m/s, Omega_z =
    1 rad/s) at the rolling speeds Vx = 5e-324 and 1e-310 (subnormal): the outputs of
    Vx = 0, the limit (the creepages on the table's face along the slip), bit for bit,
    |T| within 1 % of mu P; native FMI 2.0 and 3.0, the pythonfmu FMU on its C core and
    on its Python path (the table law of CreepTable._scalar). Before, the clamp onto the
    table's box multiplied by |Vx|, which underflowed: zero forces and full adhesion
    served with status OK."""
    if target == "CONTACT_FMU_CORE=0":
        monkeypatch.setenv("CONTACT_FMU_CORE", "0")
    path = fmus["plain"]["pythonfmu" if target.startswith("CONTACT") else target]
    names = ("Tx", "Ty", "Mz", "adhesion")
    outputs = []
    for Vx in (0.0, 5e-324, 1e-310):
        inst = Instance3(path) if target == "fmi3" else Instance(path, target)
        with inst as b:
            for name, value in (("Vx", Vx), ("Omega_y", -2.0), ("Vy", 0.5), ("Omega_z", 1.0)):
                b.set(name, value)
            assert b.step(1e-3) == OK, b.messages[-1:]
            outputs.append(tuple(b.get(n) for n in names))
    assert outputs[1] == outputs[0] and outputs[2] == outputs[0]
    Tx, Ty, _, adhesion = outputs[0]
    assert math.hypot(Tx, Ty) == pytest.approx(0.3 * 100e3, rel=0.01) and adhesion == 0.0
