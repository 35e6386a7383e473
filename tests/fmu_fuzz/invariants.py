"""What must hold after every call of a run (the FMUs' contract: docs/reliability.md).

``check(kind, ops, result)`` replays the run's call records against a model of the
instance (its phase, the values it holds, the parameters in force, its time, the load
its outputs belong to) and returns the violations, each a class name and the record's
index. The rules:

- no crash, no hang, no fmi2Fatal, from any call sequence;
- never silent: a call that answers fmi2OK or fmi2Warning logs no message of status
  fmi2Error or worse (exitInitializationMode of a model that cannot start, getReal
  serving outputs it could not update, setFMUstate refusing a state: each must answer
  fmi2Error);
- doStep before initialisation answers fmi2Error, after fmi2Terminate not fmi2OK;
- a step size <= 0 or not finite, or a communication point off the FMU's time by
  more than 1e-10 max(1, |t|) (TIME_RTOL), is not answered fmi2OK/fmi2Warning;
- an inadmissible value (outside the declared range, NaN, inf) of a parameter or input
  is refused: fmi2Error at fmi2SetXXX, or else fmi2Error at exitInitializationMode /
  fmi2Discard or fmi2Error at the next doStep; either with a logged message naming
  the variable; after the value is corrected, the same step as before answers
  fmi2OK or fmi2Warning (the instance is usable again);
- getReal with fmi2OK/fmi2Warning returns only finite numbers, and |T| = hypot(Tx, Ty)
  <= mu P (1 + 1e-12) with the mu and P its outputs belong to (contact mode: the inputs
  now set; body mode: those of the last step); in contact mode no output is served
  with OK while an input is inadmissible (it cannot belong to the current inputs);
- momentum balance, Eqs. (8)-(10), over every doStep answered OK/Warning: with the
  loads held over the step and |T| <= mu P, M dVx/dt = Fx_ex - Tx and Iy dOmega_y/dt =
  My_ex + Rx Tx (contact_fmu/dynamics/body.py's sign of Eq. 9) give
  |dVx - h Fx_ex/M| <= h mu P/M, |dOmega_y - h My_ex/Iy| <= h Rx mu P/Iy and
  |dVy - h Fy_ex/M| <= h mu P/M (Eq. 10); the rigid-body FMU takes Tx as input, so its
  changes are h (Fx_ex - Tx)/M and h (My_ex + Rx Tx)/Iy exactly. Rounding term: an
  internal step adds an increment to the state (one rounding of at most eps/2 of the
  new value) formed by a few operations on the loads and stage values (a few eps of
  their sizes); over at most N internal steps (N = 10^4, the body model's cap
  MAX_SUBSTEPS; 1 for the rigid body) that is below 16 N eps (|x0| + |x1| + the
  increment's terms), and 4 eps (...) for the rigid body's single update. The body's
  stepper holds vx and Omega_y (Eq. 20), so its Vx = vx + Rx Omega_y is resolved only
  to eps (Rx |Omega_y| + |vx|) (and Omega_y to eps (|Vx| + |vx|)/Rx): a violation within
  that is classed "momentum_balance(precision)" (values beyond what doubles resolve in
  that formulation, answered OK: the target is a refusal or a declared range), beyond
  it "momentum_balance"; the quasistationary stepper's are tagged with its name;
- a round trip (get state, k steps, set state, the same k steps) repeats statuses and
  outputs bit for bit;
- freeFMUstate of a state already freed (a dangling handle) and setFMUstate of a freed
  state are not answered fmi2OK.
"""

from __future__ import annotations

import copy
import math
from dataclasses import dataclass, field
from typing import Any

from .kinds import Kind
from .pool import Result, signal_name

OK, WARNING, DISCARD, ERROR, FATAL = range(5)
EPS = 2.220446049250313e-16
# A communication point may differ from the FMU's time by the rounding of a master's
# accumulated steps (a few ulp per step: 1e4 steps of ~1e-16 relative stay below 1e-12),
# not by a fraction of the step: the 5e-4 s at t = 1e6 s (5e-10 relative) is
# refused, so the bound is 1e-10 max(1, |t|).
TIME_RTOL = 1e-10
N_BODY = 10_000  # the body model's most internal steps per doStep (MAX_SUBSTEPS)


@dataclass
class Violation:
    cls: str  # the failure class
    index: int  # the record's index in result.records (-1: the run as a whole)
    detail: str = ""


