"""The adapter class in-process (no FMU binary): state, bad input, error handling.

pythonfmu answers fmi2Discard when do_step returns False and fmi2Fatal when anything
raises; the FMU's binary (pythonfmu_shim.c) answers the worst status the adapter wrote
into its cell. ``Slave`` hands the adapter a cell as the shim does, so every check here
is that nothing raises, that the call's status (``status``: the cell) is the one the
binary would answer, that the log names the variable and the value, that the state is
untouched and that the instance steps normally, bit for bit like a fresh one, once the
input is corrected.
"""

from __future__ import annotations

import ctypes
import dataclasses
import math
import pickle

import numpy as np
import pytest

from contact_fmu import examples as ex
from contact_fmu import native
from contact_fmu.dynamics.kinematics import rigid_slip
from contact_fmu.fmu.body_model import MAX_SUBSTEPS, substeps
from contact_fmu.fmu.config import ModelConfig
from contact_fmu.fmu.slave import CELL_VR, ContactSlave

F = ex.force_unit()
H = 1.75e-4  # s, the communication step of the Fig. 13 scene

BODY = ModelConfig(
    name="body",
    mode="body",
    inputs=("P", "Fx_ex", "My_ex"),
    outputs=("Vx", "Omega_y", "vx", "Tx", "adhesion", "regime"),
    starts={"h_max": H / 4},
)
CONTACT = ModelConfig(
    name="contact", mode="contact", inputs=("P", "Vx", "Vy", "Omega_y"),
    outputs=("Tx", "Ty", "Mz", "vx", "adhesion", "regime"),
)  # fmt: skip
RIGID = ModelConfig(name="rigid", mode="rigid_body", inputs=("Tx", "Fx_ex", "My_ex"),
                    outputs=("Vx", "Omega_y"))  # fmt: skip
OK, WARNING, DISCARD, ERROR = 0, 1, 2, 3  # fmi2Status


class Slave:
    """A ContactSlave for a configuration, addressed by variable name."""

    def __init__(self, cfg: ModelConfig, **params: float) -> None:
        cls = type("Model", (ContactSlave,), {"CONFIG": cfg.to_dict()})
        self.s = cls(instance_name="test")
        self.cell = ctypes.c_int(0)  # the shim's status cell (pythonfmu_shim.c)
        self.s.set_string([CELL_VR], [f"status cell {hex(ctypes.addressof(self.cell))}"])
        self.vr = {v.name: k for k, v in self.s.vars.items()}
        self.t = 0.0
        self.s.setup_experiment(0.0)
        self.s.enter_initialization_mode()
        for k, v in params.items():
            self.set(k, v)
        self.init_status = self.initialise()

    def initialise(self) -> int:
        """fmi2ExitInitializationMode; the status the FMU's binary answers."""
        self.cell.value = OK
        self.s.exit_initialization_mode()
        return self.cell.value

    @property
    def status(self) -> int:
        """The worst status logged since the last set, step or initialise."""
        return self.cell.value

    def set(self, name: str, value: float) -> None:
        self.cell.value = OK
        self.s.set_real([self.vr[name]], [value])

    def get(self, name: str) -> float:
        var = self.s.vars[self.vr[name]]
        if type(var).__name__ == "Integer":
            return self.s.get_integer([self.vr[name]])[0]
        return self.s.get_real([self.vr[name]])[0]

    def outputs(self) -> dict[str, float]:
        return {n: self.get(n) for n in self.s.cfg.outputs}

    def step(self, h: float = H) -> bool:
        self.cell.value = OK
        ok = self.s.do_step(self.t, h)
        if ok:
            self.t += h
        return ok

    @property
    def messages(self) -> list[str]:
        return [m.msg for m in self.s.log_queue]


def loaded_body(**params: float) -> Slave:
    b = Slave(BODY, **params)
    b.set("Fx_ex", F)
    b.set("My_ex", -0.1 * F * ex.Rx)
    return b


def test_fmu_state_restore_covers_inputs_and_parameters_too():
    b = loaded_body()
    assert b.step()
    state = b.s._get_fmu_state()
    b.set("Fx_ex", 0.5 * F)  # an input changed after the state was taken
    assert b.step()
    b.s._set_fmu_state(state)
    b.t -= H
    assert b.get("Fx_ex") == F
    assert b.step()
    reference = loaded_body()
    assert reference.step() and reference.step()
    assert b.outputs() == reference.outputs()


