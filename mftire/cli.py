"""Command-line interface: ``mftire <command> ...``.

Sub-commands are registered here; larger features (``fe``, ``fit`` ...) register
their own through an ``add_parser(subparsers)`` function.  Errors in the user's
input print one line naming the file, column and row, and exit with code 2.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence

import numpy as np
import pandas as pd

from mftire.data import default_tir  # noqa: F401  (moved to mftire.data; kept importable from here)
from mftire.errors import MftireError
from mftire.iotools.tables import read_numeric_csv

#: Columns of ``mftire evaluate``'s input CSV.
EVALUATE_REQUIRED = ("Fz", "kappa", "alpha", "gamma")
EVALUATE_OPTIONAL = ("phit", "Vx", "P", "omega")


def _cmd_evaluate(args: argparse.Namespace) -> int:
    from mftire.tyre import Tyre

    tyre = Tyre.from_file(args.tir, strict=args.strict)
    # columns the model extensions of the file need (e.g. temperature) are required too
    df = read_numeric_csv(args.input, (*EVALUATE_REQUIRED, *tyre.required_variables), EVALUATE_OPTIONAL)
    df = df.reset_index(drop=True)
    result = pd.concat([df, tyre.evaluate_frame(df, mode=args.mode, name=args.input)], axis=1)
    if args.output == "-":
        result.to_csv(sys.stdout, index=False, float_format="%.17g")
    else:
        from mftire.iotools.atomic import atomic_path

        with atomic_path(args.output) as tmp:
            result.to_csv(tmp, index=False, float_format="%.17g")
    return 0


def _cmd_convert(args: argparse.Namespace) -> int:
    from mftire.iotools.tir import read_tir, write_tir

    write_tir(read_tir(args.input), args.output)
    return 0


def _cmd_info(args: argparse.Namespace) -> int:
    from mftire.tyre import Tyre

    print(tyre_info(Tyre.from_file(args.tir, strict=args.strict)))
    return 0


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
    lines.append(f"  alpha {np.degrees(f['ALPMIN']):.2f} .. {np.degrees(f['ALPMAX']):.2f} deg")
    lines.append(f"  gamma {np.degrees(f['CAMMIN']):.2f} .. {np.degrees(f['CAMMAX']):.2f} deg")
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
    from mftire.plotting import plot_standard_curves
    from mftire.tyre import load

    tyre = load(args.tir)
    curves = standard_curves(tyre, mode=args.mode)
    plot_standard_curves(curves, args.output, title=tyre.name)
    if args.csv:
        from mftire.iotools.atomic import atomic_path

        with atomic_path(args.csv) as tmp:
            curves.to_csv(tmp, index=False)
    return 0


def _cmd_demo(args: argparse.Namespace) -> int:
    from mftire.demo import run_demo

    run_demo(args.output, quick=args.quick, progress=True)
    return 0


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="mftire", description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    p = sub.add_parser("evaluate", help="evaluate a .tir over the operating points of a CSV")
    p.add_argument("tir", metavar="TIR")
    p.add_argument("--input", required=True, help="CSV with Fz,kappa,alpha,gamma[,phit,Vx,P,omega] (SI, rad)")
    p.add_argument("--output", required=True, help="output CSV, or - for standard output")
    p.add_argument("--mode", type=int, default=111, help="MFeval useMode (default 111)")
    p.add_argument("--strict", action="store_true", help="reading warnings (blank/non-numeric values) are errors")
    p.set_defaults(func=_cmd_evaluate)

    p = sub.add_parser("convert", help="read a .tir and write it back (SI units)")
    p.add_argument("input", metavar="IN.tir")
    p.add_argument("output", metavar="OUT.tir")
    p.set_defaults(func=_cmd_convert)

    p = sub.add_parser("info", help="summarise a .tir")
    p.add_argument("tir", metavar="TIR")
    p.add_argument("--strict", action="store_true", help="reading warnings (blank/non-numeric values) are errors")
    p.set_defaults(func=_cmd_info)

    p = sub.add_parser("plot", help="draw the standard curves at 0.5, 1 and 1.5 x FNOMIN")
    p.add_argument("tir", metavar="TIR")
    p.add_argument("--output", required=True, help="PNG file")
    p.add_argument("--csv", help="also write the curve data to this CSV")
    p.add_argument("--mode", type=int, default=111)
    p.set_defaults(func=_cmd_plot)

    p = sub.add_parser(
        "demo", help="the whole loop on the shipped default data: FE and measured-like campaigns, fit, "
        "diagnosis, extended .tir, FMU, comparison with bands, HTML report",
    )
    p.add_argument("--output", default="demo_out", help="output directory (default demo_out)")
    p.add_argument("--quick", action="store_true", help="reduced grids (a test run)")
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
    from mftire.iotools import rig as rig_cli

    rig_cli.add_parser(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args) or 0)
    except MftireError as exc:
        print(f"mftire {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except OSError as exc:
        print(f"mftire {args.command}: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
