"""`mftire fe ...` sub-commands: sweep, campaign, identify.

All quantities on the command line are SI (N, m/s, Pa); ``--load-fraction`` and the
``km/h`` helpers are conveniences.  User errors raise MftireInputError (exit code 2).
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path
from typing import TYPE_CHECKING

from mftire.errors import MftireInputError

if TYPE_CHECKING:  # numpy and pandas are imported by the commands (fast ``mftire --help``)
    import pandas as pd


def _tyre(args: argparse.Namespace):
    from mftire.fe.config import load_tyre

    return load_tyre(args.tyre)


def _cmd_sweep(args: argparse.Namespace) -> int:
    from mftire.fe.slip_sweeps import sweep, write_csv_atomic
    from mftire.iotools.output import OutputPlan

    OutputPlan([args.tyre], args.force).file(args.output)
    tyre = _tyre(args)
    if args.Fz is None and args.load_fraction is None:
        raise MftireInputError("give --Fz [N] or --load-fraction")
    loads = list(args.Fz or []) + [f * tyre.load_index_load for f in (args.load_fraction or [])]
    speeds = list(args.Vx or []) + [v / 3.6 for v in (args.kmh or [])]
    if not speeds:
        raise MftireInputError("give --Vx [m/s] or --kmh")
    pressures = args.P if args.P else [tyre.size.nominal_pressure]
    table = sweep(tyre, args.kind, loads, speeds, pressures, gamma=math.radians(args.gamma_deg),
                  n_kappa=args.points, n_alpha=args.points)
    path = write_csv_atomic(table, args.output)
    print(f"wrote {len(table)} rows ({args.kind}) to {path}")
    return 0


def _cmd_campaign(args: argparse.Namespace) -> int:
    from mftire.fe.slip_sweeps import campaign, write_csv_atomic
    from mftire.iotools.output import OutputPlan
    from mftire.parallel import Executor

    OutputPlan([args.tyre], args.force).folder(args.output, ("sweeps.csv", "free_rolling.csv"))
    tyre = _tyre(args)
    out = Path(args.output)
    t0 = time.perf_counter()
    from mftire.cli_options import progress_of

    table, free = campaign(tyre, quick=args.quick, executor=Executor.from_args(args), progress=progress_of(args))
    write_csv_atomic(table, out / "sweeps.csv")
    write_csv_atomic(free, out / "free_rolling.csv")
    counts = table["kind"].value_counts().to_dict()
    print(f"wrote {out / 'sweeps.csv'} ({len(table)} rows: "
          + ", ".join(f"{k} {counts.get(k, 0)}" for k in ("braking", "cornering", "combined"))
          + f") and {out / 'free_rolling.csv'} ({len(free)} rows) in {time.perf_counter() - t0:.1f} s")
    return 0


def _read_tables(paths: list[str]) -> pd.DataFrame:
    import pandas as pd

    from mftire.iotools.loaders import read_numeric_csv

    df = pd.concat([read_numeric_csv(str(p), ()) for p in paths], ignore_index=True)
    for col in ("Fz", "kappa", "Vx", "Fx"):
        if col in df.columns and not pd.api.types.is_numeric_dtype(df[col]):
            raise MftireInputError(f"column {col!r} must be numeric")
    return df


def _cmd_identify(args: argparse.Namespace) -> int:
    from mftire.fe.friction_identify import identify_velocity_law
    from mftire.iotools.output import OutputPlan

    if args.output:
        OutputPlan([*args.data, args.tyre], args.force).file(args.output)
    data = _read_tables(args.data)
    tyre = _tyre(args) if args.mu_p is None else None
    Fz = args.Fz
    if Fz is None and args.load_fraction is not None:
        tyre = tyre or _tyre(args)
        Fz = args.load_fraction * tyre.load_index_load
    res = identify_velocity_law(data, tyre, Fz=Fz, P=args.P, kappa_max=args.kappa_max, mu_p=args.mu_p)
    text = res.to_json() if (args.output and args.output.endswith(".json")) else res.to_toml()
    if args.output:
        from mftire.iotools.atomic import write_text_atomic

        write_text_atomic(Path(args.output), text)
    print(text, end="")
    if args.output:
        print(f"# written to {args.output}", file=sys.stderr)
    return 0


def add_parser(subparsers: argparse._SubParsersAction) -> None:
    """Register ``fe`` with its sub-commands on the top-level parser."""
    fe = subparsers.add_parser("fe", help="FE-surrogate rolling-contact model (brush model, van der Steen friction)",
                               description="FE-surrogate steady-state rolling-contact model.")
    sub = fe.add_subparsers(dest="fe_command", required=True)
    from mftire.cli_options import add_force_option

    tyre_help = "tyre file (TOML) or 'default' (the shipped 205/55 R16 tyre)"

    s = sub.add_parser("sweep", help="run one kind of slip sweep",
                       description="Run one kind of slip sweep of the FE surrogate and write it as CSV.")
    s.add_argument("--tyre", default="default", help=tyre_help)
    s.add_argument("--kind", required=True, choices=["braking", "cornering", "combined"], help="kind of sweep")
    s.add_argument("--Fz", type=float, nargs="+", help="vertical load(s) [N]")
    s.add_argument("--load-fraction", type=float, nargs="+", help="load(s) as fraction of the load-index load")
    s.add_argument("--Vx", type=float, nargs="+", help="speed(s) [m/s]")
    s.add_argument("--kmh", type=float, nargs="+", help="speed(s) [km/h]")
    s.add_argument("--P", type=float, nargs="+", help="inflation pressure(s) [Pa] (default: nominal)")
    s.add_argument("--gamma-deg", type=float, default=0.0, help="camber [deg]")
    s.add_argument("--points", type=int, default=50, help="points per slip sweep (default 50)")
    s.add_argument("--output", required=True, help="output CSV (sweep-table schema)")
    add_force_option(s)
    s.set_defaults(func=_cmd_sweep)

    c = sub.add_parser("campaign", help="run the thesis's test programme (braking, cornering, combined)",
                       description="Run the thesis's test programme with the FE surrogate; write sweeps.csv and "
                       "free_rolling.csv into a folder.")  # fmt: skip
    c.add_argument("--tyre", default="default", help=tyre_help)
    c.add_argument("--output", required=True, help="output directory (sweeps.csv, free_rolling.csv)")
    c.add_argument("--quick", action="store_true", help="reduced grid (for tests)")
    from mftire.cli_options import add_parallel_options

    add_parallel_options(c, "the chunks of slip points")
    add_force_option(c)
    from mftire.cli_options import add_quiet_option

    add_quiet_option(c)
    c.set_defaults(func=_cmd_campaign)

    i = sub.add_parser("identify", help="identify the velocity part of the friction law from braking curves (ch. 5)",
                       description="Identify the velocity part of the friction law from braking curves at "
                       "several speeds (thesis ch. 5).")  # fmt: skip
    i.add_argument("data", nargs="+", help="braking sweep CSV file(s), several speeds, sweep-table schema")
    i.add_argument("--tyre", default="default", help=tyre_help + "; used to compute mu_p")
    i.add_argument("--Fz", type=float, help="identification load [N] (default: middle load in the data)")
    i.add_argument("--load-fraction", type=float, help="identification load as fraction of the load-index load")
    i.add_argument("--P", type=float, help="pressure for the mu_p simulation [Pa] (default: nominal)")
    i.add_argument("--kappa-max", type=float, default=0.05, help="kappa_max (default 0.05, thesis 5.4)")
    i.add_argument("--mu-p", type=float, help="global pressure factor mu_p (default: simulate with --tyre)")
    i.add_argument("--output", help="write the parameters to this .toml or .json file")
    add_force_option(i)
    i.set_defaults(func=_cmd_identify)