def test_fmu_state_restore_in_contact_and_rigid_body_modes():
    c = Slave(CONTACT)
    c.set("Omega_y", ex.speed_unit() / ex.Rx * 0.999)
    assert c.step()
    state = c.s._get_fmu_state()
    before = c.outputs()
    c.set("Omega_y", ex.speed_unit() / ex.Rx * 0.99)
    assert c.step() and c.outputs() != before
    c.s._set_fmu_state(state)
    assert c.outputs() == before

    r = Slave(RIGID, Iy=1e-3)
    r.set("Tx", 10.0)
    assert r.step()
    state = r.s._get_fmu_state()
    assert r.step()
    after = r.outputs()
    r.s._set_fmu_state(state)
    r.t -= H
    assert r.step() and r.outputs() == after


def test_inertia_that_underflows_fails_initialisation_with_a_named_error():
    """Rx = 5e-324 with Iy = 0 passes each range, but M Rx^2 + Iy (the denominator of
    A1, A2, Eq. 23) underflows to 0: an error naming it, not a division by zero."""
    b = loaded_body(Rx=5e-324, Ry=2.97e9, Iy=0.0)
    assert b.init_status == ERROR
    assert any("M Rx^2 + Iy = 0.0 is invalid" in m for m in b.messages), b.messages
    assert b.step() is False and b.status == ERROR


def test_stage_failure_is_discarded_with_the_state_unchanged():
    """eta = inf (Iy = 0) admits no gross sliding: loads beyond mu P have no solution."""
    b = Slave(BODY, Iy=0.0)
    b.set("Fx_ex", F)
    assert b.step()
    before = b.outputs()
    b.set("My_ex", -2.0 * ex.mu * ex.P * ex.Rx)  # |A1 My/Rx| = 2 mu P
    assert b.step() is False
    assert "no gross sliding" in b.messages[-1] and "discarded" in b.messages[-1]
    assert b.outputs() == before
    b.set("My_ex", 0.0)
    assert b.step()


def test_contact_outputs_follow_the_inputs_before_any_step():
    """A force element has direct feedthrough: getReal after setReal sees the new force."""
    c = Slave(CONTACT)
    law = ex.contact()
    for ratio in (1.0, 0.999, 1.003):
        Vx, Omega_y = ex.speed_unit(), ex.speed_unit() / ex.Rx * ratio
        c.set("Omega_y", Omega_y)
        vx, vy = rigid_slip(Vx, Omega_y, 0.0, ex.Rx)
        assert c.get("Tx") == float(law.forces(vx, vy, 0.0, Vx)[0])
        assert c.get("vx") == vx


def test_contact_outputs_of_a_bad_input_are_an_error_never_stale_ok():
    """Feedthrough outputs that cannot be had for the current inputs answer fmi2Error
    at getReal (the values kept are the last good inputs', not to be used)."""
    c = Slave(CONTACT)
    c.set("Omega_y", ex.speed_unit() / ex.Rx * 0.999)
    before = c.outputs()
    c.set("Vx", math.nan)
    assert c.status == ERROR
    c.cell.value = OK
    assert c.outputs() == before and c.status == ERROR
    assert "no outputs for the current inputs: Vx = nan is invalid" in c.messages[-1]
    assert c.step() is False
    c.set("Vx", ex.speed_unit())
    c.cell.value = OK
    assert c.step() and c.outputs() == before and c.status == OK


def test_momentum_balance_is_kept_or_the_loads_refused():
    """Eqs. 8-9 in gross sliding: M dVx = (Fx_ex - Tx) h with abs(Tx) <= mu P. Loads
    beyond LOAD_LIMIT mu P (where the eliminated form loses the balance to rounding:
    Vx went from 5.6 to 0 in one step with My_ex = 1e20) are refused with Discard."""
    for My in (-1e3, 1e3):  # 67 mu P Rx, gross sliding: the balance holds
        b = loaded_body()
        b.set("Fx_ex", 0.0)
        b.set("My_ex", My)
        V0 = b.get("Vx")
        assert b.step()
        slack = ex.mu * ex.P * H / ex.M
        assert abs(b.get("Vx") - V0) <= slack * (1 + 1e-5)
    b.set("My_ex", 1e20)
    before = b.outputs()
    assert b.step() is False and b.status == DISCARD
    assert "My_ex = 1e+20 is invalid" in b.messages[-1]
    assert b.outputs() == before


