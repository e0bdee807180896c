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


#: Fixed file names of the diagnosis folder (plus residual_vs_<variable>.png).
REPORT_FILES = ("diagnosis.md", "diagnosis.json", "extended.tir", "ranking.png", "curves_before_after.png")


def add_parser(subparsers: argparse._SubParsersAction) -> argparse.ArgumentParser:
    p = subparsers.add_parser(
        "diagnose",
        help="trace the residual of a fitted .tir to a missing effect, add it, report before/after on held-out data",
        description="Rank candidate causes of the residual of a fitted .tir, add the most likely missing effect, "
        "refit and report the error before and after on a held-out operating condition.",
    )
    p.add_argument("data", nargs="+", metavar="DATA", help="sweep data (CSV in the sweep schema, or TYDEX .tdx)")
    p.add_argument("--tir", required=True, help="the fitted .tir")
    p.add_argument("--output", required=True, help="output directory")
    p.add_argument("--holdout", help="held-out condition, COLUMN=V1[,V2...] in SI (e.g. Vx=16.67); default automatic")
    p.add_argument("--permutations", type=int, default=99, help="permutations of the significance test (default 99)")
    p.add_argument("--seed", type=int, default=0, help="random seed of the permutation test (default 0)")
    from mftire.cli_options import add_force_option

    add_force_option(p)
    from mftire.cli_options import add_quiet_option

    add_quiet_option(p)
    p.set_defaults(func=_cmd_diagnose)
    return p
