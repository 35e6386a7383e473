"""The wording of the FMUs' messages, declared once for the pythonfmu FMU and the C core.

Every message an FMU logs, and every reason a message quotes, is a ``Message`` here: a
template in ``str.format``'s syntax with named fields. The pythonfmu adapter
(``slave.py``, ``slave_state.py``, the models of this package) formats it by calling it
(``STEP_DISCARDED(t=t, h=h, why=why)``); the C core (``native/instance.c``, ``fmi3.c``, and the
pythonfmu FMU's status shim ``pythonfmu_shim.c``) formats the printf constant generated
from it into ``native/cf_messages.h`` (``CF_MSG_STEP_DISCARDED``, by ``python -m
contact_fmu.native.abi_header --write``; tests/test_native_abi.py checks the committed
header is this table's).

How a field is written, on both targets (the one formatting rule):

- ``{x!r}``: the value as Python's ``repr`` writes it: for a float the shortest digits
  that read back (C: ``%s`` of the text instance.c's ``py_repr`` makes), for a String
  value its quoted text, for an Integer's whole value its digits;
- ``{x:g}``, ``{x:.6g}``: a double as C's ``%g``, ``%.6g`` (Python's format writes the
  same digits, ``inf`` and ``nan`` included);
- ``{x:d}``, ``{x:u}``, ``{x:zu}``: an int, an unsigned, a size (C's ``%d``, ``%u``,
  ``%zu``; Python writes each as ``d``);
- ``{x}``: text as it is (C: ``%s``); ``{api}`` is the FMI version's prefix of the call
  and status names, "fmi2" or "fmi3", ``{call}`` a call's name after it (``CALL_NAMES``).

C's arguments follow the fields in the order they appear, one per occurrence.
``raised``: the type of the exception that carries the text in Python, which
``slave_state.describe`` writes before it (``FloatingPointError: ...``); the C constant
includes it. ``home``: where the pythonfmu FMU words the message: ``FMU`` (through this
table, from contact_fmu/fmu), ``SHIM`` (its status shim, through cf_messages.h), the
numerics module that raises it (the numerics import no FMU module: its text is this
template's, tests/test_fmu_messages.py checks the pieces), or ``NATIVE`` where it does
not; ``only``: why a message has one target only (the other has no such call or no
such state).
"""

from __future__ import annotations

import string
from dataclasses import dataclass
from typing import Any

FMU = "contact_fmu/fmu"  # home: worded through this table by the FMU layer
SHIM = "pythonfmu_shim.c"  # home: the pythonfmu FMU's status shim, through cf_messages.h
NATIVE = "the native FMUs only"  # home of a message no pythonfmu FMU logs
API = "fmi2"  # the pythonfmu FMU's FMI version (its {api})


class _Formatter(string.Formatter):
    def format_field(self, value: Any, spec: str) -> str:
        return format(value, "d" if spec in ("u", "zu") else spec)


_FORMATTER = _Formatter()
# a field's format spec -> its printf conversion ("" and !r: text the caller made)
_PRINTF = {"": "%s", "g": "%g", ".6g": "%.6g", "d": "%d", "u": "%u", "zu": "%zu"}


@dataclass(frozen=True)
class Message:
    """A message's template (see the module docstring)."""

    template: str
    home: str = FMU
    raised: str | None = None
    only: str | None = None
    parts: tuple[Message, ...] = ()  # the templates composed into this one (compose)

    def __call__(self, **fields: Any) -> str:
        """The text, as the C core writes it from the same template."""
        return _FORMATTER.vformat(self.template, (), fields)  # the raised type: describe()'s

    def fields(self) -> list[tuple[str, str]]:
        """(name, how) of each field in order: how is "repr", "text" or the spec."""
        out = []
        for _, name, spec, conversion in string.Formatter().parse(self.template):
            if name is not None:
                out.append((name, "repr" if conversion == "r" else spec or "text"))
        return out

    def printf(self) -> str:
        """The C format: the template's literal text, each field its conversion."""
        parts = [f"{self.raised}: "] if self.raised else []
        for literal, name, spec, conversion in string.Formatter().parse(self.template):
            parts.append(literal.replace("%", "%%"))
            if name is not None:
                parts.append("%s" if conversion == "r" else _PRINTF[spec])
        return "".join(parts)

    def compose(self, **parts: Message) -> Message:
        """This template with fields replaced by other templates (C formats once)."""
        text = self.template
        for name, part in parts.items():
            assert "{" + name + "}" in text, name
            text = text.replace("{" + name + "}", part.template)
        return Message(text, self.home, self.raised, self.only, (self, *parts.values()))


