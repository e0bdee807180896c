"""Command-line interface: ``mftire <command> ...``.

Sub-commands are registered here; larger features (``fe``, ``fit`` ...) register
their own through an ``add_parser(subparsers)`` function.  Errors in the user's
input print one line naming the file, column and row, and exit with code 2.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
from collections.abc import Sequence
from typing import TYPE_CHECKING

from mftire.data import default_tir  # noqa: F401  (moved to mftire.data; kept importable from here)
from mftire.errors import MftireError

if TYPE_CHECKING:  # pandas, scipy, matplotlib and the feature packages load when a command needs them
    import pandas as pd

#: Columns of ``mftire evaluate``'s input CSV.
EVALUATE_REQUIRED = ("Fz", "kappa", "alpha", "gamma")
EVALUATE_OPTIONAL = ("phit", "Vx", "P", "omega")


def _cmd_evaluate(args: argparse.Namespace) -> int:
    import pandas as pd

    from mftire.iotools.loaders import read_numeric_csv
    from mftire.iotools.output import OutputPlan
    from mftire.tyre import Tyre

    OutputPlan([args.tir, args.input], args.force).file(args.output, stdout=True)
    tyre = Tyre.from_file(args.tir, strict=args.strict)
    # columns the model extensions of the file need (e.g. temperature) are required too
    df = read_numeric_csv(args.input, (*EVALUATE_REQUIRED, *tyre.required_variables), EVALUATE_OPTIONAL)
    df = df.reset_index(drop=True)
    result = pd.concat([df, tyre.evaluate_frame(df, mode=args.mode, name=args.input)], axis=1)
    if args.output == "-":
        evaluate_columns(result, len(df.columns)).to_csv(sys.stdout, index=False)  # shortest exact floats
    else:
        from mftire.iotools.atomic import atomic_path

        with atomic_path(args.output) as tmp:
            evaluate_columns(result, len(df.columns)).to_csv(tmp, index=False)
    return 0


def evaluate_columns(result: pd.DataFrame, n_inputs: int) -> pd.DataFrame:
    """``result`` (the ``n_inputs`` input columns, then the model outputs) with every output
    whose name is also an input column (a measured ``Fx``, the echoed ``Fz``) renamed
    ``<name>_model`` (``Fx_model``), so that no two columns share a name."""
    inputs = [str(c) for c in result.columns[:n_inputs]]
    outputs = [f"{c}_model" if str(c) in inputs else str(c) for c in result.columns[n_inputs:]]
    return result.set_axis([*inputs, *outputs], axis=1)


def _cmd_convert(args: argparse.Namespace) -> int:
    from mftire.iotools.output import OutputPlan
    from mftire.iotools.tir import read_tir, write_tir
    from mftire.tyre import load

    OutputPlan([args.input], args.force).file(args.output)
    load(args.input)  # refuse to copy a broken file (mftire.iotools.tir_checks)
    write_tir(read_tir(args.input), args.output)
    return 0


def _cmd_info(args: argparse.Namespace) -> int:
    if args.fmu:
        from mftire.fmu.build import find_compiler
        from mftire.fmu.portable import build_info

        try:
            cc = " ".join(find_compiler())
        except MftireError as exc:
            cc = f"none ({exc})"
        print("FMU export on this machine (mftire export-fmu):")
        for key, value in build_info(cc).items():
            print(f"  {key + ':':16} {value}")
        if args.tir is None:
            return 0
        print()
    elif args.tir is None:
        raise MftireError("mftire info: give a .tir file (or --fmu)")
    from mftire.iotools.tir import read_tir
    from mftire.iotools.tir_checks import check_parameters
    from mftire.tyre import Tyre

    params = read_tir(args.tir, strict=args.strict)
    report = check_parameters(params)
    try:
        print(tyre_info(Tyre(params)))
    except MftireError:  # a file the evaluator cannot take (FNOMIN = 0): the checks say why
        print(f"file:            {args.tir}")
    print(report.format())
    return report.exit_code(strict=args.strict)


def tyre_info(tyre) -> str:
    """Human-readable summary used by ``mftire info``."""
    from mftire.parameters import BY_KEY

    params = tyre.parameters
    f = tyre.flat
    lines = [f"file:            {getattr(params, 'path', '') or tyre.name}"]
    try:
        model = params.model
    except Exception:  # noqa: BLE001 - plain mappings have no model name
        model = ""
    lines.append(f"model:           {tyre.format} ({model})" if model and model not in tyre.format else
                 f"model:           {tyre.format}")
    w, ar, rim = f["WIDTH"], f["ASPECT_RATIO"], f["RIM_RADIUS"]
    lines.append(
        f"size:            width {w * 1000:.0f} mm, aspect ratio {ar * 100:.0f} %, rim {2 * rim / 0.0254:.1f} in,"
        f" unloaded radius {f['UNLOADED_RADIUS']:.4f} m"
    )
    lines.append(f"nominal load:    FNOMIN = {f['FNOMIN']:g} N")
    lines.append(f"pressure:        NOMPRES = {f['NOMPRES'] / 1e5:g} bar, INFLPRES = {f['INFLPRES'] / 1e5:g} bar")
    lines.append(f"nominal speed:   LONGVL = {f['LONGVL']:g} m/s, VXLOW = {f['VXLOW']:g} m/s")
    lines.append("ranges:")
    lines.append(f"  Fz    {f['FZMIN']:g} .. {f['FZMAX']:g} N")
    lines.append(f"  kappa {f['KPUMIN']:g} .. {f['KPUMAX']:g}")
    lines.append(f"  alpha {math.degrees(f['ALPMIN']):.2f} .. {math.degrees(f['ALPMAX']):.2f} deg")
    lines.append(f"  gamma {math.degrees(f['CAMMIN']):.2f} .. {math.degrees(f['CAMMAX']):.2f} deg")
    lines.append(f"  P     {f['PRESMIN'] / 1e5:g} .. {f['PRESMAX'] / 1e5:g} bar")
    lines.append("parameters per section (in file / standard keys absent, taking defaults):")
    sections = getattr(params, "sections", None) or {}
    for name, content in sections.items():
        n = len(content) if isinstance(content, dict) else 0
        std = {p.key for p in BY_KEY.values() if p.section == name}
        absent = len(std - set(content)) if isinstance(content, dict) else 0
        lines.append(f"  [{name}] {n}" + (f" / {absent} defaulted" if absent else ""))
    return "\n".join(lines)


def _cmd_plot(args: argparse.Namespace) -> int:
    from mftire.curves import standard_curves
    from mftire.iotools.output import OutputPlan
    from mftire.plotting import plot_standard_curves
    from mftire.tyre import load

    plan = OutputPlan([args.tir], args.force)
    plan.file(args.output, figure=True)
    if args.csv:
        plan.file(args.csv, stdout=True)
    tyre = load(args.tir)
    curves = standard_curves(tyre, mode=args.mode)
    plot_standard_curves(curves, args.output, title=tyre.name)
    if args.csv == "-":
        curves.to_csv(sys.stdout, index=False)
    elif args.csv:
        from mftire.iotools.atomic import atomic_path

        with atomic_path(args.csv) as tmp:
            curves.to_csv(tmp, index=False)
    return 0


def _cmd_demo(args: argparse.Namespace) -> int:
    from mftire.demo import OUTPUT_NAMES, run_demo
    from mftire.iotools.output import OutputPlan
    from mftire.parallel import Executor

    OutputPlan((), args.force).folder(args.output, OUTPUT_NAMES)
    from mftire.cli_options import progress_of

    run_demo(args.output, quick=args.quick, progress=progress_of(args), executor=Executor.from_args(args))
    return 0


def build_parser() -> argparse.ArgumentParser:
    from importlib.metadata import PackageNotFoundError, version

    try:
        __version__ = version("mftire")
    except PackageNotFoundError:  # a source tree that is not installed
        __version__ = "unknown"
    from mftire.cli_options import add_force_option

    parser = argparse.ArgumentParser(
        prog="mftire", description=__doc__.splitlines()[0],
        epilog="Outputs: an existing file is replaced only with --force; an output that is one of the inputs is "
        "refused; missing folders are created; /dev/null and named pipes are written through (README, Outputs).",
    )  # fmt: skip
    parser.add_argument("--version", action="version", version=f"mftire {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    p = sub.add_parser("evaluate", help="evaluate a .tir over the operating points of a CSV",
                       description="Evaluate the Magic Formula of a .tir at every row of a CSV; the output holds the "
                       "input columns and the 30 model outputs (an output named like an input column, e.g. a "
                       "measured Fx, is written as Fx_model).")  # fmt: skip
    p.add_argument("tir", metavar="TIR", help="the .tir property file")
    p.add_argument("--input", required=True, help="CSV with Fz,kappa,alpha,gamma[,phit,Vx,P,omega] (SI, rad)")
    p.add_argument("--output", required=True, help="output CSV, or - for standard output")
    p.add_argument("--mode", type=int, default=111, help="MFeval useMode (default 111)")
    p.add_argument("--strict", action="store_true", help="reading warnings (blank/non-numeric values) are errors")
    add_force_option(p)
    p.set_defaults(func=_cmd_evaluate)

    p = sub.add_parser("convert", help="read a .tir and write it back (SI units)",
                       description="Read a .tir (any units, any layout the reader accepts) and write it in SI units.")
    p.add_argument("input", metavar="IN.tir", help="the .tir to read")
    p.add_argument("output", metavar="OUT.tir", help="the .tir to write (not the input)")
    add_force_option(p)
    p.set_defaults(func=_cmd_convert)

    p = sub.add_parser("info", help="summarise a .tir and check it",
                       description="Print the size, loads, ranges and sections of a .tir, the keys that take "
                       "default values and every failed sanity check. Exit code 0, or 1 with --strict when a "
                       "check warns, 2 when the file is broken.")  # fmt: skip
    p.add_argument("tir", metavar="TIR", nargs="?", help="the .tir property file")
    p.add_argument("--strict", action="store_true", help="reading warnings (blank/non-numeric values) are errors; "
                   "exit 1 on check warnings too (for CI)")
    p.add_argument("--fmu", action="store_true", help="also say what export-fmu builds here: compiler, glibc "
                   "floor of the Linux binary, whether a Windows DLL is shipped (MinGW-w64 present)")  # fmt: skip
    p.set_defaults(func=_cmd_info)

    p = sub.add_parser("plot", help="draw the standard curves at 0.5, 1 and 1.5 x FNOMIN",
                       description="Draw pure longitudinal, pure lateral, aligning, overturning and combined-slip "
                       "curves of a .tir in one figure.")  # fmt: skip
    p.add_argument("tir", metavar="TIR", help="the .tir property file")
    p.add_argument("--output", required=True, help="figure file; the format follows the suffix (.png, .pdf, .svg)")
    p.add_argument("--csv", help="also write the curve data to this CSV (- for standard output)")
    p.add_argument("--mode", type=int, default=111, help="MFeval useMode (default 111)")
    add_force_option(p)
    p.set_defaults(func=_cmd_plot)

    p = sub.add_parser(
        "demo", help="the whole loop on the shipped default data: FE and measured-like campaigns, fit, "
        "diagnosis, extended .tir, FMU, comparison with bands, HTML report",
        description="Run the whole loop on the shipped default data and write every result into one folder.",
    )
    p.add_argument("--output", default="demo_out", help="output directory (default demo_out)")
    p.add_argument("--quick", action="store_true", help="reduced grids (a test run)")
    from mftire.cli_options import add_parallel_options

    add_parallel_options(p, "the FE campaign chunks and the bootstrap refits")
    add_force_option(p)
    from mftire.cli_options import add_quiet_option

    add_quiet_option(p)
    p.set_defaults(func=_cmd_demo)

    from mftire.fe import cli as fe_cli

    fe_cli.add_parser(sub)
    from mftire.fitting import cli as fit_cli

    fit_cli.add_parser(sub)
    from mftire.fmu import cli as fmu_cli

    fmu_cli.add_parser(sub)
    from mftire.diagnosis import cli as diagnose_cli

    diagnose_cli.add_parser(sub)
    from mftire.compare import cli as compare_cli

    compare_cli.add_parser(sub)
    from mftire.segmentation import cli as import_cli

    import_cli.add_parser(sub)
    return parser


def _one_line_warning(prefix: str):
    """``warnings.showwarning`` replacement: one line, no source line."""

    def show(message, category, filename, lineno, file=None, line=None) -> None:
        print(f"{prefix}: warning: {message}", file=sys.stderr if file is None else file)

    return show


def main(argv: Sequence[str] | None = None) -> int:
    import warnings

    parser = build_parser()
    args = parser.parse_args(argv)
    prefix = f"mftire {args.command}"
    try:
        with warnings.catch_warnings():
            warnings.showwarning = _one_line_warning(prefix)
            rc = int(args.func(args) or 0)
        sys.stdout.flush()
        return rc
    except (MftireError, OSError) as exc:
        if isinstance(exc, BrokenPipeError):
            return _broken_pipe()
        print(f"{prefix}: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"{prefix}: interrupted", file=sys.stderr)
        return 130


def _broken_pipe() -> int:
    """Standard output was closed early (``mftire ... | head``): leave quietly."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())  # the interpreter's last flush must not fail again
        os.close(devnull)
    except (OSError, ValueError, AttributeError):
        pass
    return 141  # 128 + SIGPIPE, as a shell tool killed by the signal


if __name__ == "__main__":
    sys.exit(main())
