"""hypothesis strategies: runs of FMI calls for one kind of FMU (lists of worker ops).

A run instantiates, sets up, initialises (with parameters and inputs drawn from their
declared ranges or from the hostile values below) and then calls at random: inputs,
parameters and outputs set, doSteps of any size at or off the FMU's time, marches of
5 to 60 equal steps (for slip and the transient field to build up), load drops, outputs
read, FMU states got, set, freed (twice, or set after free), serialized, damaged (a byte
changed, truncated), crafted (the pickled state rewritten), taken from a second
instance with other parameters, round trips (get, step, set, step), bad inputs then
corrected, terminate and reset. Some runs call doStep before initialisation.
"""

from __future__ import annotations

import math

from hypothesis import strategies as st

from .kinds import Kind

NAN, INF = math.nan, math.inf
# Values no declared range foresees: the largest finite doubles (and the 6e306 and
# 1.2e308 of the issue), the smallest subnormal, zero, signs, NaN, infinities, and
# large loads (3e14 N: where the momentum balance broke).
HOSTILE = (
    1.7976931348623157e308,
    -1.7976931348623157e308,
    1.2e308,
    6e306,
    -6e306,
    1e100,
    -1e100,
    1e20,
    -1e20,
    3e14,
    -3e14,
    2.97e9,
    5e-324,
    -5e-324,
    1e-300,
    0.0,
    -0.0,
    -1.0,
    NAN,
    INF,
    -INF,
)
BAD_STEPS = (0.0, -0.0, -1e-4, -1e6, 5e-324, NAN, INF, -INF)
TIME_OFFSETS = (5e-4, -5e-4, 1e-3, 1.0, -1e-6, 1e-9, 1e-15, NAN, INF)
START_TIMES = (0.0, 0.0, 0.0, 0.5, -1.0, 1e6)
CRAFTS = (
    ("outputs_nan", None),
    ("outputs_inf", None),
    ("time", NAN),
    ("time", -1.0),
    ("time", 1e308),
    ("value", ["P", -1.0]),
    ("value", ["P", NAN]),
    ("value", ["mu", 0.0]),
    ("value", ["Rx", 5e-324]),
    ("value", ["h_max", 0.0]),
    ("value", ["Tx", 1e308]),
    ("drop", "model"),
    ("drop", "values"),
    ("drop", "out"),
    ("model_none", None),
    ("not_a_dict", None),
)


def _uniform(lo: float, hi: float) -> st.SearchStrategy[float]:
    return st.floats(lo, hi, allow_nan=False, allow_infinity=False)


def nominal(kind: Kind, name: str) -> st.SearchStrategy:
    """Values of ``name`` in its working range (around the kind's start values)."""
    v = kind.variables[name]
    if v.type == "Integer":
        return st.integers(4, 12) if name == "nx" else st.integers(2, 6)
    if v.type == "String":
        if name == "method":
            return st.sampled_from([*kind.cfg.methods, "bogus"])
        if name == "scheme":
            return st.sampled_from([*kind.cfg.schemes, "bogus"])
        if name == "field_file":
            return st.sampled_from(["", "", "/nonexistent/dir/field.csv"])
        return st.sampled_from(["", "", "1e-4", "abc"])
    x0 = kind.start(name)
    P0 = kind.start("P") if "P" in kind.variables else 1000.0
    mu = kind.start("mu") if "mu" in kind.variables else 0.3
    Rx = kind.start("Rx")
    # loads up to 6 mu P: beyond Eq. (27)'s admissible strip the body slides (Tx = mu P)
    if name in ("Fx_ex", "Fy_ex", "Tx"):
        return _uniform(-6.0 * mu * P0, 6.0 * mu * P0)
    if name in ("My_ex", "Mz_ex"):
        return _uniform(-6.0 * mu * P0 * Rx, 6.0 * mu * P0 * Rx)
    if name == "Omega_y" and kind.mode == "contact":  # creepages up to +-2 %
        Vx = kind.start("Vx")
        return _uniform(-0.02, 0.02).map(lambda xi: Vx / Rx * (1.0 - xi))
    if name in ("Vy", "Vy0"):
        return _uniform(-0.02, 0.02).map(lambda r: r * kind.start("Vx0" if name == "Vy0" else "Vx"))
    if name in ("Omega_z", "Omega_z0", "vy_ratio"):
        return _uniform(-0.05, 0.05) if name == "vy_ratio" else _uniform(-2.0, 2.0)
    if x0 == 0.0:
        return _uniform(-1.0, 1.0)
    return _uniform(0.5, 2.0).map(lambda f: f * x0)