# ---- the FMI calls messages name: (FMI 2.0 name, FMI 3.0 name), after the {api} prefix ---
# FMI 3.0 renamed the typed accessors and the FMU state calls, instantiates a
# co-simulation instance by its own call and sets the experiment up at
# EnterInitializationMode.
CALL_NAMES: dict[str, tuple[str, str]] = {
    "INSTANTIATE": ("Instantiate", "InstantiateCoSimulation"),
    "SETUP_EXPERIMENT": ("SetupExperiment", "EnterInitializationMode"),
    "ENTER_INIT": ("EnterInitializationMode", "EnterInitializationMode"),
    "EXIT_INIT": ("ExitInitializationMode", "ExitInitializationMode"),
    "TERMINATE": ("Terminate", "Terminate"),
    "GET_REAL": ("GetReal", "GetFloat64"),
    "GET_INTEGER": ("GetInteger", "GetInt32"),
    "GET_BOOLEAN": ("GetBoolean", "GetBoolean"),
    "GET_STRING": ("GetString", "GetString"),
    "SET_REAL": ("SetReal", "SetFloat64"),
    "SET_INTEGER": ("SetInteger", "SetInt32"),
    "SET_BOOLEAN": ("SetBoolean", "SetBoolean"),
    "SET_STRING": ("SetString", "SetString"),
    "DIRECTIONAL": ("GetDirectionalDerivative", "GetDirectionalDerivative"),
    "GET_STATE": ("GetFMUstate", "GetFMUState"),
    "SET_STATE": ("SetFMUstate", "SetFMUState"),
    "FREE_STATE": ("FreeFMUstate", "FreeFMUState"),
    "STATE_SIZE": ("SerializedFMUstateSize", "SerializedFMUStateSize"),
    "SERIALIZE": ("SerializeFMUstate", "SerializeFMUState"),
    "DESERIALIZE": ("DeSerializeFMUstate", "DeserializeFMUState"),
    "SET_DEBUG_LOGGING": ("SetDebugLogging", "SetDebugLogging"),
}


def call(key: str) -> str:
    """The pythonfmu FMU's (FMI 2.0) name of a call, with its prefix: "fmi2Terminate"."""
    return API + CALL_NAMES[key][0]


# ---- a value refused -------------------------------------------------------------------
# Var.check, _validate.InputError (whose f-string is this template: the numerics' errors)
INVALID = Message("{name} = {value!r} is invalid: must be {requirement}")
HELD = Message("{invalid}; doStep answers {api}Discard until it is corrected")
HELD_AT_GET = Message("{name}: {invalid} (held until corrected)")
SET_OUTPUT = Message("{name} is an output of this FMU: the value {value!r} set is ignored")
SET_FIXED = Message(
    "{name} is a fixed parameter and the model is initialised: {name} = {value!r} is "
    "ignored ({name} stays {now!r})"
)
START_TIME = Message("startTime = {start!r} is invalid: must be finite; using 0")
TUNE_REFUSED = Message(
    "{name} = {value!r} is refused: {why}",
    only="the native FMU's law takes any mu its range admits",
)
# pythonfmu's accessors with value references not of this FMU or of another type
GUARDED = Message(
    "{call}: value references {vrs}: {why}",
    only="the native FMUs word it VR_TYPE (their accessors are theirs)",
)
# the String parameters' choices (integrator.RollingBody's words)
METHOD_CHOICES = Message('"full" or "quasistationary"')
SCHEME_CHOICES = Message('"lobatto3c" or "sdirk2"')
# the requirements of field_times (body_transient.parse_times) and of a text too long
FIELD_TIMES_SYNTAX = Message("times in s separated by spaces or commas")
FIELD_TIMES_FINITE = Message("finite times in s")
FIELD_TIMES_MANY = Message(
    "at most {n:d} times (the native FMU's captures of the field)",
    home=NATIVE,
    only="the pythonfmu FMU's recorder takes any number of times",
)
TEXT_TOO_LONG = Message(
    "a text of fewer than {n:d} characters (the native FMU's)",
    home=NATIVE,
    only="the pythonfmu FMU holds a String of any length",
)

