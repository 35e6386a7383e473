"""Writes or checks cf_abi.h from the declarations of abi.py, and cf_messages.h from the
messages of fmu/messages.py (message_header.py).

``python -m contact_fmu.native.abi_header --write`` after a change to a shared struct or
to the Python value of a shared constant; ``--check`` exits 1 where the committed header
is stale; no option prints it. (A module of its own: the package imports abi.py, and
``python -m`` on a module its package has imported runs it twice.)
"""

from __future__ import annotations

import argparse
import sys

from . import message_header
from .abi import COMMAND, HEADER, header

# each generated header and its generator: the shared structs and constants (abi.py),
# the messages' constants (message_header.py, from fmu/messages.py)
GENERATED = ((HEADER, header), (message_header.HEADER, message_header.header))


def main(argv: list[str] | None = None) -> int:
    """``--write``: write cf_abi.h and cf_messages.h; ``--check``: 1 where a committed
    file differs."""
    names = " and ".join(path.name for path, _ in GENERATED)
    ap = argparse.ArgumentParser(prog="python -m contact_fmu.native.abi_header")
    ap.add_argument("--write", action="store_true", help=f"write {names}")
    ap.add_argument("--check", action="store_true", help=f"fail if {names} are stale")
    args = ap.parse_args(argv)
    stale = 0
    for path, generate in GENERATED:
        text = generate()
        if args.write:
            path.write_text(text)
            print(path)
        elif args.check:
            if not path.is_file() or path.read_text() != text:
                print(f"{path} is stale: run {COMMAND}", file=sys.stderr)
                stale = 1
        else:
            sys.stdout.write(text)
    return stale


if __name__ == "__main__":
    sys.exit(main())
