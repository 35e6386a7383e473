"""What a host sees when the FMU refuses a value, with debug logging off.

FMI 2.0 (section 2.1.5): debug logging (fmi2SetDebugLogging, loggingOn) gates the FMU's
debug messages, not the explanation of a call that answered fmi2Warning, fmi2Discard or
fmi2Error. A tool user who sets mu = -1 must read why, naming mu and its bound, in the
importer's logger without switching debug logging on: through fmpy's ``simulate_fmu``
as a user calls it, for the pythonfmu FMU (whose status shim passes the adapter's
messages on while pythonfmu's own logger drops them) and for the native FMU.
"""

from __future__ import annotations

import ast
import re
import string
import subprocess
import sys
from pathlib import Path

import fmpy
import pytest

import fmu_build
from contact_fmu.fmu import messages as words
from contact_fmu.fmu import variables as fv
from contact_fmu.scenario import load
from fmu_build import native_fmu

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "out" / "fmu"
FIG13 = ROOT / "scenarios" / "fig13.toml"


@pytest.fixture(scope="module", params=["pythonfmu", "native"])
def fmu(request) -> Path:
    build = fmu_build.build if request.param == "pythonfmu" else native_fmu.build
    return build(load(FIG13).config, OUT).path


def run(fmu: Path, **kwargs) -> tuple[list[tuple[int, str]], Exception | None]:
    """simulate_fmu with a logger of our own and debug logging off (fmpy's default)."""
    messages: list[tuple[int, str]] = []

    def logger(env, name: bytes, status: int, category: bytes, message: bytes) -> None:
        messages.append((status, message.decode()))

    try:
        fmpy.simulate_fmu(str(fmu), stop_time=1e-3, output_interval=1e-4, logger=logger,
                          debug_logging=False, **kwargs)  # fmt: skip
    except Exception as e:  # fmpy raises on fmi2Error: the message must be logged too
        return messages, e
    return messages, None


def test_a_refused_value_is_explained_without_debug_logging(fmu):
    """mu = -1: mu's range is (0, inf) (variables.py); the call is refused (fmi2Error
    or fmi2Discard, never OK) and one message of that status names mu, the value and
    the bound."""
    decl = fv.BY_NAME["mu"]
    bound = f"{'>' if decl.open_min else '>='} {decl.min:g}"  # "> 0"
    messages, error = run(fmu, start_values={"mu": -1.0})
    assert error is not None  # fmpy stops at the refused start value
    refused = [m for s, m in messages if s >= 2 and "mu" in m and "-1" in m]
    assert refused, messages
    assert any(f"must be {bound}" in m for m in refused), refused


def test_no_debug_messages_reach_the_host_without_debug_logging(fmu):
    """A run that goes well: no messages of status OK, so debug logging still gates the
    debug output."""
    messages, error = run(fmu, start_values={"mu": 0.3})
    assert error is None
    assert [m for s, m in messages if s == 0] == []


def test_messages_reach_the_instance_that_logged_them_and_outlive_it(fmu):
    """fmpy hands every FMI 2.0 message of the process to one global callback (the last
    registered). Two live Instances: mu = -1 set on the first is logged to the first
    only. Then, with both closed and collected, fmpy's own simulate_fmu of a model that
    cannot start (Rx = 5e-324 with Iy = 0, see test_fmu_fmpy) prints its message through
    fmpy's printer, instead of calling a freed callback (a segmentation fault). Run in a
    fresh process, so that nothing else in it registered a logger."""
    code = f"""
import gc
import fmpy
from fmpy.fmi1 import FMICallException
from contact_fmu.scenario.instance import Instance

a = Instance({str(fmu)!r}, "a")
b = Instance({str(fmu)!r}, "b")
try:
    a.set("mu", -1.0)
except FMICallException:
    pass
print("A", sum("mu" in m for s, m in a.messages if s >= 2))
print("B", sum("mu" in m for s, m in b.messages if s >= 2))
a.close()
b.close()
del a, b
gc.collect()
try:
    fmpy.simulate_fmu({str(fmu)!r}, start_values={{"Rx": 5e-324, "Ry": 2.97e9, "Iy": 0.0}},
                      stop_time=1e-3, output_interval=1e-4)
except FMICallException:
    print("refused")
"""
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                       timeout=300, cwd=ROOT)  # fmt: skip
    assert r.returncode == 0, (r.returncode, r.stdout[-2000:], r.stderr[-2000:])
    lines = r.stdout.splitlines()
    assert "A 1" in lines and "B 0" in lines, lines
    assert "refused" in lines, lines
    assert any(line.startswith("[ERROR]") and "Rx" in line for line in lines), lines