# ---- phases ------------------------------------------------------------------------------
CANNOT_INITIALISE = Message("cannot initialise the model: {why}")
CANNOT_START = Message("exitInitializationMode: the model cannot start: {why}")
SEE_ABOVE = Message("see the messages above")
# the shim's words (pythonfmu_shim.c) on the pythonfmu FMU: pythonfmu cannot answer them
EXIT_BEFORE_ENTER = Message(
    "exitInitializationMode refused: called before {api}{call}",
    home=SHIM,
)
TERMINATE_BEFORE_INIT = Message(
    "terminate refused: called before the model is initialised ({api}ExitInitializationMode {how})",
    home=SHIM,
)
NOT_CALLED = Message("not called", home=SHIM)
FAILED = Message("failed", home=SHIM)
SETUP_AFTER_INIT = Message(
    "{api}{call} after initialisation is ignored",
    home=NATIVE,
    only="pythonfmu answers fmi2SetupExperiment itself",
)

# ---- doStep ------------------------------------------------------------------------------
STEP_AFTER_TERMINATE = Message("doStep at t = {t!r} refused: called after {api}{call}")
STEP_BEFORE_INIT = Message(
    "doStep at t = {t!r} refused: called before the model is initialised "
    "({api}ExitInitializationMode not called)"
)
STEP_AFTER_FAILED_INIT = Message(
    "doStep at t = {t!r} refused: called before the model is initialised "
    "({api}ExitInitializationMode failed: {why})"
)
STEP_SIZE = Message("communicationStepSize = {h!r} is invalid: must be > 0 and finite")
STEP_TIME = Message("currentCommunicationPoint = {t!r} is invalid: must be the FMU's time {time!r}")
STEP_HELD = Message("doStep at t = {t!r} discarded, state unchanged: {why}")
STEP_DISCARDED = Message("doStep at t = {t!r} with h = {h!r} discarded, state unchanged: {why}")
STEP_FAILED = Message(
    "doStep discarded: {why}",
    only="an exception outside the step's own checks: the C core has none",
)
NO_OUTPUTS = Message("no outputs for the current inputs: {why}")
# slave._collect
OUTPUT_NOT_FINITE = Message("output {name} = {value!r} is not finite", raised="FloatingPointError")
# ranges.within_range: a state beyond the physical range of its speeds and rates
WITHIN_RANGE = Message("within abs <= {bound:g} ({why})")
RANGE_STEP = Message("the loads drive the body beyond it")
RANGE_START = Message("Omega_y0 = (Vx0 - vx0)/Rx: the model cannot start there")
OUT_OF_RANGE = INVALID.compose(requirement=WITHIN_RANGE)
# BodyModel.cap_note: a step taken in the budget's steps
CAP_NOTE = Message(
    "communication step h = {h:g} s needs more internal steps ({limits}) than max_work = "
    "{max_work:g} allows (each costs {work:g}): taken in {n:d} steps of {step:g} s"
)
CAP_LIMITS = Message("h_max = {h_max:g} s")
CAP_LIMITS_FIELD = Message("h_max = {h_max:g} s, cells_per_step = {cells:g}")
CAP_NOTE_BODY = CAP_NOTE.compose(limits=CAP_LIMITS)
CAP_NOTE_FIELD = CAP_NOTE.compose(limits=CAP_LIMITS_FIELD)

