"""Regenerate the figures: python -m contact_fmu.figures [module ...] [--out DIR]."""

from __future__ import annotations

import argparse
import importlib
import pkgutil
from pathlib import Path

import matplotlib

import contact_fmu.figures as pkg

DEFAULT_OUT = Path(__file__).resolve().parents[2] / "docs" / "figures"


def main(argv: list[str] | None = None) -> None:
    matplotlib.use("Agg")
    names = sorted(m.name for m in pkgutil.iter_modules(pkg.__path__) if not m.name.startswith("_"))
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("modules", nargs="*", choices=[[], *names], help="figure modules to run")
    ap.add_argument("--out", type=Path, default=DEFAULT_OUT)
    args = ap.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    for name in args.modules or names:
        mod = importlib.import_module(f"contact_fmu.figures.{name}")
        for path in mod.make_figures(args.out):
            print(path)


if __name__ == "__main__":
    main()
