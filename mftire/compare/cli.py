"""``mftire compare --tir A.tir [B.tir ...] --data D.csv [...] [--fe FE.csv ...] --output DIR``."""

from __future__ import annotations

import argparse
import os


def _cmd_compare(args: argparse.Namespace) -> int:
    from mftire.compare.comparison import compare, write_comparison
    from mftire.compare.data import load_comparison_data
    from mftire.errors import MftireInputError

    if not args.data and not args.fe:
        raise MftireInputError("give measured sweeps (--data) and/or FE-surrogate sweeps (--fe)")
    from mftire.iotools.output import OutputPlan

    OutputPlan([*args.tir, *args.data, *args.fe, args.bands], args.force).folder(
        args.output, ("compare.md", "compare.json", "bands_drawn.csv"))
    data = load_comparison_data(args.data or [], args.fe or [])
    comp = compare(args.tir, data, mode=args.mode, bands=args.bands, alpha_window_deg=args.alpha_window)
    paths = write_comparison(comp, args.output, plots=not args.no_plots)
    s = comp.summary
    lines = [f"mftire compare: {len(comp.models)} model(s), {data['source'].nunique()} source(s), "
             f"{data['sweep_id'].nunique()} sweeps, {len(comp.errors)} curve errors"]
    for r in s.itertuples(index=False):
        lines.append(f"  {r.model} vs {r.source} {r.family} {r.channel}: {r.curves} curves, RMS "
                     f"{r.rms_pct_median:.2f} % of peak (median), {r.rms_pct_max:.2f} % (worst)")
    lines.append(f"  wrote {paths['markdown']}, {paths['json']} and {len(paths['plots'])} plot(s) in "
                 f"{os.path.dirname(paths['markdown']) or '.'}")
    print("\n".join(lines))
    return 0


def add_parser(subparsers) -> argparse.ArgumentParser:
    """Register ``compare`` on the ``mftire`` sub-command parser."""
    p = subparsers.add_parser(
        "compare",
        help="overlay MF models, FE-surrogate and measured sweeps; error tables and plots",
        description="Evaluate each .tir at the exact operating points of every data sweep and on smooth grids; "
        "write compare.md, compare.json (every number) and one PNG per sweep family (braking, cornering, "
        "combined) plus stiffness, pneumatic trail and free-rolling figures.",
    )
    p.add_argument("--tir", nargs="+", required=True, metavar="TIR", help="one or more MF .tir files")
    p.add_argument("--data", nargs="+", default=[], metavar="DATA",
                   help="measured sweeps: CSV in the SI sweep schema (a source column labels them, else the file "
                   "stem) or TYDEX .tdx")
    p.add_argument("--fe", nargs="+", default=[], metavar="FE", help="FE-surrogate sweeps (mftire fe campaign CSV)")
    p.add_argument("--output", required=True, metavar="DIR", help="output directory")
    p.add_argument("--bands", metavar="BANDS.csv", help="bootstrap bands to draw (bands.csv of mftire fit --bands)")
    p.add_argument("--mode", type=int, default=111, help="MF evaluation mode (default 111)")
    p.add_argument("--alpha-window", type=float, default=2.5, metavar="DEG",
                   help="|alpha| window of the stiffness fits in degrees (default 2.5)")
    p.add_argument("--no-plots", action="store_true", help="tables only")
    from mftire.cli_options import add_force_option

    add_force_option(p)
    p.set_defaults(func=_cmd_compare)
    return p