def value(kind: Kind, name: str) -> st.SearchStrategy:
    """A value for ``name``: in the working range (three times in four) or hostile."""
    v = kind.variables[name]
    nom = nominal(kind, name)
    if v.type == "String":
        return nom
    hostile = st.sampled_from(HOSTILE)
    if v.type == "Integer":
        hostile = st.sampled_from([0, -1, 3, 1, 2**31 - 1])
    return st.one_of(nom, nom, nom, hostile)


def step_size(kind: Kind) -> st.SearchStrategy[float]:
    """Communication steps: 1e-7 .. 1e-3 s mostly, long ones (to 1e6 s) where a step
    stays affordable (not on slow kinds), and invalid ones (zero, negative, NaN, inf)."""
    usual = st.floats(-7.0, -3.0).map(lambda e: 10.0**e)
    longer = st.sampled_from([1e-2, 0.1, 1.0, 1e3, 1e6])
    bad = st.sampled_from(BAD_STEPS)
    if kind.slow:  # a doStep of up to 10^4 internal steps in Python: minutes
        return st.one_of(usual, usual, usual, bad)
    return st.one_of(usual, usual, usual, longer, bad)


def time_offset() -> st.SearchStrategy:
    return st.one_of(st.just(None), st.just(None), st.just(None), st.sampled_from(TIME_OFFSETS))


@st.composite
def init_block(draw, kind: Kind, inst: int, t0: float) -> list[dict]:
    """setup, enter, the kind's nominal values, some drawn values, exit."""
    ops = [{"op": "setup", "inst": inst, "t0": t0}, {"op": "enter", "inst": inst}]
    ops += [{"op": "set", "inst": inst, "name": n, "value": x} for n, x in kind.nominal.items()]
    settable = kind.names("parameter") + kind.names("input")
    for name in draw(st.lists(st.sampled_from(settable), max_size=4)):
        ops.append({"op": "set", "inst": inst, "name": name, "value": draw(value(kind, name))})
    ops.append({"op": "exit", "inst": inst})
    return ops


