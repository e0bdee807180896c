"""``mftire diagnose DATA [DATA ...] --tir fitted.tir --output DIR [--holdout COLUMN=VALUES]``."""

from __future__ import annotations

import argparse
import os


def _cmd_diagnose(args: argparse.Namespace) -> int:
    from mftire.diagnosis.diagnose import diagnose
    from mftire.diagnosis.holdout import parse_holdout
    from mftire.diagnosis.report import write_report
    from mftire.iotools.loaders import load_sweep_files
    from mftire.iotools.output import OutputPlan
    from mftire.tyre import load

    if args.each or os.path.isdir(args.tir):
        return _cmd_diagnose_each(args)  # one diagnosis per file (a folder of fitted .tir files: one per input)
    OutputPlan([*args.data, args.tir], args.force).folder(args.output, REPORT_FILES)
    tyre = load(args.tir)
    data, _ = load_sweep_files(args.data)
    holdout = parse_holdout(args.holdout) if args.holdout else None
    from mftire.cli_options import progress_of

    result = diagnose(data, tyre, holdout, n_perm=args.permutations, seed=args.seed, progress=progress_of(args))
    doc = write_report(result, args.output)
    print(doc["summary"])
    for ch, c in ((doc.get("holdout") or {}).get("channels") or {}).items():
        print(f"  held out {ch}: RMS {c['rms_pct_before']:.2f} % -> {c['rms_pct_after']:.2f} % of peak")
    print(f"  report: {os.path.join(args.output, 'diagnosis.md')}")
    return 0


def _cmd_diagnose_each(args: argparse.Namespace) -> int:
    """``--each``: one diagnosis per input file into ``OUTPUT/<name>/``; ``--tir`` a .tir for all, or a folder
    with ``<name>.tir`` per input (what ``mftire fit --each`` writes)."""
    from mftire.batch import run_batch
    from mftire.diagnosis.diagnose_batch import DiagnoseFile
    from mftire.diagnosis.holdout import parse_holdout
    from mftire.errors import MftireInputError
    from mftire.iotools.output import OutputPlan
    from mftire.iotools.tir import read_tir
    from mftire.parallel import Executor, batch_names, expand_inputs
    from mftire.tyre import load

    paths = expand_inputs(args.data)
    names = batch_names(paths)
    tirs = {n: os.path.join(args.tir, n + ".tir") for n in names} if os.path.isdir(args.tir) else {}
    for n, t in tirs.items():
        if not os.path.isfile(t):
            raise MftireInputError(f"{t}: no fitted .tir for input {n!r} in the folder {args.tir}")
    OutputPlan([*paths, *(tirs.values() or [args.tir])], args.force).folder(
        args.output, [f"{n}/{f}" for n in names for f in REPORT_FILES])
    executor = Executor.from_args(args)
    for t in tirs.values() or [args.tir]:
        load(t)  # a broken .tir is an error before any work
    tyres = {n: read_tir(t) for n, t in tirs.items()}
    task = DiagnoseFile(tyres, None if tirs else read_tir(args.tir),
                        parse_holdout(args.holdout) if args.holdout else None, args.permutations, args.seed)
    lines = run_batch(executor, task, paths, names, args.output, "diagnose", "diagnoses done")
    print("\n".join([f"mftire diagnose: {len(paths)} diagnoses into {args.output} ({executor.describe()})",
                     *("  " + x for x in lines)]))
    return 0


#: Fixed file names of the diagnosis folder (plus residual_vs_<variable>.png).
REPORT_FILES = ("diagnosis.md", "diagnosis.json", "extended.tir", "ranking.png", "curves_before_after.png")


def add_parser(subparsers: argparse._SubParsersAction) -> argparse.ArgumentParser:
    from mftire.cli_options import add_force_option, add_parallel_options, add_quiet_option, add_sweep_command

    p = add_sweep_command(subparsers, "diagnose", help="trace the residual of a fitted .tir to a missing effect, "
                          "add it, report before/after on held-out data",
                          description="Rank candidate causes of the residual of a fitted .tir, add the most likely "
                          "missing effect, refit and report the error before and after on a held-out operating "
                          "condition.")  # fmt: skip
    p.add_argument("--tir", required=True, help="the fitted .tir (with --each: or a folder of <name>.tir, one per "
                   "input, as mftire fit --each writes)")
    p.add_argument("--each", action="store_true",
                   help="one diagnosis per DATA file (several files or a glob), run as parallel tasks (--jobs, "
                   "--scheduler), each into OUTPUT/<name>/ (implied when --tir is a folder)")
    p.add_argument("--output", required=True, help="output directory")
    p.add_argument("--holdout", help="held-out condition, COLUMN=V1[,V2...] in SI (e.g. Vx=16.67); default automatic")
    p.add_argument("--permutations", type=int, default=99, help="permutations of the significance test (default 99)")
    p.add_argument("--seed", type=int, default=0, help="random seed of the permutation test (default 0)")
    add_parallel_options(p, "the diagnoses of --each")
    add_force_option(p)
    add_quiet_option(p)
    p.set_defaults(func=_cmd_diagnose)
    return p
