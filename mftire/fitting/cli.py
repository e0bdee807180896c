"""``mftire fit DATA [DATA ...] --template TIR --output fitted.tir [--report DIR] ...``."""

from __future__ import annotations

import argparse
import sys


def _cmd_fit(args: argparse.Namespace) -> int:
    from mftire.errors import MftireInputError
    from mftire.fitting.fitter import fit_tir
    from mftire.iotools.tir import write_tir

    _check_outputs(args)
    from mftire.tyre import load

    load(args.template)  # a broken template is an error, a suspicious one warns (mftire.iotools.tir_checks)
    fixed = [k.strip() for k in (args.fix or "").split(",") if k.strip()]
    from mftire.cli_options import progress_of

    result = fit_tir(args.data, args.template, stages=args.stages, weights=args.weights,
                     alpha_star=args.alpha_star, fixed=fixed, progress=progress_of(args))
    data = result.data
    if not any(s.status == "fitted" or (s.channel in data.columns and data[s.channel].notna().any())
               for s in result.stages):
        raise MftireInputError(f"{', '.join(args.data)}: no stage could be fitted (no force or moment channel "
                               "Fx, Fy, Mz, Mx, My with data for the chosen stages); nothing written")
    write_tir(result.parameters, args.output)
    lines = [f"mftire fit: wrote {args.output} ({len(dict.fromkeys(result.identified))} coefficients fitted, "
             f"{len(result.not_identified)} not identified, {result.time:.1f} s)"]
    for s in result.stages:
        if s.status == "fitted":
            lines.append(f"  stage {s.number} {s.name} [{s.channel}]: {s.n_points} points, "
                         f"RMS {s.rms_start:.4g} -> {s.rms:.4g}")
    lines.extend(f"  note: {m}" for m in result.messages)
    if args.report:
        from mftire.fitting.fit_report import write_report

        paths = write_report(result, args.report)
        lines.append(f"  report: {paths['report']}, {paths['metrics']}, {len(paths['plots'])} plot(s)")
    if args.bands:
        lines.extend(_bands(args, result))
    print("\n".join(lines), file=sys.stdout)
    return 0


def _check_outputs(args: argparse.Namespace) -> None:
    """Every output of ``fit`` (the .tir, the report folder, the band files) before any work."""
    import os

    from mftire.iotools.output import OutputPlan

    plan = OutputPlan([*args.data, args.template, *(args.heldout or [])], args.force)
    plan.file(args.output)
    bands = ("bands.csv", "bands.json") if args.bands else ()
    if args.report:
        plan.folder(args.report, ("report.md", "metrics.json", *bands))
    else:
        for name in bands:
            plan.file(os.path.join(os.path.dirname(os.path.abspath(args.output)), name))


def _bands(args: argparse.Namespace, result) -> list[str]:
    """``--bands N``: bootstrap bands written next to the report (or the fitted .tir)."""
    import os

    from mftire.cli_options import progress_of
    from mftire.fitting.bands import bootstrap_bands, coverage_table, write_bands
    from mftire.parallel import Executor

    bands = bootstrap_bands(None, args.template, n=args.bands, level=args.band_level, fit=result,
                            weights=args.weights, alpha_star=args.alpha_star, seed=args.seed,
                            executor=Executor.from_args(args), progress=progress_of(args))
    cov = coverage_table(bands, args.heldout) if args.heldout else None
    directory = args.report or os.path.dirname(os.path.abspath(args.output))
    paths = write_bands(bands, directory, cov)
    out = [f"  bands: {len(bands.replicates)} bootstrap replicates over sweeps ({bands.n_failed} failed), "
           f"level {bands.level:g}, {bands.time:.1f} s: {paths['csv']}, {paths['json']}"]
    if cov is not None:
        a = cov.iloc[-1]
        out.append(f"  held-out coverage: {100 * a['inside_prediction']:.1f} % of {int(a['n'])} points inside the "
                   f"prediction band (nominal {100 * bands.level:g} %), {100 * a['inside_confidence']:.1f} % inside "
                   "the confidence band of the mean curve")
    return out


def add_parser(subparsers) -> argparse.ArgumentParser:
    """Register ``fit`` on the ``mftire`` sub-command parser."""
    p = subparsers.add_parser(
        "fit",
        help="fit MF 6.1/6.2 coefficients to slip sweeps (CSV in the sweep schema or TYDEX .tdx)",
        description="Staged Magic Formula fit: 1 longitudinal, 2 lateral, 3 aligning, 4 combined Fx/Fy, "
        "5 combined Mz, 6 Mx, 7 My. Coefficients the data cannot identify keep their template values.",
    )
    p.add_argument("data", nargs="+", metavar="DATA", help="sweep files: .csv (SI sweep schema) or .tdx")
    p.add_argument("--template", required=True, metavar="TIR",
                   help="start values and constants (FNOMIN, NOMPRES, UNLOADED_RADIUS, ...), FITTYP 61/62")
    p.add_argument("--output", required=True, metavar="FITTED.tir", help="fitted .tir (written atomically)")
    p.add_argument("--report", metavar="DIR", help="write report.md, metrics.json and plots into DIR")
    p.add_argument("--stages", default="all",
                   help="stages to run, numbers or names, e.g. 1,2,3 or longitudinal,lateral (default all)")
    p.add_argument("--weights", default=None,
                   help="per-source weights, e.g. fe=1,measured=5 (source column or file name)")
    p.add_argument("--alpha-star", action="store_true",
                   help="fit for evaluation with alpha* = tan(alpha) (mode 121) instead of 111")
    p.add_argument("--bands", type=int, default=0, metavar="N",
                   help="bootstrap over sweeps with N replicates (warm-started refits): confidence and prediction "
                   "bands of the fitted curves, written to bands.csv/bands.json in the report directory "
                   "(or beside the output)")
    p.add_argument("--band-level", type=float, default=0.95, metavar="LEVEL", help="band coverage (default 0.95)")
    p.add_argument("--heldout", nargs="+", metavar="DATA",
                   help="held-out measured sweeps: report the fraction of their points inside the bands")
    p.add_argument("--seed", type=int, default=0, help="random seed of the bootstrap (default 0)")
    from mftire.cli_options import add_parallel_options

    add_parallel_options(p, "the bootstrap refits of --bands")
    p.add_argument("--fix", metavar="KEYS", help="coefficients held at their template values, "
                   "comma-separated (e.g. PPX1,PPX2,PPX3,PPX4 to fit without pressure terms)")
    from mftire.cli_options import add_force_option

    add_force_option(p)
    from mftire.cli_options import add_quiet_option

    add_quiet_option(p)
    p.set_defaults(func=_cmd_fit)
    return p
