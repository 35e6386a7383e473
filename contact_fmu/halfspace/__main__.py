"""python -m contact_fmu.halfspace build-table SPEC.json OUT.npz

Build the creep-force table of a half-space law declaration (``spec.TableSpec`` as
JSON, e.g. a scene's ``[halfspace]`` table) and write it to OUT.npz. The FMU build runs
this in a process of its own with single-threaded BLAS (threaded BLAS slows the
solver's GMRES down tenfold on a shared machine; docs/performance.md).
"""

from __future__ import annotations

import argparse
import json
import sys
import time

from .spec import build_file


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m contact_fmu.halfspace", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)  # fmt: skip
    sub = ap.add_subparsers(dest="command", required=True)
    b = sub.add_parser("build-table", help="build a creep-force table from a JSON spec")
    b.add_argument("spec", help="JSON file with the declaration (TableSpec.to_dict)")
    b.add_argument("out", help="output file (.npz)")
    args = ap.parse_args(argv)
    with open(args.spec) as f:
        spec = json.load(f)
    t0 = time.perf_counter()
    path = build_file(spec, args.out)
    print(f"{path} ({time.perf_counter() - t0:.1f} s)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
