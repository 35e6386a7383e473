"""The cost of a step through both front ends of the C core, this tree against a revision.

    .venv/bin/python benchmarks/bench_front_ends.py [--base REV] [--steps N] [--repeats R]
        [--callgrind [--write]]

The checks of a call and the step are C code that both FMUs share (contact_fmu/native:
cf_core.h, stepper.c's cf_body_check). This measures what a change to them costs, in one
run, interleaved, so that the ratios are fair on a shared machine: the tree at REV
(default HEAD; exported with git archive into a temporary folder) and this working tree,
each in processes of its own (PYTHONPATH set to it):

1. the pythonfmu FMU's per-step FMI calls on their C path (native/fmi.c): a ContactSlave
   of the Fig. 13 scene, each method, called as pythonfmu calls it (set_real of the
   loads, do_step, get_real of the outputs), N times; the fastest of 7 passes;
2. the native Fig. 13 FMU, each method, from the C importer (tests/native_importer.c):
   N communication steps of the case eta = 3 repeated from its start state, the fastest
   of its 3 passes (bench_native.py's importer run); the FMI 3.0 native FMU likewise from
   tests/native_importer3.c, where the tree builds one, against REV's FMI 2.0 FMU.

Each figure is the best of R processes; the ratio is this tree's over REV's. With
--callgrind the native FMUs' steps are also counted in machine instructions (valgrind's
callgrind: the importer's bench run of 2000 and of 12000 steps, the difference over the
30000 steps between them; the same for the same binary and inputs, whatever else runs).
``--write`` (with --callgrind) replaces the block BLOCK of docs/performance.md: the
instructions per step of each FMU.
"""

from __future__ import annotations

import os
import platform
import subprocess
import sys
import tempfile
from pathlib import Path

import fmpy

from fmu_build import c_importer

if __package__:  # python -m benchmarks
    from . import harness
else:  # run as a script: benchmarks/ is first on sys.path
    import harness  # type: ignore[no-redef]

DOC = harness.PERFORMANCE
BLOCK = "bench_front_ends.py"  # the marker block it writes (with --callgrind)

ROOT = harness.ROOT
METHODS = ("quasistationary", "full")

# run in a tree's own process: seconds per step of the adapter's C path
SLAVE = """
import ctypes, sys, time
from contact_fmu.fmu.config import ModelConfig
from contact_fmu.fmu.slave import CELL_VR, ContactSlave
from contact_fmu.scenario import load

n, method = int(sys.argv[1]), sys.argv[2]
scene = load("scenarios/fig13.toml")
cfg = ModelConfig.from_dict(scene.config.to_dict() | {"methods": [method]})
s = type("Model", (ContactSlave,), {"CONFIG": cfg.to_dict()})(instance_name="bench")
cell = ctypes.c_int(0)
s.set_string([CELL_VR], [f"status cell {hex(ctypes.addressof(cell))}"])
vr = {v.name: k for k, v in s.vars.items()}
s.setup_experiment(0.0)
s.enter_initialization_mode()
s.exit_initialization_mode()
assert s._fast_fmi is not None, "no fmi.c binding"
loads, values = [vr["Fx_ex"], vr["My_ex"]], [17.0, -0.001]
outs = [vr[o] for o in cfg.outputs if o != "regime"]
t, h, best = 0.0, scene.step, float("inf")
for _ in range(7):
    t0 = time.perf_counter()
    for _ in range(n):
        s.set_real(loads, values)
        assert s.do_step(t, h)
        s.get_real(outs)
        t += h
    best = min(best, (time.perf_counter() - t0) / n)
print(best)
"""

# run in a tree's own process: the native Fig. 13 FMUs of each method into argv[1], FMI 2.0
# and, where the tree builds it, FMI 3.0
BUILD = """
import sys
from pathlib import Path
from contact_fmu.fmu.config import ModelConfig
from contact_fmu.scenario import load
from fmu_build import native_fmu
native_fmu3 = None
if Path("fmu_build/native_fmu3.py").exists():  # the tree's own, not the installed one's
    from fmu_build import native_fmu3

scene = load("scenarios/fig13.toml")
for m in sys.argv[2:]:
    cfg = ModelConfig.from_dict(scene.config.to_dict() | {"methods": [m]})
    print("FMU 2", m, native_fmu.build(cfg, sys.argv[1]).path)
    if native_fmu3 is not None:
        print("FMU 3", m, native_fmu3.build(cfg, sys.argv[1]).path)
"""


def _run(tree: Path, *args: str) -> str:
    env = {**os.environ, "PYTHONPATH": str(tree)}
    cmd = [sys.executable, *args]
    return subprocess.run(cmd, cwd=tree, env=env, capture_output=True, text=True, check=True).stdout


def _importer_runs(trees: dict[str, Path], work: Path, n: int) -> dict[tuple, list]:
    """The C importers' command lines (FMI 2.0, FMI 3.0) for each tree's native FMUs of
    each method: (tree, method, version) -> argv."""
    from contact_fmu.scenario import load

    scene = load(ROOT / "scenarios" / "fig13.toml")
    case = scene.case("eta = 3")
    exe = {"2": harness.compile_importer(work), "3": harness.compile_importer(work, fmi3=True)}
    runs = {}
    for label, tree in trees.items():
        built = _run(tree, "-c", BUILD, str(work / label), *METHODS).splitlines()
        for _, v, m, path in (line.split(maxsplit=3) for line in built if line[:4] == "FMU "):
            unzip = work / f"{label}-{m}-{v}"
            fmpy.extract(path, str(unzip))
            md = fmpy.read_model_description(str(unzip))
            spec_file = unzip / "spec.txt"
            spec_file.write_text(c_importer.spec(md, scene, case))
            ident = md.coSimulation.modelIdentifier
            folder = f"{platform.machine()}-linux" if v == "3" else "linux64"
            lib = str(unzip / "binaries" / folder / f"{ident}.so")
            head = [str(exe[v]), lib, md.guid] + ([ident] if v == "2" else [])
            runs[label, m, v] = [*head, "bench", str(spec_file), str(n)]
    return runs


