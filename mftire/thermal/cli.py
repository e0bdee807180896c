"""``mftire fit-thermal`` and ``mftire replay``: the command line of :mod:`mftire.thermal`."""

from __future__ import annotations

import argparse
import inspect
import json
import os
import sys

from mftire.errors import MftireInputError


def _add_command(subparsers: argparse._SubParsersAction, name: str, func, tir: tuple[str, str],
                 output: tuple[str, str]) -> argparse.ArgumentParser:  # fmt: skip
    """A sub-command on a rig series: the data options, ``--tir`` and ``--output`` (each: metavar, help),
    ``--force``.  Its help is the first line of ``func``'s docstring, its description the rest."""
    from mftire.cli_options import add_force_option

    summary, _, rest = inspect.cleandoc(func.__doc__).partition("\n\n")
    p = subparsers.add_parser(name, help=summary, description=" ".join(rest.split()))
    _add_data_options(p)
    p.add_argument("--tir", required=True, metavar=tir[0], help=tir[1])
    p.add_argument("--output", required=True, metavar=output[0], help=output[1])
    add_force_option(p)
    p.set_defaults(func=func)
    return p


def _add_data_options(p: argparse.ArgumentParser) -> None:
    p.add_argument("data", metavar="DATA", help="raw rig file (.gz accepted) or an imported series CSV")
    p.add_argument("--format", default=None,  # checked by mftire.thermal.series.read_series (no pandas at start-up)
                   help="ttc or columns: a raw file as mftire import reads it; series: the continuous CSV mftire "
                   "import writes (default: series for .csv, else ttc)")  # fmt: skip
    p.add_argument("--map", action="append", metavar="TARGET=SOURCE[:UNIT[:SIGN]]",
                   help="column map entry for --format columns (repeatable)")
    p.add_argument("--columns-map", metavar="MAP.toml", help="column map file for --format columns")
    p.add_argument("--convention", choices=("sae", "iso"), default=None,
                   help="axis convention of a raw file (default sae for ttc, the map's or iso for columns)")


def _read(args: argparse.Namespace):
    from mftire.iotools.rig import parse_map_options
    from mftire.thermal.series import read_series

    return read_series(args.data, args.format, columns=parse_map_options(args.map or []) or None,
                       column_map=args.columns_map, convention=args.convention)  # fmt: skip


def _side_path(output: str, suffix: str) -> str:
    stem, _ = os.path.splitext(output)
    return stem + suffix


def _cmd_fit_thermal(args: argparse.Namespace) -> int:
    """fit the thermal tyre (three nodes, gas law, temperature laws) to a rig series

    Fit the thermal parameters of [MFTIRE_THERMAL] and the temperature laws of a fitted .tir to a continuous rig
    series (measured surface temperatures compared with the surface node, the pressure with the gas law); each
    law reads the node with the lower held-out error. Writes the .tir, a figure of measured against predicted
    temperature and pressure, and prints every parameter with its standard error.
    """
    from mftire.iotools.output import OutputPlan

    plot = args.plot or _side_path(args.output, "_temperature.png")
    plan = OutputPlan([args.data, args.tir, args.columns_map], args.force)
    plan.file(args.output)
    plan.file(plot, figure=True)
    if args.report:
        plan.file(args.report)
    if args.fit_until is not None and not args.fit_until > 0:
        raise MftireInputError(f"--fit-until {args.fit_until!r}: must be a time > 0 s")
    from mftire.iotools.atomic import write_text_atomic
    from mftire.iotools.tir import write_tir
    from mftire.thermal.thermal_fit import fit_thermal
    from mftire.tyre import load

    tyre = load(args.tir)
    df = _read(args)
    res = fit_thermal(tyre, df, fit_until=args.fit_until, name=args.data, sealed=args.pressure == "sealed")
    write_tir(res.tir, args.output)
    _plot_fit(res, plot)
    if args.report:
        doc = {"fit_until": res.fit_until,
               "parameters": {k: {"value": getattr(res.thermal.params, k), "sigma": res.thermal.sigma.get(k)}
                              for k in res.thermal.sigma},
               "rms_surface_K": res.thermal.rms_surface, "rms_pressure_Pa": res.thermal.rms_pressure,
               "laws": [{"index": c.index, "law": c.description, "node": c.node, "heldout": c.heldout}
                        for c in res.laws],
               "law_sigma": res.law_sigma, "rms_forces_N": res.rms_forces}  # fmt: skip
        write_text_atomic(args.report, json.dumps(doc, indent=1, default=float) + "\n")
    print(res.summary())
    print(f"mftire fit-thermal: wrote {args.output} and {plot}")
    return 0