def test_rigid_body_integrates_eqs_8_and_9_exactly_for_held_force():
    r = Slave(RIGID, Iy=1e-3)
    r.set("Tx", 30.0)
    r.set("Fx_ex", 50.0)
    r.set("My_ex", -1.0)
    assert r.step(0.01)
    assert r.get("Vx") == pytest.approx(ex.speed_unit() + 0.01 * (50.0 - 30.0) / 1.0, rel=1e-15)
    dOmega = 0.01 * (-1.0 + ex.Rx * 30.0) / 1e-3  # Eq. (9) with +Rx Tx
    assert r.get("Omega_y") == pytest.approx(ex.speed_unit() / ex.Rx + dOmega, rel=1e-15)


def test_substeps_split_a_communication_step_by_h_max():
    assert substeps(1e-6, 1e-4) == 1
    assert substeps(1e-4, 1e-4) == 1
    assert substeps(3e-4, 1e-4) == 3  # 3e-4/1e-4 = 2.9999999999999996 in floating point
    assert substeps(3.0001e-4, 1e-4) == 4
    assert substeps(1.0, 1e-9) == MAX_SUBSTEPS


def test_normal_load_input_moves_the_contact_ellipse_and_is_part_of_the_state():
    """P is an input in body mode: the ellipse follows Eq. (34) from the next step on."""
    cfg = ModelConfig(name="bodyP", mode="body", inputs=("P", "Fx_ex"),
                      outputs=("Tx", "a1", "a2", "p0"), starts={"h_max": H / 4})  # fmt: skip
    b = Slave(cfg)
    b.set("Fx_ex", F)
    assert b.step()
    state = b.s._get_fmu_state()
    b.set("P", 2.0 * ex.P)
    assert b.step()
    doubled = ex.contact().with_load(2.0 * ex.P)
    assert (b.get("a1"), b.get("a2"), b.get("p0")) == (doubled.a1, doubled.a2, doubled.p0)
    b.s._set_fmu_state(state)
    assert b.get("P") == ex.P and b.get("a1") == ex.contact().a1


# ---- the compiled step (BodyModel.fast, contact_fmu/native) ---------------------------
def _compiled_and_python(monkeypatch, cfg: ModelConfig = BODY, **params: float):
    """Two instances of one FMU class: one with the compiled step, one without."""
    from contact_fmu.fmu import body_model

    fast = Slave(cfg, **params)
    with monkeypatch.context() as m:
        m.setattr(body_model.BodyModel, "fast", lambda self: None)
        slow = Slave(cfg, **params)
    slow.s._fast_enable = lambda: None  # stays Python after set state too
    return fast, slow


@pytest.mark.skipif(native.library() is None, reason="no C compiler")
@pytest.mark.parametrize(
    ("calls", "scheme"), [("fmi.c", "lobatto3c"), ("ctypes", "lobatto3c"), ("fmi.c", "sdirk2")]
)
def test_compiled_step_repeats_the_python_step_through_every_fmi_path(monkeypatch, calls, scheme):
    """A body FMU whose steps run in C (state in the struct, Python synced on demand)
    gives the Python adapter's outputs bit for bit (no lateral slip: stepper.c's
    contract) through all that hands the state between them: a load change (P: Python
    takes that step), internal steps at the cap (Python's note), a bad input (discard)
    and its correction, get state / step / set state / step, Integer outputs. Both
    ways of calling the step: the FMI calls themselves in C (native/fmi.c) and the
    adapter's Python calling the step through ctypes; both schemes (the FMU's one)."""
    if calls == "fmi.c" and native.fmi_module() is None:
        pytest.skip("no Python headers for native/fmi.c")
    if calls == "ctypes":
        monkeypatch.setattr(native, "fmi_module", lambda: None)
    fast, slow = _compiled_and_python(monkeypatch, dataclasses.replace(BODY, schemes=(scheme,)))
    assert fast.s._model.stepper.scheme == scheme
    assert fast.s._fast is not None and slow.s._fast is None
    assert (fast.s._fast_fmi is not None) == (calls == "fmi.c")
    compiled = [0]
    bindings = set()  # the C bindings (a new one after each set state): their step counts
    stepper = native.FastBody.stepper

    def counted(self):
        step = stepper(self)

        def count(h):
            status = step(h)
            compiled[0] += status == 0
            return status

        return count

    monkeypatch.setattr(native.FastBody, "stepper", counted)
    fast.s._fast_enable()  # its stepper counted from here
    rng = np.random.default_rng(3)

    def both(action):
        bindings.add(fast.s._fast_fmi)
        a, b = action(fast), action(slow)
        assert a == b
        assert fast.outputs() == slow.outputs()
        assert fast.messages == slow.messages

    for k in range(120):
        fx, my = rng.uniform(-1.2, 1.2) * F, rng.uniform(-0.3, 0.3) * F * ex.Rx
        both(lambda s, fx=fx: s.set("Fx_ex", fx))
        both(lambda s, my=my: s.set("My_ex", my))
        if k % 17 == 5:
            both(lambda s, k=k: s.set("P", 1000.0 * (1.0 + 0.01 * k)))
        if k % 23 == 7:
            both(lambda s: s.set("Fx_ex", math.nan))  # discarded until corrected
            both(lambda s: s.step())
            both(lambda s, fx=fx: s.set("Fx_ex", fx))
        if k % 29 == 13:  # not a float: the general setter
            both(lambda s, k=k: s.set("Fx_ex", k - 20))
        h = H * 10 ** rng.uniform(-3, 1)
        if k % 31 == 11:
            h = H / 4 * (MAX_SUBSTEPS + 3)  # beyond the cap: Python logs the note
        both(lambda s, h=h: s.step(h))
        if k % 13 == 3:  # state round trip through the struct
            states = [s.s._get_fmu_state() for s in (fast, slow)]
            both(lambda s: s.step())
            for s, st in zip((fast, slow), states, strict=True):
                s.s._set_fmu_state(st)
                s.t = st["time"]
            both(lambda s: s.step())
    # the compiled step took most steps (a test of the fallback alone would pass vacuously)
    assert fast.s._fast is not None and slow.s._fast is None
    compiled[0] += sum(b.steps for b in bindings if b is not None)
    assert compiled[0] > 100


