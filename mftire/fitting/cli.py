"""``mftire fit DATA [DATA ...] --template TIR --output fitted.tir [--report DIR] ...``."""

from __future__ import annotations

import argparse
import sys


def _cmd_fit(args: argparse.Namespace) -> int:
    import os

    from mftire.errors import MftireInputError
    from mftire.fitting.fitter import fit_tir
    from mftire.iotools.tir import write_tir

    if args.each or args.output.endswith(("/", os.sep)):
        return _cmd_fit_each(args)  # one fit per file (an output named as a folder cannot be one fitted .tir)
    from mftire.parallel import expand_inputs

    args.data = expand_inputs(args.data)  # a glob the shell did not expand
    _check_outputs(args)
    if args.bands:  # the cluster is checked before any work
        from mftire.parallel import Executor

        args.executor = Executor.from_args(args)
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


def _cmd_fit_each(args: argparse.Namespace) -> int:
    """``--each``: one fit per input file, ``OUTPUT/<name>.tir`` (and ``OUTPUT/<name>/`` with ``--report``)."""
    from mftire.batch import run_batch
    from mftire.errors import MftireInputError
    from mftire.fitting.fit_batch import FitFile
    from mftire.iotools.output import OutputPlan
    from mftire.parallel import Executor, batch_names, expand_inputs
    from mftire.tyre import load

    if args.bands or args.heldout or (args.report and args.report != "each"):
        raise MftireInputError("with --each, --report takes the word 'each' (a report folder <name>/ per input in "
                               "the output folder); --bands and --heldout are for one fit")
    paths = expand_inputs(args.data)
    names = batch_names(paths)
    plan = OutputPlan([*paths, args.template], args.force)
    plan.folder(args.output, [n + ".tir" for n in names])
    executor = Executor.from_args(args)
    fixed = tuple(k.strip() for k in (args.fix or "").split(",") if k.strip())
    load(args.template)  # a broken template is an error, a suspicious one warns
    from mftire.iotools.tir import read_tir

    task = FitFile(read_tir(args.template), args.stages, args.weights, args.alpha_star, fixed,
                   report=bool(args.report))
    lines = run_batch(executor, task, paths, names, args.output, "fit", "fits done")
    print("\n".join([f"mftire fit: {len(paths)} fits into {args.output} ({executor.describe()})",
                     *("  " + x for x in lines)]))
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
                            executor=getattr(args, "executor", None) or Executor.from_args(args),
                            progress=progress_of(args))
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
    from mftire.cli_options import add_force_option, add_parallel_options, add_quiet_option, add_sweep_command

    p = add_sweep_command(subparsers, "fit", help="fit MF 6.1/6.2 coefficients to slip sweeps",
                          description="Staged Magic Formula fit: 1 longitudinal, 2 lateral, 3 aligning, 4 combined "
                          "Fx/Fy, 5 combined Mz, 6 Mx, 7 My. Coefficients the data cannot identify keep their "
                          "template values.")  # fmt: skip
    p.add_argument("--template", required=True, metavar="TIR",
                   help="start values and constants (FNOMIN, NOMPRES, UNLOADED_RADIUS, ...), FITTYP 61/62")
    p.add_argument("--output", required=True, metavar="FITTED.tir", help="fitted .tir (written atomically)")
    p.add_argument("--report", metavar="DIR", help="write report.md, metrics.json and plots into DIR "
                   "(with --each: --report each, a report folder per input in the output folder)")
    p.add_argument("--each", action="store_true",
                   help="one fit per DATA file (several files or a glob such as 'runs/*.csv'), run as parallel "
                   "tasks (--jobs, --scheduler); --output is then a folder receiving <name>.tir per input "
                   "(implied when --output ends with /)")
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
    add_parallel_options(p, "the fits of --each and the bootstrap refits of --bands")
    p.add_argument("--fix", metavar="KEYS", help="coefficients held at their template values, "
                   "comma-separated (e.g. PPX1,PPX2,PPX3,PPX4 to fit without pressure terms)")
    add_force_option(p)
    add_quiet_option(p)
    p.set_defaults(func=_cmd_fit)
    return p
