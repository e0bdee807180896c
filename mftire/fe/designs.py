"""``mftire fe campaign --designs TABLE``: a design of experiments (tyre designs x programmes) on the local
pool or a Dask cluster (:mod:`mftire.parallel`); every table is written by the client."""

from __future__ import annotations

import os
import warnings
from typing import Any

from mftire.batch import write_files
from mftire.parallel import Executor, FilesTask, progress_printer

#: Columns of a design table that are not tyre parameters.
DESIGN_COLUMNS = ("design", "tyre", "programme")


def read_designs(path: str, quick: bool) -> list[tuple[str, Any, bool]]:
    """The runs of a design-of-experiments table (CSV): one row per run, ``design`` (its name, the output
    sub-folder), optional ``tyre`` (TOML file, relative to the table, or ``default``), optional ``programme``
    (``full`` or ``quick``: the thesis programme or its reduced grid; default from ``--quick``), and any
    other column a tyre parameter as ``section.key`` (``friction.mu_s``, ``grid.nx``) in the TOML's units.
    Returns ``(name, TyreConfig, quick)`` per row; every row is checked before any run."""
    import math

    import pandas as pd

    from mftire.errors import MftireInputError
    from mftire.fe.config import load_tyre, to_dict

    try:
        table = pd.read_csv(path, dtype={c: str for c in DESIGN_COLUMNS}, keep_default_na=False)
    except FileNotFoundError:
        raise MftireInputError(f"{path}: file not found") from None
    except (pd.errors.ParserError, pd.errors.EmptyDataError, UnicodeDecodeError) as exc:
        raise MftireInputError(f"{path}: not a readable CSV file ({exc})") from None
    table.columns = [str(c).strip() for c in table.columns]
    if "design" not in table.columns or table.empty:
        raise MftireInputError(f"{path}: a design table needs a 'design' column and one row per run")
    runs, seen = [], set()
    for i, row in table.iterrows():
        where = f"{path}: row {i + 1} (line {i + 2})"
        name = str(row["design"]).strip()
        if not name or name in seen or "/" in name or name.startswith("."):
            raise MftireInputError(f"{where}: design name {name!r} is empty, repeated or not a folder name")
        seen.add(name)
        src = str(row.get("tyre", "") or "default").strip()
        if src != "default" and not os.path.isabs(src):
            src = os.path.join(os.path.dirname(os.path.abspath(path)), src)
        base = load_tyre(src)
        prog = str(row.get("programme", "") or ("quick" if quick else "full")).strip().lower()
        if prog not in ("full", "quick"):
            raise MftireInputError(f"{where}: programme {prog!r} is not 'full' or 'quick'")
        current, changes = to_dict(base), {}
        for col in table.columns:
            if col in DESIGN_COLUMNS or row[col] == "" or (isinstance(row[col], float) and math.isnan(row[col])):
                continue
            section, _, key = col.partition(".")
            old = current.get(section, {}).get(key) if isinstance(current.get(section), dict) else None
            value = row[col]
            if isinstance(old, int) and not isinstance(old, bool) and float(value).is_integer():
                value = int(value)
            changes[col] = value
        try:
            tyre = base.updated(changes) if changes else base
        except MftireInputError as exc:
            raise MftireInputError(f"{where}: {exc}") from None
        runs.append((name, tyre, prog == "quick"))
    return runs


def _write_design(folder: str, name: str, table: Any, free: Any) -> None:
    from mftire.fe.slip_sweeps import write_csv_atomic

    write_csv_atomic(table, os.path.join(folder, name, "sweeps.csv"))
    write_csv_atomic(free, os.path.join(folder, name, "free_rolling.csv"))


def _campaign_task(run: tuple[str, Any, bool], folder: str) -> int:
    """One design's campaign in one task (the designs spread over the workers); the worker formats the CSV
    files too (into ``folder``, returned as bytes by :class:`~mftire.parallel.FilesTask`), the client only
    writes bytes.  Returns the rows of the sweep table."""
    from mftire.fe.slip_sweeps import campaign

    name, tyre, quick = run
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        table, free = campaign(tyre, quick=quick, progress=False)
    _write_design(folder, name, table, free)
    return len(table)


def run_designs(executor: Executor, runs: list[tuple[str, Any, bool]], output: str) -> list[str]:
    """Every run of a design table into ``output/<design>/`` (sweeps.csv, free_rolling.csv).  As many designs
    as workers or more: one task per design; fewer: the designs one after the other, each campaign's
    chunks of points spread over every worker.  The files are the same either way (byte for byte)."""
    from mftire.fe.slip_sweeps import campaign
    from mftire.iotools.atomic import staged_folder

    lines = []
    with executor.session() as ex, staged_folder(output) as stage:
        if len(runs) >= ex.workers:
            for (name, _tyre, quick), (rows, files) in zip(runs, ex.stream(
                    FilesTask(_campaign_task), runs, labels=lambda r: f"design {r[0]}", total=len(runs),
                    progress=progress_printer("mftire fe", "designs done")), strict=True):  # fmt: skip
                write_files(stage, files)
                lines.append(f"{name}/: {rows} rows{' (quick)' if quick else ''}")
        else:
            for name, tyre, quick in runs:
                table, free = campaign(tyre, quick=quick, progress=False, executor=ex)
                _write_design(stage, name, table, free)
                lines.append(f"{name}/: {len(table)} rows{' (quick)' if quick else ''}")
    return lines