@pytest.mark.skipif(native.library() is None, reason="no C compiler")
def test_compiled_step_with_a_held_lateral_ratio_agrees_to_rounding(monkeypatch):
    cfg = ModelConfig(
        name="lat", mode="body", vy="ratio", inputs=("P", "Fx_ex"),
        outputs=("Vx", "Vy", "vx", "Tx", "Ty", "xi_y", "adhesion"), starts={"h_max": H / 4},
    )  # fmt: skip
    fast, slow = _compiled_and_python(monkeypatch, cfg, vy_ratio=0.002)
    assert fast.s._fast is not None
    for k in range(200):
        for s in (fast, slow):
            s.set("Fx_ex", F * math.sin(0.1 * k) * 1.3)
            assert s.step()
        a, b = fast.outputs(), slow.outputs()
        for n in a:
            scale = {"Tx": F, "Ty": F, "adhesion": 1.0}.get(n, max(abs(b[n]), 1e-6))
            assert abs(a[n] - b[n]) <= 1e-11 * scale, n


@pytest.mark.parametrize("cfg", [BODY, CONTACT, RIGID], ids=lambda c: c.mode)
def test_input_fast_check_is_var_check(cfg):
    """set_real tests a Real input's float against the declared range itself (the
    per-step call); what it accepts or refuses must be exactly Var.check's verdict."""
    from contact_fmu.fmu import variables as fv

    s = Slave(cfg)
    values = [math.nan, math.inf, -math.inf, 0.0, -0.0, 1e-300, -1e-300, 1.0, -1.0, 1e300]
    values += [5e-324, 3, True, "1.0"]  # not floats: the general path
    for name in cfg.inputs:
        var = fv.BY_NAME[name]
        extra = [b + d for b in (var.min, var.max) if b is not None for d in (-1e-9, 0.0, 1e-9)]
        for value in values + extra:
            s.s._call.bad.clear()
            s.set(name, value)
            assert (name in s.s._call.bad) == (var.check(value) is not None), (name, value)
            if name not in s.s._call.bad:
                assert s.s._call.inputs[name] == float(value) and s.get(name) == float(value)


@pytest.mark.skipif(native.library() is None, reason="no C compiler")
def test_compiled_step_state_survives_a_python_step_that_fails_late(monkeypatch):
    """A step Python takes (here: a new load P) whose stepper succeeds but whose outputs
    then fail is discarded with the state unchanged, in the struct too: the next
    compiled steps continue from the state before it, as the Python adapter does."""
    from contact_fmu.dynamics.integrator import RollingBody

    fast, slow = _compiled_and_python(monkeypatch)
    for s in (fast, slow):
        s.set("Fx_ex", 0.5 * F)
        assert s.step()
    outputs = RollingBody.outputs
    with monkeypatch.context() as m:
        m.setattr(RollingBody, "outputs", lambda self: {**outputs(self), "Tx": math.nan})
        for s in (fast, slow):
            s.set("P", 1100.0)
            assert s.step() is False
    assert fast.outputs() == slow.outputs() and fast.messages == slow.messages
    for _ in range(5):
        for s in (fast, slow):
            assert s.step()
        assert fast.outputs() == slow.outputs()