# ---- the models' own refusals --------------------------------------------------------------
# the numerics' own refusals (_validate.InputError: INVALID with these requirements)
REQ_POSITIVE = Message("> 0", home="_validate.py")  # _validate.positive
NOT_POSITIVE = INVALID.compose(requirement=REQ_POSITIVE)
# layer.LayerContact.__post_init__, beyond the declared ranges (name "k1 + k2", "kb + ks")
REQ_WINKLER = Message("> 0 (a Winkler layer carries the load)", home="laws/thin_layer.py")
WINKLER = INVALID.compose(requirement=REQ_WINKLER)
REQ_COMPLIANCE = Message("> 0 (tangential layer compliance)", home="laws/thin_layer.py")
COMPLIANCE = INVALID.compose(requirement=REQ_COMPLIANCE)
# dynamics.Body: A1, A2 (Eq. 23) divide by M Rx^2 + Iy
REQ_INERTIA = Message(
    "positive and finite with M Rx^2 > 0 (M = {M!r}, Rx = {Rx!r}, Iy = {Iy!r})",
    home="dynamics/body.py",
)
INERTIA = INVALID.compose(requirement=REQ_INERTIA)
# integrator.RollingBody._bounded (name "Fx_ex", "My_ex")
REQ_LOAD_FX = Message("<= {limit:g} mu P = {cap:.6g} N in magnitude", home="dynamics/integrator.py")
LOAD_LIMIT_FX = INVALID.compose(requirement=REQ_LOAD_FX)
REQ_LOAD_MY = Message(
    "<= {limit:g} mu P Rx = {cap:.6g} N m in magnitude", home="dynamics/integrator.py"
)
LOAD_LIMIT_MY = INVALID.compose(requirement=REQ_LOAD_MY)
NO_GROSS_SLIDING = Message(
    "eta = inf (Iy = 0) admits no gross sliding: |A2 Fx_ex - A1 My_ex/Rx| = {target:.6g} N "
    "reaches mu P = {muP:.6g} N",
    home="dynamics/integrator.py",
    raised="StageSolveError",
)
NO_ROOT = Message(
    "no root: the stage residual keeps its sign (loads beyond mu P?)",
    home="dynamics/solvers.py",
    raised="StageSolveError",
)
# integrator.WorkBudgetError, with the FMU's budget (body_model.BodyModel.step)
WORK_BUDGET = Message(
    "the stage solves need more than {limit:d} evaluations of the law{why}",
    home="dynamics/integrator.py",
    raised="WorkBudgetError",
)
BEYOND_MAX_WORK = Message(", beyond max_work = {max_work:g} (each costs {work:g})")
WORK_BUDGET_MAX = WORK_BUDGET.compose(why=BEYOND_MAX_WORK)
# halfspace TableLaw (spec.py): a table with layers outside its load nodes
REQ_TABLE_LOAD_RANGE = Message(
    "within the load range [{lo:g}, {hi:g}] N of the FMU's creep-force table (its layers, "
    "kb + ks > 0, break the load similarity)",
    home="halfspace/spec.py",
)
TABLE_LOAD_RANGE = INVALID.compose(requirement=REQ_TABLE_LOAD_RANGE)
# phase "transient" (body_transient.py, transient.py)
REQ_LIFTOFF = Message("> 0 in the transient phase (lift-off, P = 0, is the steady phase's)")
P_LIFTOFF = INVALID.compose(requirement=REQ_LIFTOFF)
REQ_MAX_WORK_FIELD = Message(
    ">= {work:g}, the work of one internal step on the {nx:d} x {ny:d} field"
)
MAX_WORK_FIELD = INVALID.compose(requirement=REQ_MAX_WORK_FIELD)
REQ_FIELD_FILE = Message("a writable file ({why})")
FIELD_FILE = INVALID.compose(requirement=REQ_FIELD_FILE)
FIELD_OUTGROWN = Message(
    "P = {value!r} is invalid: must be at most the load at set-up (its contact, a1 = {a1:g} m "
    "and a2 = {a2:g} m, outgrows the field laid there, X = {X:g} m and Y = {Y:g} m: the "
    "native FMU's field has the fixed size of {nx:d} x {ny:d} cells, the pythonfmu FMU's "
    "grows)",
    home=NATIVE,
    only="the pythonfmu FMU's field grows with the load",
)
FIELD_NO_ROOT = Message(
    "no slip velocity satisfies the stage equation (target force {target:.6g} N against mu "
    "P = {muP:.6g} N)",
    home="dynamics/thin_layer_field.py",
    raised="StageSolveError",
)
FIELD_SHIFT = Message(
    "the step would roll the traction field's lattice by more than {columns:g} columns (the "
    "loads or the step drive the body beyond what the field resolves)",
    home="dynamics/thin_layer_field.py",
    raised="FloatingPointError",
)
FIELD_NOT_FINITE = Message(
    "the traction field's step is not finite (the loads or the step drive it beyond the doubles)",
    home=NATIVE,
    raised="FloatingPointError",
    only="Python's field raises where a value first overflows, with numpy's words",
)
FIELD_SUMMARY = Message(
    "the traction field's summary is not finite",
    home=NATIVE,
    raised="FloatingPointError",
    only="no input reaches it; Python's field would fail in numpy's words",
)