def _plot_fit(res, path: str) -> None:
    from mftire.iotools.atomic import atomic_path
    from mftire.iotools.output import figure_format
    from mftire.plotting import subplots

    pred = res.thermal.prediction
    fig, axes = subplots(2, 1, figsize=(9, 7), sharex=True, constrained_layout=True)
    ax = axes[0]
    ax.plot(pred["ET"], pred["T_measured"], ".", ms=2, color="0.4", label="measured (mean of TSTI/TSTC/TSTO)")
    ax.plot(pred["ET"], pred["T_surface"], "-", lw=1.2, label="surface node")
    ax.plot(pred["ET"], pred["T_bulk"], "--", lw=1.0, label="bulk node")
    ax.plot(pred["ET"], pred["T_gas"], ":", lw=1.0, label="gas node")
    ax.set_ylabel("temperature [°C]")
    ax.set_title(f"thermal fit: surface RMS {res.thermal.rms_surface:.2f} K")
    ax.legend(fontsize=8)
    ax = axes[1]
    if "P_measured" in pred.columns:
        ax.plot(pred["ET"], pred["P_measured"] / 1e3, ".", ms=2, color="0.4", label="measured")
        ax.plot(pred["ET"], pred["P_model"] / 1e3, "-", lw=1.2, label="gas law of the gas node")
        ax.set_ylabel("pressure [kPa]")
        ax.legend(fontsize=8)
    ax.set_xlabel("ET [s]")
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=100, format=figure_format(path))


def _cmd_replay(args: argparse.Namespace) -> int:
    """run a .tir (thermal or not) along a measured series given only kinematics and conditions

    Run the model along a measured series (ET, Fz, Vx, slips, inclination, ambient and road temperature; cold
    pressure: P_cold column, TH_COLD_PRESSURE or the first P sample) and write the node temperatures, the
    pressure and Fx_model, Fy_model, ... next to the measured columns, keyed by ET. A .tir without
    [MFTIRE_THERMAL] replays isothermally at the cold pressure.
    """
    from mftire.iotools.output import OutputPlan

    OutputPlan([args.data, args.tir, args.columns_map], args.force).file(args.output, stdout=True)
    import numpy as np

    from mftire.iotools.atomic import atomic_path
    from mftire.thermal.simulation import replay
    from mftire.tyre import load

    tyre = load(args.tir)
    df = _read(args)
    res = replay(tyre, df, name=args.data)
    table = res.table
    if args.output == "-":
        table.to_csv(sys.stdout, index=False)
    else:
        with atomic_path(args.output) as tmp:
            table.to_csv(tmp, index=False)
    what = f"thermal, coupling converged in {res.iterations} iterations" if res.thermal else \
        "isothermal (the .tir has no [MFTIRE_THERMAL] section)"
    lines = [f"mftire replay: {len(table)} rows, {what}"]
    for ch in ("Fx", "Fy", "Mz"):
        if ch in table.columns:
            lines.append(f"  {ch} RMS error {np.sqrt(np.mean((table[ch + '_model'] - table[ch]) ** 2)):.1f}")
    ir = [c for c in ("TSTI", "TSTC", "TSTO") if c in table.columns]
    if res.thermal and ir:
        d = table["T_surface"] - table[ir].mean(axis=1)
        lines.append(f"  surface temperature RMS error {np.sqrt(np.nanmean(d ** 2)):.2f} K")
    print("\n".join(lines), file=sys.stderr if args.output == "-" else sys.stdout)
    return 0


def add_parser(subparsers: argparse._SubParsersAction) -> None:
    """Register ``fit-thermal`` and ``replay`` on the ``mftire`` sub-command parser."""
    p = _add_command(subparsers, "fit-thermal", _cmd_fit_thermal, ("FIT.tir", "the fitted (isothermal) .tir"),
                     ("THERMAL.tir", "the .tir to write"))
    p.add_argument("--fit-until", type=float, default=None, metavar="SECONDS",
                   help="fit on the rows with ET <= SECONDS (default: all), leaving the rest to a replay")
    p.add_argument("--pressure", choices=("sealed", "regulated"), default="sealed",
                   help="sealed (default): the measured P follows the gas law and identifies the gas node; "
                   "regulated: the rig holds the pressure, P is not fitted and the replay uses the cold pressure")
    p.add_argument("--plot", metavar="FIG.png", help="figure (default: OUTPUT stem + _temperature.png)")
    p.add_argument("--report", metavar="REPORT.json", help="also write the results as JSON")

    _add_command(subparsers, "replay", _cmd_replay, ("THERMAL.tir", "the .tir to replay"),
                 ("REPLAY.csv", "output CSV, or - for standard output"))