@dataclass
class Track:
    """What the instance holds, as far as the calls so far determine it."""

    phase: str = "instantiated"  # instantiated, init, ready, error, terminated
    values: dict[str, Any] = field(default_factory=dict)  # held parameter/input values
    inforce: dict[str, Any] | None = None  # the parameters the model was set up with
    known: bool = True  # False after a damaged or crafted state was accepted
    t: float | None = 0.0  # the FMU's time
    load: tuple[float, float] | None = None  # (mu, P) the body's outputs belong to
    named: dict[str, list[str]] = field(default_factory=dict)  # messages since a bad set
    # a doStep before initialisation was answered OK (itself a violation): what the
    # model was set up with is unknown from then on
    tainted: bool = False


def _finite(values: dict) -> bool:
    return all(not isinstance(v, str) and math.isfinite(v) for v in values.values())


class Checker:
    def __init__(self, kind: Kind, ops: list[dict], result: Result) -> None:
        self.kind, self.ops, self.res = kind, ops, result
        self.out: list[Violation] = []
        start = {n: kind.start(n) for n in kind.names("parameter") + kind.names("input")}
        self.tracks = {0: Track(values=dict(start)), 1: Track(values=dict(start))}
        self.start = start
        self.slots: dict[int, Track | None] = {}  # state slot -> the track it holds
        self.bufs: dict[int, Track | None] = {}
        # where a state came from: own, foreign (the other instance), damaged, crafted
        self.origin: dict[int, str] = {}
        self.buf_origin: dict[int, str] = {}
        self.freed: set[int] = set()
        self.roundtrip: Track | None = None
        self.badfix_pre: int | None = None  # status of the last badfix-pre step

    def flag(self, cls: str, k: int, detail: str = "") -> None:
        self.out.append(Violation(cls, k, detail))

    # ---- the run ------------------------------------------------------------------------
    def run(self) -> list[Violation]:
        recs = self.res.records
        for k, rec in enumerate(recs):
            op = self.ops[rec["i"]] if 0 <= rec["i"] < len(self.ops) else {}
            inst = int(op.get("inst", 0)) if rec["call"] != "instantiate" else rec.get("inst", 0)
            self.record(k, rec, op, self.tracks[inst])
        if self.res.crashed:
            last = recs[-1] if recs else {"i": -1, "call": "start"}
            self.flag(
                "crash",
                len(recs),
                f"{signal_name(self.res.returncode)} after {last['call']} of op {last['i']}; "
                f"stack: {_stack(self.res.stderr_tail)}",
            )
        if self.res.hung:
            self.flag("hang", len(recs), f"no answer within the limit ({self.res.seconds:.0f} s)")
        return self.out

    def record(self, k: int, rec: dict, op: dict, tr: Track) -> None:
        call, st, log = rec["call"], rec["status"], rec["log"]
        if call == "setFMUstate" and "slot" in op and rec.get("phase") != "roundtrip":
            call = f"setFMUstate[{self.origin.get(op['slot'], 'unknown')}]"
        if rec.get("freed"):
            call = "setFMUstate[freed]"
        if st >= FATAL:
            self.flag(f"fatal:{call}", k, _msgs(log))
            return
        if st <= WARNING and any(s >= ERROR for s, _ in log):
            if not call.startswith("set") or call.startswith("setFMUstate"):
                self.flag(f"silent_error:{call}", k, _msgs(log))
        call = rec["call"]
        handler = getattr(self, "on_" + call, None)
        if handler is not None:
            handler(k, rec, op, tr)

    # ---- life cycle -----------------------------------------------------------------
    def on_setupExperiment(self, k, rec, op, tr):
        tr.t = float(op.get("t0", 0.0))

    def on_enterInitializationMode(self, k, rec, op, tr):
        if rec["status"] <= WARNING and tr.phase == "instantiated":
            tr.phase = "init"

    def on_exitInitializationMode(self, k, rec, op, tr):
        bad = [n for n, v in tr.values.items() if not self.kind.admissible(n, v)]
        st = rec["status"]
        if tr.tainted:
            tr.phase = "ready" if st <= WARNING else "error"
            return
        if bad:
            if st != ERROR:
                self.flag("bad_value_init_not_error", k, f"{bad} held; answered {st}")
            elif not self._named(bad, tr, rec):
                self.flag("bad_value_unnamed", k, f"{bad}: {_msgs(rec['log'])}")
        if st <= WARNING:
            tr.phase = "ready"
            tr.inforce = {n: tr.values[n] for n in self.kind.names("parameter")}
            tr.load = self._load(tr)
            # accepted with a bad value held (flagged above): whether a model was set up,
            # and with what, is unknown from then on (parameters may still be settable)
            tr.known = not bad
            tr.tainted = bool(bad)
        else:
            tr.phase = "error"

    def on_terminate(self, k, rec, op, tr):
        if rec["status"] <= WARNING:
            tr.phase = "terminated"

    def on_reset(self, k, rec, op, tr):
        if rec["status"] <= WARNING:
            fresh = Track(values=dict(self.start))
            tr.__dict__.update(fresh.__dict__)

    # ---- values -----------------------------------------------------------------------
    def on_setReal(self, k, rec, op, tr):
        self._set(k, rec, op, tr)

    on_setInteger = on_setString = on_setReal

    def _set(self, k, rec, op, tr):
        name, value = op["name"], op["value"]
        causality = self.kind.variables[name].causality
        st = rec["status"]
        tunable = self.kind.variables[name].variability == "tunable"  # mu: takes effect
        if causality == "output" or (
            causality == "parameter" and tr.phase == "ready" and not tunable
        ):
            return  # illegal set: ignored by the FMU (an error status is the right answer)
        if st <= WARNING:
            tr.values[name] = value
            if tunable and tr.phase == "ready" and tr.inforce is not None:
                if self.kind.admissible(name, value):  # the next step's (the body's outputs
                    tr.inforce[name] = value  # keep tr.load until then)
            if not self.kind.admissible(name, value):
                tr.named[name] = [m for _, m in rec["log"]]
            else:
                tr.named.pop(name, None)
        elif st == ERROR and not self.kind.admissible(name, value):
            if not any(name in m for _, m in rec["log"]):
                self.flag("bad_value_unnamed", k, f"{name} = {value!r}: {_msgs(rec['log'])}")

    def _named(self, names: list[str], tr: Track, rec: dict) -> bool:
        msgs = [m for _, m in rec["log"]] + [m for n in names for m in tr.named.get(n, [])]
        return all(any(n in m for m in msgs) for n in names)

    def _load(self, tr: Track) -> tuple[float, float] | None:
        """(mu, P) of the outputs of a body-mode step or initialisation, if admissible."""
        p = tr.inforce or {}
        mu, P = p.get("mu", self.kind.start("mu") if "mu" in self.start else None), None
        if "P" in tr.values:
            P = tr.values["P"]
        if mu is None or P is None:
            return None
        if not (self.kind.admissible("mu", mu) and self.kind.admissible("P", P)):
            return None
        return float(mu), float(P)

    def on_getReal(self, k, rec, op, tr):
        st, values = rec["status"], rec.get("values", {})
        if st > WARNING or tr.phase in ("instantiated", "init"):
            return
        if not _finite(values):
            bad = {n: v for n, v in values.items() if isinstance(v, str) or not math.isfinite(v)}
            # an output, or only the held value of an input/parameter set so
            outs = [n for n in bad if self.kind.variables[n].causality == "output"]
            self.flag("nonfinite_ok:output" if outs else "nonfinite_ok:held_value", k, f"{bad}")
            return
        if not tr.known:
            return
        mode = self.kind.mode
        if mode == "contact":
            bad = [n for n in self.kind.names("input") if not self.kind.admissible(n, tr.values[n])]
            if bad and tr.phase == "ready":
                self.flag("stale_outputs_ok", k, f"inputs {bad} inadmissible, getReal OK")
                return
            mu, P = (tr.inforce or {}).get("mu"), tr.values["P"]
            admissible = mu is not None and self.kind.admissible("mu", mu)
            load = (mu, P) if admissible and self.kind.admissible("P", P) else None
        else:
            load = tr.load
        if load and "Tx" in values and self.kind.variables["Tx"].causality == "output":
            T = math.hypot(values["Tx"], values.get("Ty", 0.0))
            mu, P = load
            if T > mu * P * (1.0 + 1e-12):
                ratio = T / (mu * P) if mu * P > 0.0 else math.inf  # mu P may underflow
                self.flag("T_exceeds_muP", k, f"|T| = {T!r} = {ratio!r} mu P (P = {P!r})")

    # ---- steps ---------------------------------------------------------------------------
    def on_doStep(self, k, rec, op, tr):
        st, t, h = rec["status"], rec["t"], rec["h"]
        tag = op.get("tag")
        if tr.phase in ("instantiated", "init"):
            if st != ERROR:
                self.flag("step_before_init_not_error", k, f"phase {tr.phase}, answered {st}")
            if st <= WARNING:  # it did step: the FMU's time moved
                tr.t, tr.tainted, tr.known = t + h, True, False
            return
        if tr.phase == "terminated":
            if st <= WARNING:
                self.flag("step_after_terminate_ok", k, f"answered {st}")
            return
        if tr.phase != "ready":
            return
        ok = st <= WARNING
        if not (math.isfinite(h) and h > 0.0) and ok:
            self.flag("bad_step_size_ok", k, f"h = {h!r}")
        if tr.t is not None and ok:
            off = abs(t - tr.t) if math.isfinite(t) else math.inf
            if off > TIME_RTOL * max(1.0, abs(tr.t)):
                self.flag("time_off_ok", k, f"t = {t!r}, FMU time {tr.t!r}, h = {h!r}")
        bad = [n for n, v in tr.values.items() if not self.kind.admissible(n, v)]
        if bad and tr.known:
            if st not in (DISCARD, ERROR):
                self.flag("bad_value_step_not_refused", k, f"{bad} held; answered {st}")
            elif not self._named(bad, tr, rec):
                self.flag("bad_value_unnamed", k, f"{bad}: {_msgs(rec['log'])}")
        if tag == "badfix-pre":
            self.badfix_pre = st
        elif tag == "badfix-fix" and self.badfix_pre is not None:
            if self.badfix_pre <= WARNING and not bad and tr.known and not ok:
                self.flag("not_usable_after_fix", k, f"answered {st}: {_msgs(rec['log'])}")
        if not ok:
            return
        if tr.known:
            self._momentum(k, rec, tr)
        tr.t = t + h
        if self.kind.mode != "contact":
            tr.load = self._load(tr)

    def _momentum(self, k: int, rec: dict, tr: Track) -> None:
        recs = self.res.records
        before, after = recs[k - 1], recs[k + 1] if k + 1 < len(recs) else None
        if after is None or before.get("phase") != "before" or after.get("phase") != "after":
            return
        if before["status"] > WARNING or after["status"] > WARNING:
            return
        x0, x1 = before["values"], after["values"]
        if not (_finite(x0) and _finite(x1)):
            return
        p, v = tr.inforce or {}, tr.values
        if any(not self.kind.admissible(n, x) for n, x in {**p, **v}.items()):
            return
        h = rec["h"]
        M, Rx, Iy = p.get("M"), p.get("Rx"), p.get("Iy")
        Fx, My, Fy = (float(v.get(n, 0.0)) for n in ("Fx_ex", "My_ex", "Fy_ex"))
        if M is None:
            return
        if self.kind.mode == "rigid_body":
            Tx = float(v["Tx"])
            checks = [("Vx", h * (Fx - Tx) / M, 0.0, 4.0, h * (abs(Fx) + abs(Tx)) / M, 0.0)]
            if Iy > 0.0:
                d = h * (My + Rx * Tx) / Iy
                terms = h * (abs(My) + abs(Rx * Tx)) / Iy
                checks.append(("Omega_y", d, 0.0, 4.0, terms, 0.0))
        else:
            mu, P = float(p["mu"]), float(v["P"])
            n = 16.0 * N_BODY
            # the stepper's state is the slip vx and Omega_y (Eq. 20), Vx = vx + Rx Omega_y:
            # its Vx carries the rounding of Rx |Omega_y| and its Omega_y that of |Vx| / Rx
            Omega_y0 = (float(p.get("Vx0", 0.0)) - float(p.get("vx0", 0.0))) / Rx
            spin = Rx * _sizes(x0, x1, "Omega_y", fallback=abs(Omega_y0))
            slip = _sizes(x0, x1, "vx")
            terms = h * (abs(Fx) + mu * P) / M
            checks = [("Vx", h * Fx / M, h * mu * P / M, n, terms, spin + slip)]
            if Iy and Iy > 0.0:
                terms = h * (abs(My) + Rx * mu * P) / Iy
                extra = (_sizes(x0, x1, "Vx") + slip) / Rx
                checks.append(("Omega_y", h * My / Iy, h * Rx * mu * P / Iy, n, terms, extra))
            if self.kind.cfg.vy == "eq10":
                terms = h * (abs(Fy) + mu * P) / M
                checks.append(("Vy", h * Fy / M, h * mu * P / M, n, terms, 0.0))
        for name, expect, slack, factor, terms, extra in checks:
            if name not in x0 or name not in x1:
                continue
            d = x1[name] - x0[name]
            r = factor * EPS * (abs(x0[name]) + abs(x1[name]) + terms)
            if not abs(d - expect) <= slack * (1.0 + 1e-12) + r:
                # within what the (vx, Omega_y) formulation can resolve at these sizes: a
                # value beyond the doubles' reach answered OK (refuse it, or declare a range)
                resolvable = abs(d - expect) > slack * (1.0 + 1e-12) + r + factor * EPS * extra
                method = v.get("method", "full")  # "quasistationary": Eq. 26's stepper
                tags = [] if method == "full" else [method]
                tags += [] if resolvable else ["precision"]
                self.flag(
                    "momentum_balance" + (f"({','.join(tags)})" if tags else ""),
                    k,
                    f"d{name} = {d!r} over h = {h!r}: the balance allows {expect!r} +- "
                    f"{slack + r!r} (loads {dict(v)})",
                )

    # ---- FMU states -----------------------------------------------------------------------
    def on_getFMUstate(self, k, rec, op, tr):
        if rec["status"] > WARNING:
            return
        snap = copy.deepcopy(tr)
        if rec.get("phase") == "roundtrip":
            self.roundtrip = snap
        else:
            self.slots[op["slot"]] = snap
            self.freed.discard(op["slot"])
            self.origin[op["slot"]] = "own" if int(op.get("inst", 0)) == 0 else "foreign"

    def on_setFMUstate(self, k, rec, op, tr):
        st = rec["status"]
        if rec.get("skipped"):
            return
        if rec.get("freed"):
            if st <= WARNING:
                self.flag("freed_state_set_ok", k, "setFMUstate of a freed state answered OK")
            tr.known = False
            return
        src = self.roundtrip if rec.get("phase") == "roundtrip" else self.slots.get(op["slot"])
        if st > WARNING:
            return
        if src is None:
            tr.known, tr.t = False, None
            return
        tr.__dict__.update(copy.deepcopy(src).__dict__)

    def on_freeFMUstate(self, k, rec, op, tr):
        if rec.get("phase") == "roundtrip" or rec.get("skipped") or "slot" not in op:
            self._roundtrip(k, rec)
            return
        slot = op["slot"]
        if slot in self.freed and rec.get("before") and rec["status"] <= WARNING:
            self.flag("double_free_ok", k, "freeFMUstate of a freed (dangling) state answered OK")
        self.freed.add(slot)

    def _roundtrip(self, k: int, rec: dict) -> None:
        series = rec.get("series")
        if not series or len(series) != 2 or len(series[0]) != len(series[1]):
            return
        a, b = series
        if all(s[0] <= WARNING and s[1] <= WARNING for s in a + b) and a != b:
            diff = next(j for j in range(len(a)) if a[j] != b[j])
            keys = [n for n in a[diff][2] if a[diff][2][n] != b[diff][2].get(n)]
            self.flag("roundtrip_not_bitexact", k, f"step {diff}: {keys}")
        elif [s[0] for s in a] != [s[0] for s in b]:
            self.flag("roundtrip_status_differs", k, f"{[s[0] for s in a]} vs {[s[0] for s in b]}")

    def on_serializeFMUstate(self, k, rec, op, tr):
        src = self.slots.get(op["slot"])
        self.bufs[op["buf"]] = src if rec["status"] <= WARNING else None
        self.buf_origin[op["buf"]] = "bytes," + self.origin.get(op["slot"], "unknown")

    def on_craft(self, k, rec, op, tr):
        self.bufs[op["buf"]] = None  # the state is no longer one the FMU wrote
        self.buf_origin[op["buf"]] = f"crafted:{op['edit'][0]}"

    def on_deSerializeFMUstate(self, k, rec, op, tr):
        src = self.bufs.get(op["buf"])
        damaged = bool(op.get("damage"))
        self.slots[op["slot"]] = None if (damaged or src is None) else copy.deepcopy(src)
        self.freed.discard(op["slot"])
        origin = self.buf_origin.get(op["buf"], "unknown")
        self.origin[op["slot"]] = f"damaged:{op['damage'][0]}" if damaged else origin


def _sizes(x0: dict, x1: dict, name: str, fallback: float = 0.0) -> float:
    """|x| before plus after the step (2 fallback where the FMU does not output x)."""
    if name in x0 and name in x1:
        return abs(x0[name]) + abs(x1[name])
    return 2.0 * fallback


def _stack(stderr: str) -> str:
    """The worker's Python frames from faulthandler's report of the crash."""
    frames = [ln.strip() for ln in stderr.splitlines() if ln.strip().startswith("File")]
    return " < ".join(frames[:3]) or stderr[-300:]


def _msgs(log: list) -> str:
    return " | ".join(f"[{s}] {m}" for s, m in log)[:400]


def check(kind: Kind, ops: list[dict], result: Result) -> list[Violation]:
    return Checker(kind, ops, result).run()
