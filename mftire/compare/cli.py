"""``mftire compare --tir A.tir [B.tir ...] [--data D.csv ...] [--fe FE.csv ...] [--conditions ...] --output DIR``."""

from __future__ import annotations

import argparse
import os


def _cmd_compare(args: argparse.Namespace) -> int:
    from mftire.compare.comparison import compare, write_comparison
    from mftire.compare.data import load_comparison_data
    from mftire.errors import MftireInputError
    from mftire.iotools.output import OutputPlan

    if not args.data and not args.fe:
        return _compare_models(args)
    if args.conditions:
        raise MftireInputError("--conditions is for a comparison without data; with --data/--fe the curves are "
                               "drawn at the data's conditions")
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


def _compare_models(args: argparse.Namespace) -> int:
    """No data: the models' curves over the usual (or ``--conditions``) conditions and the difference table."""
    from mftire.compare.comparison import compare_models, write_comparison
    from mftire.compare.conditions import parse_conditions
    from mftire.iotools.output import OutputPlan

    conditions = parse_conditions(args.conditions) if args.conditions is not None else None  # before any work
    OutputPlan([*args.tir], args.force).folder(args.output, ("compare.md", "compare.json"))
    comp = compare_models(args.tir, conditions, mode=args.mode)
    paths = write_comparison(comp, args.output, plots=not args.no_plots)
    t = comp.characteristics
    lines = [f"mftire compare: {len(comp.models)} model(s), no data, {len(t) // len(comp.models)} condition(s)"]
    first = next(iter(comp.models))
    for r in t.itertuples(index=False):
        d = "" if r.model == first else (f"  (vs {first}: Kxk {r.d_Kxk_pct:+.1f} %, Kya {r.d_Kya_pct:+.1f} %, "
                                         f"µx {r.d_mu_x_peak_pct:+.1f} %, µy {r.d_mu_y_peak_pct:+.1f} %, "
                                         f"t0 {r.d_t0_pct:+.1f} %)")
        lines.append(f"  {r.model} at Fz {r.Fz:.0f} N, {r.Vx * 3.6:.0f} km/h, {r.P / 1e5:.3g} bar, "
                     f"γ {r.gamma * 57.29577951308232:.1f}°: Kxk {r.Kxk:.4g} N, Kya {r.Kya:.4g} N/rad, "
                     f"µx {r.mu_x_peak:.3f}, µy {r.mu_y_peak:.3f}, t0 {1000 * r.t0:.1f} mm{d}")
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
        "write compare.md, compare.json (every number) and one PNG per sweep family and channel (braking, "
        "cornering, combined; every condition of the data) plus stiffness, pneumatic trail and free-rolling "
        "figures. Without --data/--fe: the models' curves over the usual conditions (or --conditions) and a "
        "table of slip stiffness, cornering stiffness, peak µ and trail with differences to the first model.",
    )
    p.add_argument("--tir", nargs="+", required=True, metavar="TIR", help="one or more MF .tir files")
    p.add_argument("--data", nargs="+", default=[], metavar="DATA",
                   help="measured sweeps: CSV in the SI sweep schema (a source column labels them, else the file "
                   "stem) or TYDEX .tdx")
    p.add_argument("--fe", nargs="+", default=[], metavar="FE", help="FE-surrogate sweeps (mftire fe campaign CSV)")
    p.add_argument("--conditions", metavar="SPEC",
                   help="without data: conditions of the curves, e.g. loads=3000,4500,6000,speeds=40,80,"
                   "pressures=2.2,cambers=0,-2 (loads N, speeds km/h, pressures bar, cambers deg; a list runs "
                   "until the next key=); default 0.5/1/1.5 x FNOMIN at LONGVL, NOMPRES, camber 0")
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