def instructions_per_step(
    argv: list[str], work: Path, short: int = 2000, long: int = 12000
) -> float:
    """Instructions of one step (setReal, doStep, getReal) of the importer's bench run
    ``argv`` (its last argument the step count), under callgrind: the bench runs 3 passes,
    so ``long`` steps less ``short`` steps is 3 (long - short) steps with the start-up
    cancelled (by default 30000)."""
    counts = []
    for n in (short, long):
        out = subprocess.run(
            ["valgrind", "--tool=callgrind", f"--callgrind-out-file={work / 'cg.out'}",
             *argv[:-1], str(n)], capture_output=True, text=True, check=True,
        ).stderr  # fmt: skip
        counts.append(int(out.split("Collected : ")[1].split()[0]))
    return (counts[1] - counts[0]) / (3 * (long - short))


def main(argv: list[str] | None = None) -> int:
    ap = harness.parser(__doc__, "docs/performance.md")
    ap.add_argument("--base", default="HEAD", help="the revision to compare with")
    ap.add_argument("--steps", type=int, default=3000, help="steps of the adapter's C path")
    ap.add_argument("--importer-steps", type=int, default=20_000)
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--callgrind", action="store_true", help="count instructions per step")
    args = ap.parse_args(argv)
    if args.write and not args.callgrind:
        ap.error("--write needs --callgrind: the block gives instructions per step")
    counts: dict[tuple[str, str], dict[str, float]] = {}
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        base = work / "base"
        base.mkdir()
        archive = subprocess.run(["git", "archive", args.base], cwd=ROOT, capture_output=True,
                                 check=True).stdout  # fmt: skip
        subprocess.run(["tar", "-x", "-C", str(base)], input=archive, check=True)
        trees = {args.base: base, "this tree": ROOT}
        print(f"{args.base} against this tree; best of {args.repeats} interleaved processes")
        for m in METHODS:
            cost = {k: [] for k in trees}
            for _ in range(args.repeats):
                for k, tree in trees.items():
                    cost[k].append(float(_run(tree, "-c", SLAVE, str(args.steps), m)))
            b, a = min(cost[args.base]), min(cost["this tree"])
            print(f"pythonfmu adapter on fmi.c, fig13 {m}: {b * 1e6:.3f} -> {a * 1e6:.3f} "
                  f"us per step (setReal, doStep, getReal), ratio {a / b:.3f}")  # fmt: skip
        runs = _importer_runs(trees, work, args.importer_steps)
        for m in METHODS:
            keys = [k for k in runs if k[1] == m]
            rate = {k: [] for k in keys}
            for _ in range(args.repeats):
                for k in keys:
                    rate[k].append(harness.importer_rate(runs[k]))
            b = max(rate[args.base, m, "2"])
            for (tree, _, v), r in rate.items():
                if (tree, v) != (args.base, "2"):
                    print(f"native FMI {v}.0 FMU ({tree}) from the C importer, fig13 {m}: "
                          f"{max(r):.4g} steps/s against {b:.4g} ({args.base}, FMI 2.0), "
                          f"time ratio {b / max(r):.3f}")  # fmt: skip
        if args.callgrind:
            for m in METHODS:
                ins = {k: instructions_per_step(v, work) for k, v in runs.items() if k[1] == m}
                b = ins[args.base, m, "2"]
                for (tree, _, v), n in ins.items():
                    counts.setdefault((tree, v), {})[m] = n
                    print(
                        f"native FMI {v}.0 FMU ({tree}), fig13 {m}: {n:.0f} instructions "
                        f"per step, ratio {n / b:.3f} to {args.base}'s FMI 2.0 FMU"
                    )
    if args.write:
        cmd = (
            f"python benchmarks/bench_front_ends.py --base {args.base} --steps {args.steps} "
            f"--importer-steps {args.importer_steps} --repeats {args.repeats}"
        )
        harness.write_block(DOC, BLOCK, instruction_table(counts, args.base, cmd))
    return 0


def instruction_table(counts: dict[tuple[str, str], dict[str, float]], base: str, cmd: str) -> str:
    """Instructions per step of each native FMU (tree, FMI version) and method, and their
    ratio to the FMI 2.0 FMU of ``base``."""
    lines = [
        harness.made_by(f"{cmd} --callgrind --write"),
        "",
        "| FMU | " + " | ".join(f"{m} | ratio" for m in METHODS) + " |",
        "|---|" + "---|---|" * len(METHODS),
    ]
    ref = counts[base, "2"]
    for (tree, v), n in sorted(counts.items(), key=lambda kv: (kv[0][1], kv[0][0] != base)):
        cells = " | ".join(f"{n[m]:.0f} | {n[m] / ref[m]:.3f}" for m in METHODS)
        lines.append(f"| native FMI {v}.0, {tree} | {cells} |")
    return "\n".join(lines)


if __name__ == "__main__":
    sys.exit(main())