# ---- FMU state ---------------------------------------------------------------------------
STATE_REFUSED = Message("the FMU state given to setFMUstate is refused: {why}")
STATE_UNCHANGED = Message("{refused}; the instance's state is unchanged")
STATE_HELD_NOTE = Message(
    " (doStep refused until a valid state is set)",
    only="pythonfmu's binary alone (no shim) cannot answer fmi2Error at setFMUstate",
)
STATE_TIME = Message("its time {time!r} is not a finite float")
STATE_OUTPUT = Message("its output {name} = {value!r} is not a finite float")
STATE_RECORD = Message(
    "its record of invalid values does not match its values ({value}, recorded as {recorded})"
)
STATE_NAMED = Message("{name} = {value!r}")
STATE_PARAMS = Message("its model's parameters differ from its values or are invalid ({value})")
STATE_MODEL = Message("its model state cannot be restored ({why})")
STATE_MODEL_NOT_FINITE = Message("it is not finite", home=NATIVE, only="Python says why")
# the pythonfmu FMU's state format (a dict of Python values: slave_state.py)
_PY_STATE = "the pythonfmu FMU's state format (the native FMU's is its C core, whole)"
STATE_OWNER = Message(
    "a state of the FMU {owner!r}, not of this FMU ({package!r})",
    only=_PY_STATE,
)
STATE_UNREADABLE = Message("the state cannot be read ({why})", only=_PY_STATE)
STATE_FIELDS = Message("not a state of this FMU (its fields differ)", only=_PY_STATE)
STATE_FLAG = Message("its flag {flag!r} is not a bool", only=_PY_STATE)
STATE_VARIABLES = Message("its variables differ from this FMU's", only=_PY_STATE)
STATE_VALUE_TYPE = Message("its value of {name}, {value!r}, is not a {kind}", only=_PY_STATE)
STATE_RECORD_TYPE = Message("its record of invalid values {record!r} is not a dict", only=_PY_STATE)
STATE_OUTPUTS = Message("its outputs differ from this FMU's", only=_PY_STATE)
STATE_OUT_MU = Message("its outputs' mu {mu!r} is not a positive float", only=_PY_STATE)
STATE_MODEL_PART = Message("its model part is not (parameters, snapshot)", only=_PY_STATE)
STATE_COULOMB = Message(
    "its outputs break Coulomb's bound: abs(T) = {T!r} N > mu P = {muP!r} N", only=_PY_STATE
)
STATE_NOT_A_VARIABLE = Message("{name!r}, not a variable of this FMU", only=_PY_STATE)
# the pythonfmu FMU's two paths (fmu/slave_core.py): its C core where carried, its
# Python path with CONTACT_FMU_CORE=0 or CONTACT_FMU_NATIVE=0; their states refuse each other
_TWO_PATHS = "the pythonfmu FMU alone runs either its C core or its Python path"
STATE_OF_CORE = Message(
    "a state of this FMU's C core; this instance runs its Python path "
    "(CONTACT_FMU_CORE=0 or CONTACT_FMU_NATIVE=0 when it was made)",
    only=_TWO_PATHS,
)
STATE_OF_PYTHON = Message(
    "a state of this FMU's Python path (saved with CONTACT_FMU_CORE=0 or "
    "CONTACT_FMU_NATIVE=0); this instance runs its C core",
    only=_TWO_PATHS,
)
CORE_REFUSED = Message(
    "the C core refused the call (status {status:d}; its reason logged before)",
    only="pythonfmu's binary alone (no shim) cannot answer fmi2Error",
)
CORE_UNUSABLE = Message(
    "the FMU's C core cannot start ({why}): the adapter's Python path runs", only=_TWO_PATHS
)
CORE_RELEASED = Message(
    "called after the instance's C core was freed (fmi2FreeInstance, fmi2Reset)",
    only=_TWO_PATHS,
)
STATE_FLAGS = Message(
    "its phase and flags ({phase:d}, {built:d}, {dirty:d}, {tried:d}) are not this FMU's",
    home=NATIVE,
    only="the pythonfmu FMU's state holds no phase (pythonfmu keeps it)",
)
STATE_DISAGREE = Message(
    "its values of {name} disagree",
    home=NATIVE,
    only="the pythonfmu FMU's state holds each value once",
)
# the registry of live states (the shim's words on the pythonfmu FMU)
NOT_A_STATE = Message(
    "{api}{call}: {pointer} is not an FMU state of this instance (never given, or freed)",
    home=SHIM,
)
NO_PLACE = Message("{api}{call}: no place for the {what} given", home=NATIVE, only="pythonfmu's")
NO_STATE = Message("{api}{call}: no state given", home=NATIVE, only="pythonfmu's")
SERIALIZE_BUFFER = Message(
    "{api}{call}: no buffer, or one of {size:zu} bytes ({needed:zu} needed)",
    home=NATIVE,
    only="the shim asks for the exact size (SERIALIZE_SIZE)",
)
SERIALIZE_SIZE = Message(
    "{api}{call}: size = {size:zu}, the state needs {needed:zu} bytes ({api}{size_call})",
    home=SHIM,
    only="the native FMUs take a larger buffer too (SERIALIZE_BUFFER)",
)
# bytes refused at deserialisation: the envelope of either format (magic, format version,
# GUID, length, checksum) names the same faults in the same words
BYTES_REFUSED = Message("{api}{call}: the {size:zu} bytes are refused: {why}", home=SHIM)
NOT_SERIALIZED = Message("not a serialized contact_fmu FMU state", home=SHIM)
OTHER_VERSION = Message("a state of another format version", home=SHIM)
OTHER_FMU = Message("a state of another FMU (its GUID differs from this FMU's)", home=SHIM)
LENGTH_DIFFERS = Message("truncated or extended (its length differs from {expected})", home=SHIM)
LENGTH_RECORDED = Message("the recorded one", home=SHIM, only="the shim's envelope records it")
LENGTH_OF_STATES = Message(
    "this FMU's states'", home=NATIVE, only="a native FMU's states have one length"
)
CHECKSUM_DIFFERS = Message("damaged (its checksum differs)", home=SHIM)
PAYLOAD_DIFFERS = Message(
    "damaged (its payload length differs from this FMU's)",
    home=NATIVE,
    only="the shim's payload is pythonfmu's, whose length it records",
)
NO_BYTES = Message("no bytes", home=NATIVE, only="the shim refuses NULL bytes as not a state")
TOO_MANY_STATES = Message(
    "more than {n:d} FMU states held at once: free some ({api}{call})",
    home=SHIM,
    only="the native FMUs hold any number (a hash set)",
)
# the shim's own (pythonfmu's binary behind it, its instantiation)
SHIM_LOAD = Message(
    "cannot load pythonfmu's binary {path}: {why}", home=SHIM, only="the pythonfmu FMU's binary"
)
SHIM_LACKS = Message(
    "pythonfmu's binary lacks {name}", home=SHIM, only="the pythonfmu FMU's binary"
)
CO_SIMULATION_ONLY = Message(
    "this FMU is for co-simulation only (fmuType = {type:d})",
    home=SHIM,
    only="the native front ends refuse model exchange in their own version's terms",
)
RESOURCE_URI = Message(
    "resourceLocation {uri} is not a local file URI",
    home=SHIM,
    only="pythonfmu needs its resources folder; the native FMUs read a table from it only",
)
NOT_A_VARIABLE = Message(
    "value reference {vr:u} is not a variable of this FMU",
    home=SHIM,
    only="the status cell's value reference, the shim's own",
)

