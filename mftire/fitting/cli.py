"""``mftire fit DATA [DATA ...] --template TIR --output fitted.tir [--report DIR] ...``."""

from __future__ import annotations

import argparse
import sys


def _cmd_fit(args: argparse.Namespace) -> int:
    from mftire.fitting.core import fit_tir
    from mftire.iotools.tir import write_tir

    result = fit_tir(args.data, args.template, stages=args.stages, weights=args.weights,
                     alpha_star=args.alpha_star)
    write_tir(result.parameters, args.output)
    lines = [f"mftire fit: wrote {args.output} ({len(dict.fromkeys(result.identified))} coefficients fitted, "
             f"{len(result.not_identified)} not identified, {result.time:.1f} s)"]
    for s in result.stages:
        if s.status == "fitted":
            lines.append(f"  stage {s.number} {s.name} [{s.channel}]: {s.n_points} points, "
                         f"RMS {s.rms_start:.4g} -> {s.rms:.4g}")
    lines.extend(f"  note: {m}" for m in result.messages)
    if args.report:
        from mftire.fitting.report import write_report

        paths = write_report(result, args.report)
        lines.append(f"  report: {paths['report']}, {paths['metrics']}, {len(paths['plots'])} plot(s)")
    print("\n".join(lines), file=sys.stdout)
    return 0


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
    p.set_defaults(func=_cmd_fit)
    return p
