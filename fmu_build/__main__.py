"""python -m fmu_build: build the FMUs of scenes, or the full FMU of a mode.

python -m fmu_build scenarios/fig13.toml        the scene's FMU (only what it uses)
python -m fmu_build --all                       every scene of scenarios/
python -m fmu_build --full body                 every variable of a mode (body,
                                                contact, rigid_body, or all)
python -m fmu_build --native scenarios/fig13.toml  the native FMU (C only, no Python on
                                                the target; fmu_build/native_fmu.py)
python -m fmu_build --native --fmi3 scenarios/fig13.toml  the native FMU as FMI 3.0
                                                (<name>_native3.fmu; fmu_build/native_fmu3.py)

The last line of the output is the path of the (last) FMU.
"""

from __future__ import annotations

import argparse
import subprocess
import sys
from pathlib import Path

from contact_fmu.fmu.config import MODEL_MODULES, ModelConfig
from contact_fmu.scenario import ScenarioError, discover, load

from . import DEFAULT_OUT, BuildError, build


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(
        prog="python -m fmu_build",
        description=__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    ap.add_argument("scenes", nargs="*", type=Path, help="scene files (TOML)")
    ap.add_argument("--all", action="store_true", help="every scene of --scenarios")
    ap.add_argument("--scenarios", type=Path, default=Path("scenarios"))
    ap.add_argument(
        "--full",
        action="append",
        default=[],
        choices=[*MODEL_MODULES, "all"],
        help="the full FMU of a mode",
    )
    ap.add_argument("--out", type=Path, default=DEFAULT_OUT, help="output folder (out/fmu)")
    ap.add_argument("--force", action="store_true", help="rebuild even if cached")
    ap.add_argument(
        "--native", action="store_true", help="the native FMU (compiled C only, no Python)"
    )
    ap.add_argument(
        "--fmi3", action="store_true", help="with --native: an FMI 3.0 FMU (<name>_native3.fmu)"
    )
    args = ap.parse_args(argv)

    configs = []
    try:
        for path in [*args.scenes, *(discover(args.scenarios) if args.all else [])]:
            configs.append(load(path).config)
    except ScenarioError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    for mode in args.full:
        modes = list(MODEL_MODULES) if mode == "all" else [mode]
        configs += [ModelConfig.full(m) for m in modes]
    if not configs:
        ap.error("nothing to build: give scene files, --all or --full MODE")
    if args.fmi3 and not args.native:
        ap.error("--fmi3 is for the native FMU: give --native --fmi3")
    if args.native:
        return _native(configs, args)
    for cfg in configs:
        try:
            built = build(cfg, args.out, force=args.force)
        except BuildError as e:
            print(f"error: {e}", file=sys.stderr)
            return 1
        state = "cached" if built.cached else "built"
        print(
            f"{built.stable}  ({state}; {len(cfg.variables)} variables; "
            f"modelIdentifier {built.identifier}; cache {built.path.name})"
        )
    return 0


def _native(configs: list, args: argparse.Namespace) -> int:
    from . import native_fmu, native_fmu3

    builder = native_fmu3.build if args.fmi3 else native_fmu.build
    paths = []
    for cfg in configs:
        try:
            built = builder(cfg, args.out, force=args.force)
        except native_fmu.NativeUnsupportedError as e:
            print(f"error: {e}", file=sys.stderr)
            return 1
        except subprocess.CalledProcessError as e:
            print(f"error: compiling the native FMU of {cfg.name}:\n{e.stderr}", file=sys.stderr)
            return 1
        state = "cached" if built.cached else "built"
        n = len(cfg.variables)
        kind = "native FMI 3.0 FMU" if args.fmi3 else "native FMU"
        print(f"{cfg.name}: {kind} ({state}; {n} variables; {built.identifier})")
        paths.append(built.stable)
    print(paths[-1])
    return 0


if __name__ == "__main__":
    sys.exit(main())