@st.composite
def runs(draw, kind: Kind) -> list[dict]:
    """One run: the ops for the worker."""
    ops: list[dict] = []
    h = step_size(kind)
    inputs = kind.names("input")
    params = kind.names("parameter")
    outputs = kind.names("output")
    early = draw(st.sampled_from([None, None, None, None, "instantiated", "init"]))
    if early == "instantiated":
        ops.append({"op": "step", "h": 1e-4})
    t0 = draw(st.sampled_from(START_TIMES))
    init = draw(init_block(kind, 0, t0))
    if early == "init":
        init.insert(2, {"op": "step", "h": 1e-4})
    ops += init
    foreign = draw(st.booleans())
    if foreign:  # a second instance with other parameters: its states go into the first
        other = [p for p in params if kind.variables[p].type == "Real"]
        ops += [
            {"op": "setup", "inst": 1, "t0": t0},
            {"op": "enter", "inst": 1},
            *[{"op": "set", "inst": 1, "name": n, "value": x} for n, x in kind.nominal.items()],
        ]
        for name in draw(st.lists(st.sampled_from(other), min_size=1, max_size=3)):
            x = draw(value(kind, name))
            ops.append({"op": "set", "inst": 1, "name": name, "value": x})
        ops.append({"op": "exit", "inst": 1})
    n = draw(st.integers(1, 14))
    for _ in range(n):
        what = draw(
            st.sampled_from(
                ["step"] * 6
                + ["set_input"] * 3
                + ["get", "set_param", "set_output", "state", "state", "serial", "craft"]
                + ["roundtrip", "badfix", "terminate", "reset", "march", "march", "unload"]
                + ["liftoff"]
                + (["foreign"] * 2 if foreign else [])
            )
        )
        if what == "step":
            ops.append({"op": "step", "h": draw(h), "t": draw(time_offset())})
        elif what == "march":  # long enough for slip and the transient field to build up
            hh = draw(st.floats(-6.0, -4.0).map(lambda e: 10.0**e))
            ops += [{"op": "step", "h": hh}] * draw(st.integers(5, 60))
        elif what == "unload" and "P" in inputs:  # the load drops while the body slides
            hh = draw(st.floats(-6.0, -4.0).map(lambda e: 10.0**e))
            P = kind.start("P") * draw(_uniform(0.1, 0.7))
            ops += [{"op": "set", "name": "P", "value": P}, {"op": "step", "h": hh}]
            ops += [{"op": "step", "h": hh}] * draw(st.integers(0, 10)) + [{"op": "get"}]
        elif what == "liftoff" and "P" in inputs:  # P = 0, stepped, set back (re-contact)
            hh = draw(st.floats(-6.0, -3.0).map(lambda e: 10.0**e))
            ops += [{"op": "set", "name": "P", "value": 0.0}, {"op": "step", "h": hh}]
            ops += [{"op": "step", "h": hh}] * draw(st.integers(0, 5)) + [{"op": "get"}]
            back = kind.start("P") * draw(st.sampled_from([1e-6, 1e-3, 0.3, 1.0]))
            ops += [{"op": "set", "name": "P", "value": back}, {"op": "step", "h": hh}]
            ops += [{"op": "step", "h": hh}] * draw(st.integers(0, 5)) + [{"op": "get"}]
        elif what == "set_input" and inputs:
            name = draw(st.sampled_from(inputs))
            ops.append({"op": "set", "name": name, "value": draw(value(kind, name))})
        elif what == "set_param":
            name = draw(st.sampled_from(params))
            ops.append({"op": "set", "name": name, "value": draw(value(kind, name))})
        elif what == "set_output" and outputs:
            name = draw(st.sampled_from([o for o in outputs if kind.variables[o].type == "Real"]))
            x = draw(st.one_of(_uniform(-10.0, 10.0), st.sampled_from(HOSTILE)))
            ops.append({"op": "set", "name": name, "value": x})
        elif what == "get":
            ops.append({"op": "get"})
        elif what == "state":
            slot = draw(st.integers(0, 1))
            act = draw(st.sampled_from(["getstate", "getstate", "setstate", "setstate"]
                                       + ["freestate", "setfreed"]))  # fmt: skip
            ops.append({"op": act, "slot": slot})
        elif what == "serial":
            slot = draw(st.integers(0, 1))
            damage = draw(
                st.one_of(
                    st.none(),
                    st.tuples(st.just("flip"), _uniform(0.0, 1.0), st.integers(1, 255)),
                    st.tuples(st.just("truncate"), _uniform(0.0, 0.999)),
                )
            )
            ops += [
                {"op": "getstate", "slot": slot},
                {"op": "serialize", "slot": slot, "buf": 0},
                {"op": "deserialize", "buf": 0, "slot": 2, "damage": damage},
                {"op": "setstate", "slot": 2},
            ]
        elif what == "craft":
            edit = draw(st.sampled_from(CRAFTS))
            ops += [
                {"op": "getstate", "slot": 0},
                {"op": "serialize", "slot": 0, "buf": 1},
                {"op": "craft", "buf": 1, "edit": list(edit)},
                {"op": "deserialize", "buf": 1, "slot": 2, "damage": None},
                {"op": "setstate", "slot": 2},
            ]
        elif what == "roundtrip":
            ops.append({"op": "roundtrip", "h": draw(h), "k": draw(st.integers(1, 3))})
        elif what == "badfix" and inputs:
            name = draw(st.sampled_from([i for i in inputs if kind.variables[i].type == "Real"]))
            bad = draw(st.sampled_from([x for x in HOSTILE if not kind.admissible(name, x)]))
            good = kind.start(name)
            hh = draw(st.floats(-6.0, -4.0).map(lambda e: 10.0**e))
            ops += [
                {"op": "set", "name": name, "value": good, "tag": "badfix-pre"},
                {"op": "step", "h": hh, "tag": "badfix-pre"},
                {"op": "set", "name": name, "value": bad, "tag": "badfix-bad"},
                {"op": "step", "h": hh, "tag": "badfix-bad"},
                {"op": "set", "name": name, "value": good, "tag": "badfix-fix"},
                {"op": "step", "h": hh, "tag": "badfix-fix"},
            ]
        elif what == "terminate":
            ops.append({"op": "terminate"})
            if draw(st.booleans()):
                ops.append({"op": "step", "h": 1e-4})
        elif what == "reset":
            ops.append({"op": "reset"})
            if draw(st.booleans()):
                ops.append({"op": "step", "h": 1e-4})
            if draw(st.booleans()):
                ops += draw(init_block(kind, 0, draw(st.sampled_from(START_TIMES))))
        elif what == "foreign":
            if draw(st.booleans()):
                ops += [
                    {"op": "step", "inst": 1, "h": 1e-4},
                    {"op": "getstate", "inst": 1, "slot": 3},
                    {"op": "setstate", "slot": 3},
                ]
            else:
                ops += [
                    {"op": "getstate", "inst": 1, "slot": 3},
                    {"op": "serialize", "inst": 1, "slot": 3, "buf": 2},
                    {"op": "deserialize", "buf": 2, "slot": 2, "damage": None},
                    {"op": "setstate", "slot": 2},
                ]
    return ops