# ---- one declaration of the wording (contact_fmu/fmu/messages.py) ------------------------
PACKAGE = ROOT / "contact_fmu"
NATIVE_SOURCES = sorted((PACKAGE / "native").glob("*.c"))  # the C core and its front ends
SHIM = PACKAGE / "fmu" / "pythonfmu_shim.c"  # the pythonfmu FMU's binary


def _string_pieces(path: Path) -> list[str]:
    """The literal text of every string and f-string of a Python module (an f-string's
    pieces between its fields; implicit concatenation joined, as the parser does)."""
    pieces = []
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Constant) and isinstance(node.value, str):
            pieces.append(node.value)
        elif isinstance(node, ast.JoinedStr):
            pieces += [v.value for v in node.values if isinstance(v, ast.Constant)]
    return pieces


def _literals(m: words.Message) -> list[str]:
    return [lit for lit, *_ in string.Formatter().parse(m.template) if lit.strip()]


def test_every_message_is_worded_once_and_used_by_both_targets_or_says_why_not():
    """Each message of fmu/messages.py is formatted by the native FMUs (CF_MSG_<NAME> in
    a C source of contact_fmu/native, or through a message composed of it) and by the
    pythonfmu FMU (the adapter's words.<NAME>; its status shim's CF_MSG_<NAME>; or the
    numerics module it names, whose own strings hold every literal piece of the
    template), unless it says why it has one target only: then the other does not use
    it. No C source or adapter module words a message of the table itself (a template's
    full text appears nowhere else)."""
    table = words.table()
    name_of = {id(m): n for n, m in table.items()}
    native_text = "\n".join(p.read_text() for p in NATIVE_SOURCES)
    shim_text = SHIM.read_text()
    fmu_text = "\n".join(
        p.read_text() for p in (PACKAGE / "fmu").glob("*.py") if p.name != "messages.py"
    )

    def composed_closure(used: set[str]) -> set[str]:
        """A composed message's parts reach a target through it."""
        for n in list(used):
            used |= {name_of[id(p)] for p in table[n].parts}
        return used

    native = composed_closure({n for n in table if re.search(rf"\bCF_MSG_{n}\b", native_text)})
    shim = composed_closure({n for n in table if re.search(rf"\bCF_MSG_{n}\b", shim_text)})

    def pythonfmu(n: str, m: words.Message) -> bool:
        if n in shim:
            return True
        if m.parts:
            return all(pythonfmu(name_of[id(p)], p) for p in m.parts)
        if m.home.endswith(".py"):  # a numerics module: its own strings hold the words
            pieces = _string_pieces(PACKAGE / m.home)
            return all(any(lit in piece for piece in pieces) for lit in _literals(m))
        return re.search(rf"\bwords\.{n}\b", fmu_text) is not None

    for n, m in table.items():
        py, c = pythonfmu(n, m), n in native
        if m.only is None:
            assert py and c, (n, py, c)
        elif m.home == words.NATIVE:
            assert c and not py, (n, py, c)
        else:
            assert py and not c, (n, py, c)
    # the wording lives in the table only: no full template elsewhere (a literal text of
    # a whole message, longer than a few words)
    for n, m in table.items():
        whole = max(_literals(m), key=len, default="")
        if len(whole) > 30 and not m.home.endswith(".py"):
            assert whole not in fmu_text, n
            assert whole.replace('"', '\\"') not in native_text + shim_text, n


def test_the_numerics_input_error_is_the_invalid_template():
    """_validate.InputError words a refused value as the table's INVALID does (the
    numerics import no FMU module: the same words, checked here): the requirement of a
    step's load limit (integrator) and of the body's inertia (dynamics) reach both
    targets in these words."""
    from contact_fmu._validate import InputError

    e = InputError("Fx_ex", -1.2e308, words.REQ_LOAD_FX(limit=1e9, cap=0.1 + 0.2))
    assert (
        str(e)
        == words.LOAD_LIMIT_FX(name="Fx_ex", value=-1.2e308, limit=1e9, cap=0.1 + 0.2)
        == "Fx_ex = -1.2e+308 is invalid: must be <= 1e+09 mu P = 0.3 N in magnitude"
    )
