"""``mftire import RAW --output SWEEPS.csv``: the command line of :mod:`mftire.segmentation.rig_segments`.

Kept apart from the importer so that registering the command (``mftire --help``) does
not load pandas.
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Sequence

from mftire.errors import MftireInputError


def _parse_signs(items: Sequence[str] | None) -> dict[str, float]:
    out: dict[str, float] = {}
    for raw in items or ():
        col, _, val = raw.partition("=")
        try:
            out[col.strip()] = float(val)
        except ValueError:
            raise MftireInputError(f"--sign {raw!r}: expected COLUMN=-1 or COLUMN=1") from None
    return out


def _cmd_import(args: argparse.Namespace) -> int:
    from mftire.iotools.atomic import write_text_atomic
    from mftire.iotools.rig import parse_map_options
    from mftire.segmentation.rig_segments import import_rig

    columns = parse_map_options(args.map or [])
    warm: str | float = args.warmup
    try:
        warm = float(warm)
    except ValueError:
        pass
    table, rep = import_rig(args.raw, args.format, output=args.output, columns=columns or None,
                            column_map=args.columns_map, convention=args.convention, signs=_parse_signs(args.sign),
                            points_per_sweep=args.points_per_sweep, warmup=warm)  # fmt: skip
    if args.report:
        write_text_atomic(args.report, json.dumps(rep.to_dict(), indent=1, default=float) + "\n")
    print(str(rep))
    left = len(table) - rep.n_points
    print(f"mftire import: wrote {args.output} ({rep.n_points} points in {rep.n_sweeps} sweeps, {left} rows outside "
          f"the sweeps kept with fit_row = False, {rep.seconds:.1f} s)", file=sys.stdout)
    return 0


def add_parser(subparsers: argparse._SubParsersAction) -> argparse.ArgumentParser:
    """Register ``import`` on the ``mftire`` sub-command parser."""
    p = subparsers.add_parser(
        "import",
        help="import a raw rig time series (TTC-style run file or mapped columns) as a sweep table",
        description="Read a continuous rig time series, convert units to SI and SAE J670 axes to ISO/TYDEX W, "
        "cut it into sweeps (steady load, pressure, inclination, speed; transitions and warm-up dropped and "
        "reported) and write the sweep CSV that mftire fit and mftire diagnose read.",
    )
    p.add_argument("raw", metavar="RAW", help="raw file (.gz accepted)")
    p.add_argument("--format", choices=("ttc", "columns"), default="ttc", help="input layout (default ttc)")
    p.add_argument("--output", required=True, metavar="SWEEPS.csv", help="sweep table (written atomically)")
    p.add_argument("--map", action="append", metavar="TARGET=SOURCE[:UNIT[:SIGN]]",
                   help="column map entry for --format columns, e.g. Fy=FY or Fz=LOAD:kN:-1 (repeatable)")
    p.add_argument("--columns-map", metavar="MAP.toml", help="column map file for --format columns")
    p.add_argument("--convention", choices=("sae", "iso"), default=None,
                   help="axis convention of the file: sae (converted to ISO W) or iso (taken unchanged); "
                   "default sae for ttc, the map's or iso for columns")
    p.add_argument("--sign", action="append", metavar="COLUMN=-1",
                   help="extra sign flip after the conversion, e.g. gamma=-1 (repeatable)")
    p.add_argument("--points-per-sweep", type=int, default=None, metavar="N",
                   help="down-sample every sweep to N binned means (default: keep every row)")
    p.add_argument("--warmup", default="auto", metavar="auto|none|SECONDS",
                   help="warm-up to drop: auto (first segment when its condition recurs), none, or seconds")
    p.add_argument("--report", metavar="REPORT.json", help="also write the import report as JSON")
    p.set_defaults(func=_cmd_import)
    return p
