"""An FMU state as bytes (fmi2SerializeFMUstate / fmi2DeSerializeFMUstate).

The bytes are a header naming the format and the FMU's package (``cfmu_<content
hash>`` in a built FMU: a state is only meaningful to the FMU that wrote it), then the
state pickled. They are read back by an unpickler that admits only what a state holds:
builtin containers and numbers (which need no lookup), numpy arrays and scalars, and
the FMU's own classes (its dataclasses, the contact law of a contact-mode state), so
bytes from elsewhere cannot name any other callable. Bytes that are not such a state
give ``Unreadable`` with the reason instead of an exception: pythonfmu turns any
exception into fmi2Fatal, and the adapter refuses the state with a message instead.
"""

from __future__ import annotations

import io
import pickle
from typing import Any, NamedTuple

from . import messages as words

MAGIC = b"contact_fmu FMU state 1\n"
# the first bytes of a state of the FMU's C core (native/instance.c's MAGIC: slave_core.py,
# slave_state.py)
CORE_MAGIC = b"cfmuSTAT"
# numpy's pickle entry points for arrays, dtypes and scalars (numpy 1.x and 2.x names)
_NUMPY = {
    (m, n)
    for m in ("numpy.core.multiarray", "numpy._core.multiarray")
    for n in ("_reconstruct", "scalar")
} | {
    ("numpy", "ndarray"),
    ("numpy", "dtype"),
    ("numpy.core.numeric", "_frombuffer"),
    ("numpy._core.numeric", "_frombuffer"),
}


class Unreadable(NamedTuple):
    """Bytes that are not a state of this FMU, and why."""

    reason: str


def dumps(state: Any, package: str) -> bytes:
    """The state as bytes for the FMU whose package is ``package``."""
    return MAGIC + package.encode() + b"\n" + pickle.dumps(state, protocol=5)


def loads(data: bytes, package: str) -> Any:
    """The state written by ``dumps`` for ``package``, or Unreadable."""
    if not data.startswith(MAGIC):
        return Unreadable(words.NOT_SERIALIZED())
    owner, _, body = data[len(MAGIC) :].partition(b"\n")
    if owner != package.encode():
        name = owner.decode(errors="replace")
        return Unreadable(words.STATE_OWNER(owner=name, package=package))
    try:
        return _Restricted(io.BytesIO(body), package).load()
    except Exception as e:  # truncated or altered bytes: any unpickling error
        return Unreadable(words.STATE_UNREADABLE(why=f"{type(e).__name__}: {e}"))


class _Restricted(pickle.Unpickler):
    def __init__(self, f: io.BytesIO, package: str) -> None:
        super().__init__(f)
        self._package = package

    def find_class(self, module: str, name: str) -> Any:
        own = module == self._package or module.startswith(self._package + ".")
        if own or (module, name) in _NUMPY:
            return super().find_class(module, name)
        raise pickle.UnpicklingError(f"{module}.{name} is not part of an FMU state")