@pytest.mark.skipif(native.fmi_module() is None, reason="no C compiler or Python headers")
def test_c_binding_of_the_fmi_calls_leaves_the_instance_collectable():
    """native/fmi.c's binding refers to the instance that holds it (a cycle through the
    instance's __dict__): the garbage collector must still free both (fmi2FreeInstance,
    fmi2Reset re-create the object), and set state must not pile bindings up."""
    import gc
    import weakref

    b = loaded_body()
    assert type(b.s.do_step).__name__ == "builtin_function_or_method"
    state = b.s._get_fmu_state()
    first = weakref.ref(b.s._fast_fmi)
    b.s._set_fmu_state(state)  # a new binding replaces the first
    assert b.step() and b.s._fast_fmi.steps == 1
    ref = weakref.ref(b.s)
    del b
    gc.collect()
    assert ref() is None and first() is None


@pytest.mark.parametrize("calls", ["fmi.c", "ctypes"])
def test_empty_value_reference_lists_are_answered(monkeypatch, calls):
    """fmi2GetReal/fmi2SetReal with nvr = 0 are legal calls: an empty answer, no error,
    on every path that answers them (the C binding, the adapter's own methods)."""
    if calls == "ctypes":
        monkeypatch.setattr(native, "fmi_module", lambda: None)
    b = loaded_body()
    assert b.s.get_real([]) == [] and b.s.set_real([], []) is None
    assert b.step() and b.s.get_real([]) == []
    assert not b.messages


def test_state_bytes_admit_only_the_classes_a_state_holds():
    """The unpickler of serialized FMU states resolves numpy's and the FMU package's
    names only: a pickle that would call anything else (here os.system) is Unreadable,
    naming it, and nothing is called; a real state round-trips exactly."""
    import os
    import pickle

    from contact_fmu.fmu import state_bytes

    class Payload:
        def __reduce__(self):
            return (os.system, ("echo should-not-run",))

    evil = state_bytes.MAGIC + b"contact_fmu\n" + pickle.dumps(Payload(), protocol=5)
    got = state_bytes.loads(evil, "contact_fmu")
    assert isinstance(got, state_bytes.Unreadable)
    assert f"{os.system.__module__}.system is not part of an FMU state" in got.reason
    state = {"y": np.array([1.0, 2e-3, 0.0, 0.0]), "out": (1.5, np.float64(2.0), True)}
    back = state_bytes.loads(state_bytes.dumps(state, "contact_fmu"), "contact_fmu")
    assert back["out"] == state["out"] and np.array_equal(back["y"], state["y"])


def test_fmu_state_is_checked_whole_and_refused_without_a_trace():
    """Crafted states (NaN outputs, outputs beyond Coulomb's bound, a value of the
    wrong type, a model snapshot that cannot be restored, another FMU's fields) answer
    fmi2Error and change nothing; pythonfmu answered fmi2Fatal and left the instance
    half restored, or accepted NaN outputs."""
    b = loaded_body()
    assert b.step()
    good = b.s._get_fmu_state()
    before = (b.outputs(), pickle.dumps(b.s._get_fmu_state()))

    def crafted(**change):
        return {**good, **change}

    cases = [
        (crafted(out={**good["out"], "Tx": math.nan}), "not a finite float"),
        (crafted(out={**good["out"], "Tx": 10.0 * ex.mu * ex.P}), "Coulomb's bound"),
        (crafted(values={**good["values"], "mu": "0.3"}), "is not a number"),
        (crafted(model=(good["model"][0], "not a snapshot")), "cannot be restored"),
        ({k: v for k, v in good.items() if k != "dirty"}, "fields differ"),
        (crafted(out_mu=-0.3), "is not a positive float"),
        (crafted(values={k: v for k, v in good["values"].items() if k != "mu"}), "differ"),
    ]
    for state, reason in cases:
        b.cell.value = OK
        b.s._set_fmu_state(state)
        assert b.status == ERROR and reason in b.messages[-1], b.messages[-1]
        assert (b.outputs(), pickle.dumps(b.s._get_fmu_state())) == before
    assert b.step()
