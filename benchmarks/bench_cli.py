"""Command-line start-up time: ``mftire --help`` and ``mftire info FILE``.

Run: ``python benchmarks/bench_cli.py [--repeat N] [--importtime]``.  Each command runs
``--repeat`` times in a fresh interpreter (``python -m mftire.cli ...``, this source
tree first on the path); the median wall time is printed, with the interpreter alone
(``python -c pass``) and, as the baseline measured in the same run, a start-up that
imports what ``mftire --help`` loaded before the lazy imports (pandas, scipy and the
fitting, FE, FMU, comparison and rig-import modules).  Target (issue 15): < 0.3 s for
``--help`` and ``info``; the CPU time of each process is printed too.  ``--importtime``
also prints the slowest imports of each command (``python -X importtime``).
"""

from __future__ import annotations

import argparse
import os
import resource
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
TIR = ROOT / "tests/data/tir/mfeval/MagicFormula61_Paramerters.tir"
TARGET_S = 0.3
EAGER = ("import mftire.cli, mftire.tyre, mftire.fitting.fitter, mftire.fe.slip_sweeps, mftire.fmu.export, "
         "mftire.compare.comparison, mftire.iotools.rig, mftire.iotools.loaders; mftire.cli.build_parser()")


def _env() -> dict[str, str]:
    env = dict(os.environ)
    env["PYTHONPATH"] = str(ROOT) + (os.pathsep + env["PYTHONPATH"] if env.get("PYTHONPATH") else "")
    return env


def _cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def _time(args: list[str], repeat: int) -> tuple[float, float]:
    """Median wall and CPU (user + system) time of ``python ARGS``."""
    wall, cpu = [], []
    for _ in range(repeat):
        t0, c0 = time.perf_counter(), _cpu()
        subprocess.run([sys.executable, *args], env=_env(), check=True, stdout=subprocess.DEVNULL)
        wall.append(time.perf_counter() - t0)
        cpu.append(_cpu() - c0)
    return statistics.median(wall), statistics.median(cpu)


def _slowest_imports(args: list[str], n: int = 5) -> list[str]:
    err = subprocess.run([sys.executable, "-X", "importtime", *args], env=_env(), stdout=subprocess.DEVNULL,
                         stderr=subprocess.PIPE, text=True, check=True).stderr
    rows = []
    for line in err.splitlines():
        parts = line.split("|")
        if len(parts) == 3 and parts[1].strip().isdigit():
            rows.append((int(parts[1]), parts[2].strip()))
    return [f"{us / 1e3:8.1f} ms  {name}" for us, name in sorted(rows, reverse=True)[:n]]


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=7)
    ap.add_argument("--importtime", action="store_true")
    args = ap.parse_args()

    cases = {
        "python -c pass (interpreter)": ["-c", "pass"],
        "mftire --help": ["-m", "mftire.cli", "--help"],
        "mftire info FILE": ["-m", "mftire.cli", "info", str(TIR)],
        "eager imports (baseline)": ["-c", EAGER],
    }
    times = {name: _time(cmd, args.repeat) for name, cmd in cases.items()}
    base = times["eager imports (baseline)"]
    print(f"start-up, median of {args.repeat} runs [s] (CPU = user + system of the process, which stands for "
          "the wall time when the machine is shared):")
    print(f"  {'':<32}{'wall':>8}{'CPU':>8}")
    for name, (wall, cpu) in times.items():
        ratio = f"  {base[0] / wall:5.1f}x faster than the baseline" if name.startswith("mftire") else ""
        print(f"  {name:<32}{wall:8.3f}{cpu:8.3f}{ratio}")
    ok = {kind: all(times[n][i] < TARGET_S for n in ("mftire --help", "mftire info FILE"))
          for i, kind in enumerate(("wall", "CPU"))}
    print(f"target < {TARGET_S} s for --help and info: wall {'met' if ok['wall'] else 'NOT met'}, "
          f"CPU {'met' if ok['CPU'] else 'NOT met'}")
    if args.importtime:
        for name in ("mftire --help", "mftire info FILE"):
            print(f"\nslowest imports of {name} (cumulative):")
            print("\n".join(_slowest_imports(cases[name])))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
