"""Command line: ``contact-fmu <command>``.

contact-fmu run scenarios/fig13.toml     build the scene's FMU (cached), simulate it
                                         with fmpy, write CSV and PNG, compare with
                                         the references; exit 1 on a mismatch
contact-fmu run --all                    every scene of scenarios/
contact-fmu run --native scenarios/x.toml  the same through the native FMU (C only;
                                         a scene it does not cover is an error);
                                         --fmi3: its FMI 3.0 build
contact-fmu references scenarios/x.toml  a scene's references from their independent
                                         source (no FMU involved), under
                                         out/references/; --overwrite rewrites the
                                         stored ones (maintainers)
contact-fmu system scenarios/fig13.toml --case "eta = 3" --set My_ex=-0.95 [--native]
                                         the scene's body as a contact-mode and a
                                         rigid_body-mode FMU coupled: SSP 1.0 file and
                                         libcosim's OspSystemStructure.xml (out/system/)
contact-fmu report [--quick] [--stiff | --workprecision]
                                         error against run time of every scene's FMU
                                         (reports/workprecision/), and the stiff and
                                         extreme cases with pass/fail (reports/stiff.md)
contact-fmu sweep SCENE.toml --vary NAME=VALUES [--vary ...]
      [--workers N | --scheduler tcp://host:8786] --out DIR
                                         every combination of the values times every
                                         case as Dask tasks: DIR/results.parquet (one
                                         row per run) and a plot of a metric
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

DEFAULT_SCENES = Path("scenarios")
DEFAULT_OUT = Path("out")


def _scene_paths(args: argparse.Namespace) -> list[Path]:
    from .scenario import discover

    paths = list(args.scenes)
    if args.all:
        paths += discover(args.scenarios)
    if not paths:
        raise SystemExit("no scene given (a TOML file, or --all)")
    return paths


def _load_warning_once(path: Path):
    """The scene of ``path``; its plausibility warnings printed once each, one line on
    stderr (other warnings shown as Python shows them)."""
    import warnings

    from .scenario import load
    from .scenario.plausibility import PlausibilityWarning

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", PlausibilityWarning)
        scene = load(path)
    shown = set()
    for w in caught:
        if issubclass(w.category, PlausibilityWarning):
            if str(w.message) not in shown:
                print(f"warning: {w.message}", file=sys.stderr)
                shown.add(str(w.message))
        else:
            warnings.showwarning(w.message, w.category, w.filename, w.lineno)
    return scene


def run_scene(
    path: Path,
    out: Path,
    rebuild: bool = False,
    make_plot: bool = True,
    native: bool = False,
    fmi3: bool = False,
) -> bool:
    """Build, simulate, write and compare one scene; True when it matches its references.
    ``native``: through the native FMU (fmu_build.native_fmu); ``fmi3``: its FMI 3.0
    build (fmu_build.native_fmu3)."""
    import fmu_build
    from fmu_build import native_fmu, native_fmu3

    from .scenario import runner

    scene = _load_warning_once(path)
    t0 = time.perf_counter()
    if fmi3:
        built = native_fmu3.build(scene.config, out / "fmu", force=rebuild)
    elif native:
        built = native_fmu.build(scene.config, out / "fmu", force=rebuild)
    else:
        built = fmu_build.build(scene.config, out / "fmu", force=rebuild)
    t_build = time.perf_counter() - t0
    n_vars = len(scene.config.variables)
    size = built.path.stat().st_size
    print(f"{scene.name}: {scene.title}")
    state = "cached" if built.cached else f"built in {t_build:.1f} s"
    print(f"  FMU  {built.stable} ({state}; {n_vars} variables, {size / 1024:.0f} KiB)")
    t0 = time.perf_counter()
    field_dir = out / "scenes" / scene.name / "fields"  # the FMU's field files, if any
    results = runner.simulate(built.path, scene, field_dir=field_dir)
    wall = time.perf_counter() - t0
    print(
        f"  ran  {len(results)} case(s) x {scene.n_steps} steps of {scene.step:g} s in {wall:.2f} s"
    )
    for r in results:
        if r.error:
            print(f"  case {r.case}: FAILED: {r.error}")
            continue
        last = ", ".join(f"{n} = {r.columns[n][-1]:.6g}" for n in scene.outputs[:4])
        print(f"  case {r.case}: at t = {r.columns['time'][-1]:.6g} s: {last}")
    checks = runner.compare(scene, results)
    for c in checks:
        status = "ok" if c.ok else "MISMATCH"
        print(
            f"  ref  {c.reference}: {c.variable:8s} {c.case:16s} max|err| = "
            f"{c.max_error:.3g} (tol {c.tolerance:.3g}, {c.points} points) {status}"
        )
    scene_dir = out / "scenes" / scene.name
    runner.write_csv(scene_dir / f"{scene.name}.csv", scene, results)
    print(f"  CSV  {scene_dir / (scene.name + '.csv')}")
    if scene.field is not None:  # written by the FMU during the run (phase "transient")
        for c in scene.cases:
            print(f"  field {scene.field.path(field_dir, c.name)}")
    if make_plot:
        from .scenario.plot import plot

        print(f"  PNG  {plot(scene, results, scene_dir / (scene.name + '.png'))}")
    ok = all(not r.error for r in results) and all(c.ok for c in checks)
    if not scene.references:  # a run without a comparison is no pass
        print("  no references: nothing compared")
        if not ok:
            print("  FAIL")
        return ok
    print(f"  {'PASS' if ok else 'FAIL'}")
    return ok


def _run(args: argparse.Namespace) -> int:
    from .scenario import ScenarioError

    failed = []
    for path in _scene_paths(args):
        try:
            ok = run_scene(
                path,
                args.out,
                args.rebuild,
                make_plot=not args.no_plot,
                native=args.native or args.fmi3,
                fmi3=args.fmi3,
            )
        except (ScenarioError, OSError, RuntimeError, ValueError) as e:
            where = "" if str(path) in str(e) else f"{path}: "  # a scene's errors name it
            print(f"ERROR: {where}{e}", file=sys.stderr)
            ok = False
        if not ok:
            failed.append(str(path))
    if failed:
        print(f"{len(failed)} scene(s) failed: {', '.join(failed)}", file=sys.stderr)
        return 1
    return 0


def _references(args: argparse.Namespace) -> int:
    from .scenario import load
    from .scenario.references import discretisation_error, regenerate

    for path in _scene_paths(args):
        scene = load(path)
        if args.estimate:
            for ref in scene.references:
                if ref.source in ("simulate", "traction"):
                    est = discretisation_error(scene, ref)
                    print(
                        f"{ref.file.name}: discretisation error estimate "
                        + ", ".join(
                            f"{k} {v:.3g} (tol {ref.tolerance[k]:.3g})" for k, v in est.items()
                        )
                    )
            continue
        where = None if args.overwrite else args.out / "references" / scene.name
        for written in regenerate(scene, where):
            print(written)
        if where is not None:
            print(f"  (written under {where}; --overwrite rewrites the scene's own files)")
    return 0


def _system(args: argparse.Namespace) -> int:
    from fmu_build import system

    from ._validate import InputError
    from .scenario import ScenarioError, load

    overrides = {}
    for item in args.set:
        name, _, value = item.partition("=")
        try:
            overrides[name.strip()] = float(value)
        except ValueError:
            raise SystemExit(f"--set {item!r} is invalid: must be NAME=NUMBER") from None
    try:
        scene = load(args.scene)
        names = [c.name for c in scene.cases]
        if args.case is not None and args.case not in names:
            raise InputError("--case", args.case, f"one of {names}")
        case = scene.case(args.case) if args.case else scene.cases[0]
        folder = args.out / (scene.name + ("_native" if args.native else ""))
        made = system.write(
            scene, case, folder, args.step, overrides, args.fmu_out, native=args.native
        )
    except (ScenarioError, InputError, OSError, RuntimeError, ValueError) as e:
        where = "" if str(args.scene) in str(e) else f"{args.scene}: "  # a scene's errors name it
        print(f"ERROR: {where}{e}", file=sys.stderr)
        return 1
    kind = "native " if args.native else ""
    print(f"{scene.name}, case {case.name!r}: {kind}contact-mode and rigid_body-mode FMUs coupled")
    print(
        f"  step {made.step:g} s (slip relaxation time tau = {made.tau:.3g} s; explicit "
        f"coupling needs step < tau), stop time {made.stop_time:g} s"
    )
    for path in (*made.fmus.values(), made.ssp, made.osp):
        print(f"  wrote {path}")
    print("  libcosim takes the step from either file (from_ssp_file, from_osp_config_file);")
    print(
        "  fmpy reads no step or stop time from the .ssp: "
        f"simulate_ssp('{made.ssp}', stop_time={made.stop_time!r}, step_size={made.step!r})"
    )
    return 0


def _report(args: argparse.Namespace) -> int:
    from . import InputError
    from .report import command
    from .study.engine import Engine

    if args.write_docs and (args.quick or args.scenes or args.case):
        raise SystemExit("--write-docs needs the full report (no --quick, scenes or --case)")
    if args.write_docs and (args.workers or args.scheduler):
        raise SystemExit("--write-docs needs the times of runs one at a time (no --workers)")
    if args.repeats < 1:
        raise SystemExit(f"--repeats = {args.repeats} is invalid: must be >= 1")
    if not args.budget > 0:
        raise SystemExit(f"--budget = {args.budget} is invalid: must be > 0 (seconds)")
    both = not (args.stiff or args.workprecision)
    reports = results = None
    fmu_dir = args.fmu_out
    try:
        engine = Engine(None if args.scheduler else args.workers, args.scheduler)
        engine.__enter__()  # connected here: a wrong --scheduler is one line, not a traceback
    except InputError as e:
        raise SystemExit(f"contact-fmu report: {e}") from None
    with engine:
        if args.workprecision or both:
            paths = command.scene_paths(args.scenes, args.scenarios)
            reports = command.workprecision(
                paths,
                args.out,
                fmu_dir,
                args.quick,
                args.repeats,
                args.held,
                budget=args.budget,
                engine=engine,
            )
        if args.stiff or both:
            try:
                results = command.stiff_suite(
                    args.out, fmu_dir, args.quick, args.case, engine=engine
                )
            except ValueError as e:
                raise SystemExit(str(e)) from e
    if args.write_docs:
        cmd = "contact-fmu report" + (" --stiff" if args.stiff else "")
        cmd += " --workprecision" if args.workprecision else ""
        command.write_docs(reports, results, args.out, cmd + " --write-docs")
    failed = [r.case.name for r in results or [] if not r.ok]
    if failed:
        print(f"stiff cases failed: {', '.join(failed)}", file=sys.stderr)
        return 1
    return 0


def _vary(text: str):
    """--vary NAME=VALUES: a list "0.1,0.2" or a range "start:stop:n"."""
    from . import InputError
    from .scenario.schema import Vary, sweep_values

    name, sep, values = text.partition("=")
    if not sep or not name.strip():
        raise argparse.ArgumentTypeError(f"--vary {text!r}: expected NAME=VALUES")
    try:
        return Vary(name.strip(), sweep_values(f"--vary {name.strip()}", values))
    except InputError as e:
        raise argparse.ArgumentTypeError(str(e)) from None


def _sweep(args: argparse.Namespace) -> int:
    from . import InputError
    from .scenario import ScenarioError, load, variation
    from .study import metrics, sweep, tables
    from .study.engine import Engine
    from .study.plot import plot

    try:
        scene = load(args.scene)
        vary = sweep.merge_vary(scene, args.vary)
        if not vary:
            raise ScenarioError(
                f"{args.scene}: nothing varied (--vary NAME=VALUES or [sweep].vary)"
            )
        variation.check(scene, [v.name for v in vary])
        engine = Engine(args.workers, args.scheduler, progress=not args.no_progress)
        engine.__enter__()  # connected here: a wrong --scheduler is one line, not a traceback
    except (ScenarioError, InputError) as e:
        raise SystemExit(f"contact-fmu sweep: {e}") from None
    out = args.out or DEFAULT_OUT / "sweeps" / scene.name
    n_runs = len(sweep.runs(scene, vary))
    print(f"{scene.name}: {n_runs} runs ({' x '.join(str(len(v.values)) for v in vary)} "
          f"values x {len(scene.cases)} case(s))")  # fmt: skip
    t0 = time.perf_counter()
    with engine:
        print(f"  on {engine.describe()}")
        table = tables.ensure(scene.config, engine)
        if table is not None:
            print(f"  creep-force table {table}")
        rows = sweep.sweep(
            scene, vary, engine, args.fmu_out, trajectories=args.trajectories or None
        )
    wall = time.perf_counter() - t0
    ms = scene.sweep.metrics or metrics.defaults(scene.outputs)
    files = sweep.write(rows, vary, out, [m.name for m in ms])
    failed = [r for r in rows if r["status"] != "ok"]
    print(f"  {len(rows) - len(failed)} ok, {len(failed)} failed, in {wall:.1f} s")
    for r in failed[:5]:
        print(f"    run {r['run']} ({r['case']}): {r['status']}")
    for f in files:
        print(f"  {f}")
    spec = dict(scene.sweep.plot)
    metric = args.plot or spec.get("metric") or ms[0].name
    if metric not in {m.name for m in ms}:
        raise SystemExit(f"contact-fmu sweep: --plot {metric!r} is not a metric")
    names = [v.name for v in vary]
    x = spec.get("x") if spec.get("x") in names else names[0]
    y = spec.get("y") if spec.get("y") in names else next((n for n in names if n != x), None)
    png = plot(sweep.strip(rows), names, metric, x, y, out / f"{metric}.png", scene.title, ms)
    print(f"  PNG {png}")
    return 0


def parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(
        prog="contact-fmu",
        description=__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    sub = ap.add_subparsers(dest="command", required=True)

    def scenes_args(p: argparse.ArgumentParser) -> None:
        p.add_argument("scenes", nargs="*", type=Path, help="scene files (TOML)")
        p.add_argument("--all", action="store_true", help="every scene of --scenarios")
        p.add_argument("--scenarios", type=Path, default=DEFAULT_SCENES)

    run = sub.add_parser("run", help="build and run scenes, compare with references")
    scenes_args(run)
    run.add_argument("--out", type=Path, default=DEFAULT_OUT, help="output folder (out/)")
    run.add_argument("--rebuild", action="store_true", help="ignore the FMU cache")
    run.add_argument("--no-plot", action="store_true", help="skip the PNG")
    run.add_argument("--native", action="store_true", help="through the native FMU (C only)")
    run.add_argument(
        "--fmi3", action="store_true", help="through the native FMU's FMI 3.0 build (C only)"
    )
    run.set_defaults(func=_run)

    refs = sub.add_parser(
        "references", help="a scene's references from their source (--overwrite: the stored)"
    )
    scenes_args(refs)
    refs.add_argument(
        "--estimate",
        action="store_true",
        help="print the Richardson error estimates that justify the "
        "tolerances ('simulate', 'traction') instead of writing",
    )
    refs.add_argument(
        "--out", type=Path, default=DEFAULT_OUT, help="written under OUT/references/<scene>/"
    )
    refs.add_argument(
        "--overwrite",
        action="store_true",
        help="rewrite the scene's stored reference files (tracked; for maintainers)",
    )
    refs.set_defaults(func=_references)

    sys_ = sub.add_parser(
        "system", help="a scene's contact and rigid-body FMUs coupled: SSP and OSP files"
    )
    sys_.add_argument("scene", type=Path, help="a planar body-mode scene (TOML)")
    sys_.add_argument("--case", help="the case whose parameters are used (default: first)")
    sys_.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="NAME=VALUE",
        help="a parameter or held input value (SI); needed for inputs that vary in time",
    )
    sys_.add_argument(
        "--step", type=float, help="communication step (s; default: the power of ten <= tau/5)"
    )
    sys_.add_argument(
        "--native", action="store_true", help="the native (C) contact and rigid_body FMUs"
    )
    sys_.add_argument("--out", type=Path, default=DEFAULT_OUT / "system", help="out/system")
    sys_.add_argument("--fmu-out", type=Path, default=DEFAULT_OUT / "fmu", help="FMU cache")
    sys_.set_defaults(func=_system)

    rep = sub.add_parser(
        "report", help="error against run time per scene, and the stiff and extreme cases"
    )
    rep.add_argument("scenes", nargs="*", type=Path, help="scene files (default: all)")
    rep.add_argument("--scenarios", type=Path, default=DEFAULT_SCENES)
    rep.add_argument("--out", type=Path, default=Path("reports"), help="output folder (reports/)")
    rep.add_argument("--fmu-out", type=Path, default=DEFAULT_OUT / "fmu", help="FMU cache")
    rep.add_argument("--quick", action="store_true", help="two steps, one case, short sweep")
    rep.add_argument("--stiff", action="store_true", help="only the stiff and extreme cases")
    rep.add_argument("--workprecision", action="store_true", help="only the error/time sweep")
    rep.add_argument("--case", action="append", default=[], help="stiff case or group (repeat)")
    rep.add_argument("--repeats", type=int, default=2, help="timed runs per point (fastest)")
    rep.add_argument(
        "--budget", type=float, default=12.0, help="seconds per point; finer ones are skipped"
    )
    rep.add_argument(
        "--held", action="store_true", help="also the error against held inputs (slower)"
    )
    rep.add_argument(
        "--write-docs", action="store_true", help="update docs/accuracy.md, docs/performance.md"
    )
    rep_where = rep.add_mutually_exclusive_group()
    rep_where.add_argument(
        "--workers", type=int, default=0, help="the work-precision families and the stiff "
        "cases on a LocalCluster of N worker processes (default 0: in this process; times "
        "are then measured with N runs at once)"
    )  # fmt: skip
    rep_where.add_argument("--scheduler", help="... or on a running Dask scheduler (tcp://...)")
    rep.set_defaults(func=_report)

    sw = sub.add_parser(
        "sweep", help="a parameter study of a scene on Dask: results.parquet and a plot"
    )
    sw.add_argument("scene", type=Path, help="scene file (TOML); its [sweep] is the default")
    sw.add_argument(
        "--vary",
        type=_vary,
        action="append",
        default=[],
        metavar="NAME=VALUES",
        help="a parameter, an input (held at the value) or INPUT.piece.field; VALUES a "
        "list 0.1,0.2,0.3 or a range start:stop:n (repeat; replaces the scene's [sweep] "
        "values of that name, or adds it)",
    )
    where = sw.add_mutually_exclusive_group()
    where.add_argument(
        "--workers", type=int, help="worker processes of a LocalCluster (default: one per "
        "CPU; 0: serial, in this process)"
    )  # fmt: skip
    where.add_argument("--scheduler", help="address of a running Dask scheduler (tcp://...)")
    sw.add_argument("--out", type=Path, help="output folder (default out/sweeps/<scene>)")
    sw.add_argument("--fmu-out", type=Path, default=DEFAULT_OUT / "fmu", help="FMU cache")
    sw.add_argument("--trajectories", action="store_true", help="also trajectories.parquet")
    sw.add_argument("--plot", metavar="METRIC", help="the metric plotted (default: the scene's)")
    sw.add_argument("--no-progress", action="store_true", help="no progress bar")
    sw.set_defaults(func=_sweep)
    return ap


def main(argv: list[str] | None = None) -> int:
    args = parser().parse_args(argv)
    return args.func(args)


def entry() -> None:
    """The console script: main, then the end of the process without the interpreter's
    finalisation. pythonfmu's native wrapper can corrupt the heap when its libraries
    are torn down at exit (its use-after-free in finalizePythonInterpreter, reported at
    https://github.com/NTNU-IHB/PythonFMU/issues/228; tests/conftest.py does the
    same for the test session): the results are written by then, and the status must
    be main's, not a crash's."""
    try:
        status = main()
    except SystemExit as e:  # argparse's --help and usage errors: as sys.exit would
        if e.code is None or isinstance(e.code, int):
            status = e.code or 0
        else:
            print(e.code, file=sys.stderr)
            status = 1
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(status)


if __name__ == "__main__":
    entry()
