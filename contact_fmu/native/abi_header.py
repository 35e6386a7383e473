"""Writes or checks cf_abi.h from the declarations of abi.py.

``python -m contact_fmu.native.abi_header --write`` after a change to a shared struct or
to the Python value of a shared constant; ``--check`` exits 1 where the committed header
is stale; no option prints it. (A module of its own: the package imports abi.py, and
``python -m`` on a module its package has imported runs it twice.)
"""

from __future__ import annotations

import argparse
import sys

from .abi import COMMAND, HEADER, header


def main(argv: list[str] | None = None) -> int:
    """``--write``: write cf_abi.h; ``--check``: 1 where the committed file differs."""
    ap = argparse.ArgumentParser(prog="python -m contact_fmu.native.abi_header")
    ap.add_argument("--write", action="store_true", help=f"write {HEADER.name}")
    ap.add_argument("--check", action="store_true", help=f"fail if {HEADER.name} is stale")
    args = ap.parse_args(argv)
    text = header()
    if args.write:
        HEADER.write_text(text)
        print(HEADER)
        return 0
    if args.check:
        stale = not HEADER.is_file() or HEADER.read_text() != text
        if stale:
            print(f"{HEADER} is stale: run {COMMAND}", file=sys.stderr)
        return int(stale)
    sys.stdout.write(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
