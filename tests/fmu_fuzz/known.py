"""Runs that once broke the FMUs' contract, replayed first in every fuzz session (hypothesis
explicit examples): the fuzzer's draws need not find them again to keep them checked."""

from __future__ import annotations

INIT = [{"op": "setup"}, {"op": "enter"}, {"op": "exit"}]


def _set(name: str, value: object, **kw: object) -> dict:
    return {"op": "set", "name": name, "value": value, **kw}


def _step(h: float, t: float | None = None) -> dict:
    return {"op": "step", "h": h, "t": t}


def _state_via_bytes(edit: list | None = None, damage: list | None = None) -> list[dict]:
    ops = [{"op": "getstate", "slot": 0}, {"op": "serialize", "slot": 0, "buf": 0}]
    if edit:
        ops.append({"op": "craft", "buf": 0, "edit": edit})
    ops += [{"op": "deserialize", "buf": 0, "slot": 2, "damage": damage}]
    return ops + [{"op": "setstate", "slot": 2}, {"op": "get"}]


KNOWN: dict[str, list[list[dict]]] = {
    "fig13": [
        [*INIT, _step(1e-4), _set("mu", 5e-324), _step(1e-4)],  # Fatal: ZeroDivisionError
        [
            {"op": "setup"},
            {"op": "enter"},
            _set("M", 1e-300),
            {"op": "exit"},
            _step(1.75e-4),
            _step(4.03e-9),
            _step(1.75e-5),
            _step(1.75e-5),
            _set("Fx_ex", -38.2284),
            _step(1e-12),  # at t = 0.00021000403
            {"op": "get"},
        ],  # Omega_y jumped 1.9e7 times mu P Rx h/Iy with OK  # fmt: skip
        [
            *INIT,
            _step(1e-4),
            _set("P", 0.0),
            _step(1e-4),
            {"op": "get"},
            _set("P", 1000.0),
            _step(1e-4),
            {"op": "get"},
        ],  # lift-off was refused  # fmt: skip
        [*INIT, _set("My_ex", 6e306), _step(1e-4)],  # SIGSEGV in the compiled march
        [
            {"op": "setup"},
            {"op": "enter"},
            _set("mu", 1.7976931348623157e308),
            {"op": "exit"},
            _step(1e-4),
        ],  # SIGSEGV  # fmt: skip
        [
            {"op": "setup"},
            {"op": "enter"},
            _set("Rx", 5e-324),
            _set("Ry", 2.97e9),
            _set("Iy", 0.0),
            {"op": "exit"},
        ],  # fmi2Fatal 'float division by zero'  # fmt: skip
        [{"op": "setup"}, {"op": "enter"}, _set("P", -5.0), {"op": "exit"}, _step(1e-4)],
        [*INIT, _set("My_ex", 1e20), _step(1e-4)],  # dVx 2.36 m/s where 0.03 is allowed
        [*INIT, _step(1e6), _step(1e-4, 5e-4)],  # a point 5e-4 s off accepted
        [*INIT, _step(1e-4, float("inf"))],
        [*INIT, *_state_via_bytes(edit=["outputs_nan", None])],
        [
            *INIT,
            {"op": "getstate", "slot": 0},
            {"op": "freestate", "slot": 0},
            {"op": "freestate", "slot": 0},
            {"op": "setfreed", "slot": 0},
        ],  # fmt: skip
    ],
    "full_contact": [
        [*INIT, _set("Omega_z", 0.5), {"op": "get"}],  # native/stepper.c not in the FMU
        [*INIT, *_state_via_bytes(edit=["not_a_dict", None])],
    ],
    "rail_creep": [
        [*INIT, {"op": "get"}, _set("Vx", 1.797e308), {"op": "get"}],
        [*INIT, {"op": "get"}, _set("P", 5e-324), {"op": "get"}],
        [*INIT, {"op": "get"}, _set("P", -1.0), {"op": "get"}],
    ],
    "rail_traction": [
        [*INIT, _set("My_ex", 1e100), _step(5e-3)],  # Vx to -3e78 m/s with OK
    ],
    "fig12_transient": [
        # sliding, then the load drops: |T| = 1.016 mu P with OK
        [
            {"op": "setup"},
            {"op": "enter"},
            _set("nx", 8),
            _set("ny", 4),
            _set("Fx_ex", 2000.0),
            {"op": "exit"},
            *[_step(2e-5)] * 60,
            _set("P", 200.0),
            *[_step(2e-5)] * 3,
        ],  # fmt: skip
    ],
    "full_rigid_body": [
        [*INIT, *_state_via_bytes(edit=["outputs_nan", None]), _step(1e-4)],
    ],
    "full_body": [
        [*INIT, *_state_via_bytes(damage=["flip", 0.5, 47])],
    ],
    "cornering": [
        [*INIT, _set("Fy_ex", 6e306), _step(2e-5)],
    ],
}