# ---- instantiation, variables, and calls of the native FMUs only ----------------------------
OUT_OF_MEMORY = Message("{api}{call}: out of memory", home=SHIM)
GUID = Message(
    "{api}{call}: GUID {guid} is not this FMU's ({own})", home=NATIVE, only="pythonfmu's"
)
RESOURCE_PATH = Message(
    "{api}{call}: the resource path is too long", home=NATIVE, only="tables load in Python"
)
TABLE_OPEN = Message(
    "{api}{call}: the creep-force table {path} cannot be opened",
    home=NATIVE,
    only="tables load in Python",
)
TABLE_REFUSED = Message(
    "{api}{call}: the creep-force table {path} is refused: {why}",
    home=NATIVE,
    only="tables load in Python",
)
VR_TYPE = Message(
    "{api}{call}: value reference {vr:u} is not a variable of this type",
    home=NATIVE,
    only="pythonfmu's accessors: slave._guarded words its exception",
)
NO_BOOLEAN = Message(
    "{api}{call}: this FMU has no Boolean variable (vr {vr:u})",
    home=NATIVE,
    only="pythonfmu's accessors: slave._guarded words its exception",
)
LINE_BEFORE_INIT = Message(
    "{name}: the model is set up at {api}ExitInitializationMode: read it after",
    home=NATIVE,
    only="FMI 3.0 arrays",
)
LINE_NOT_FINITE = Message(
    "{name}: the traction field is not finite at vx = {vx:g}, vy = {vy:g}, Vx = {Vx:g}, "
    "Omega_z = {Omega_z:g}",
    home=NATIVE,
    only="FMI 3.0 arrays",
)
DIRECTIONAL_MODE = Message(
    "{api}{call}: provided by the contact mode only (providesDirectionalDerivative is false here)",
    home=NATIVE,
    only="directional derivatives",
)
DIRECTIONAL_BEFORE_INIT = Message(
    "{api}{call}: the model is not initialised", home=NATIVE, only="directional derivatives"
)
DIRECTIONAL_BAD_INPUT = Message(
    "{api}{call}: an input is invalid (see setReal)", home=NATIVE, only="directional derivatives"
)
DIRECTIONAL_VR = Message(
    "{api}{call}: value reference {vr:u} is not a Real {kind}",
    home=NATIVE,
    only="directional derivatives",
)
DIRECTIONAL_DIRECTION = Message(
    "{api}{call}: a direction is not finite", home=NATIVE, only="directional derivatives"
)
DIRECTIONAL_NEAR = Message(
    "{api}{call}: the outputs are not finite next to the inputs",
    home=NATIVE,
    only="directional derivatives",
)
DIRECTIONAL_NOT_FINITE = Message(
    "{api}{call}: the derivative of {name} is not finite at the current inputs",
    home=NATIVE,
    only="directional derivatives",
)


def table() -> dict[str, Message]:
    """Every message of this module by name (the C constant is CF_MSG_<name>)."""
    return {k: v for k, v in globals().items() if isinstance(v, Message)}
