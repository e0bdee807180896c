"""Batch commands: many inputs, one task each, on local processes or a Dask cluster (:mod:`mftire.parallel`).

``mftire fit --each``, ``mftire diagnose --each``: every input file is one task.  The client reads each file
and sends its bytes (the workers need no shared folder); the worker writes the input into a scratch folder,
runs the command's own library function and writes its outputs there; the files come back as bytes
(:class:`mftire.parallel.FilesTask`) and the client writes them into a staging folder beside the output
folder, published when every task is done (:func:`mftire.iotools.atomic.staged_folder`): a failed batch
writes nothing.  At most twice as many tasks as workers are in flight (:meth:`Executor.stream`), so the
client's memory does not grow with the number of inputs.
"""

from __future__ import annotations

import os
import tempfile
import warnings
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from typing import Any

from mftire.parallel import Executor, FilesTask, progress_printer, write_files


@dataclass(frozen=True)
class InputFile:
    """One input of a batch: its output name, its file name and its bytes."""

    name: str
    filename: str
    data: bytes


def read_inputs(paths: Sequence[str], names: Sequence[str]) -> Iterator[InputFile]:
    """The inputs, each read when its task is sent."""
    for path, name in zip(paths, names, strict=True):
        with open(path, "rb") as fh:
            yield InputFile(name, os.path.basename(path), fh.read())


def _local_copy(item: InputFile, folder: str) -> str:
    path = os.path.join(folder, item.filename)
    with open(path, "wb") as fh:
        fh.write(item.data)
    return path


@dataclass(frozen=True)
class FitFile:
    """``mftire fit`` of one input file: ``<name>.tir`` (and the report in ``<name>/`` with ``report``)."""

    template: Any  #: TirParameters
    stages: str | None
    weights: str | None
    alpha_star: bool
    fixed: tuple[str, ...]
    report: bool

    def __call__(self, item: InputFile, folder: str) -> list[str]:
        from mftire.errors import MftireInputError
        from mftire.fitting.core import fit_tir
        from mftire.iotools.tir import write_tir

        with tempfile.TemporaryDirectory(prefix="mftire-in-") as tmp, warnings.catch_warnings():
            warnings.simplefilter("ignore")
            result = fit_tir([_local_copy(item, tmp)], self.template, stages=self.stages, weights=self.weights,
                             alpha_star=self.alpha_star, fixed=list(self.fixed), progress=False)
        data = result.data
        if not any(s.status == "fitted" or (s.channel in data.columns and data[s.channel].notna().any())
                   for s in result.stages):
            raise MftireInputError("no stage could be fitted (no force or moment channel with data)")
        write_tir(result.parameters, os.path.join(folder, item.name + ".tir"))
        if self.report:
            from mftire.fitting.report import write_report

            write_report(result, os.path.join(folder, item.name))
        rms = ", ".join(f"{s.channel} {s.rms:.4g}" for s in result.stages if s.status == "fitted")
        return [f"{item.name}.tir: {len(dict.fromkeys(result.identified))} coefficients fitted ({rms})"]


@dataclass(frozen=True)
class DiagnoseFile:
    """``mftire diagnose`` of one input file into ``<name>/``; the fitted tyre is ``tyres[name]`` or ``tyre``."""

    tyres: dict  #: output name -> TirParameters (a folder of fitted .tir files), or {} for ``tyre``
    tyre: Any
    holdout: Any
    n_perm: int
    seed: int

    def __call__(self, item: InputFile, folder: str) -> list[str]:
        from mftire.diagnosis.diagnose import diagnose
        from mftire.diagnosis.report import write_report
        from mftire.iotools.tables import load_sweep_files
        from mftire.tyre import Tyre

        tyre = Tyre(self.tyres[item.name] if self.tyres else self.tyre)
        with tempfile.TemporaryDirectory(prefix="mftire-in-") as tmp, warnings.catch_warnings():
            warnings.simplefilter("ignore")
            data, _ = load_sweep_files([_local_copy(item, tmp)])
            result = diagnose(data, tyre, self.holdout, n_perm=self.n_perm, seed=self.seed, progress=False)
            doc = write_report(result, os.path.join(folder, item.name))
        return [f"{item.name}/: {doc['summary'].splitlines()[0] if doc.get('summary') else ''}"]


def run_batch(executor: Executor, task: Callable[[InputFile, str], list[str]], paths: Sequence[str],
              names: Sequence[str], output: str, command: str, what: str) -> list[str]:
    """Run ``task`` on every input (in parallel), write every output into ``output``; returns the lines of the
    tasks, in the order of the inputs."""
    from mftire.iotools.atomic import staged_folder

    lines: list[str] = []
    with staged_folder(output) as stage:
        for result, files in executor.stream(FilesTask(task), read_inputs(paths, names), labels=lambda x: x.filename,
                                             progress=progress_printer(f"mftire {command}", what), total=len(paths)):
            write_files(stage, files)
            lines.extend(result)
    return lines


# ---------------------------------------------------------------------------------------- streamed evaluate


@dataclass(frozen=True)
class EvaluateChunk:
    """``mftire evaluate`` of one chunk of rows: the rows ``keep`` of ``frame`` as CSV text (the header with the
    first chunk).  ``frame`` holds one row before and one after the chunk where the table has them: the
    instantaneous cornering stiffness ``instKya`` is a difference of neighbouring rows (mftire.mf.solver), so a
    chunk's rows get exactly the values of the whole table.  Warnings come back as text."""

    parameters: Any  #: TirParameters
    mode: int
    name: str

    def __call__(self, item: tuple) -> tuple[bytes, list[str]]:
        import pandas as pd

        from mftire.cli import evaluate_columns
        from mftire.tyre import Tyre

        frame, lo, hi, header = item
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            out = Tyre(self.parameters).evaluate_frame(frame, mode=self.mode, name=self.name)
        result = pd.concat([frame, out], axis=1).iloc[lo:hi]
        text = evaluate_columns(result, len(frame.columns)).to_csv(index=False, header=header)
        return text.encode(), list(dict.fromkeys(str(w.message) for w in caught))


def evaluate_chunks(path: str, rows: int, required: Sequence[str], optional: Sequence[str]) -> Iterator[tuple]:
    """The table of ``path`` read ``rows`` rows at a time, checked as :func:`read_numeric_csv` checks the whole
    table, each chunk with its neighbour rows: ``(frame, lo, hi, header)`` for :class:`EvaluateChunk`."""
    import pandas as pd

    from mftire.errors import MftireInputError
    from mftire.iotools.tables import check_numeric_columns

    try:
        reader = pd.read_csv(path, chunksize=max(1, rows))
        prev_last, row0 = None, 0
        cur = next(reader, None)
        if cur is None:
            raise MftireInputError(f"{path}: no data rows")
        cur = check_numeric_columns(cur, path, required, optional, first_row=0)
        while cur is not None:
            nxt = next(reader, None)
            if nxt is not None:
                nxt = check_numeric_columns(nxt, path, required, optional, first_row=row0 + len(cur))
            parts = [p for p in (prev_last, cur, None if nxt is None else nxt.iloc[:1]) if p is not None]
            frame = pd.concat(parts, ignore_index=True) if len(parts) > 1 else cur.reset_index(drop=True)
            lo = 0 if prev_last is None else 1
            yield frame, lo, lo + len(cur), row0 == 0
            prev_last, row0, cur = cur.iloc[-1:], row0 + len(cur), nxt
    except FileNotFoundError:
        raise MftireInputError(f"{path}: file not found") from None
    except (pd.errors.ParserError, pd.errors.EmptyDataError, UnicodeDecodeError) as exc:
        raise MftireInputError(f"{path}: not a readable CSV file ({exc})") from None


def evaluate_streamed(executor: Executor, parameters: Any, path: str, output: str, rows: int, mode: int,
                      required: Sequence[str], optional: Sequence[str]) -> int:
    """Evaluate the table of ``path`` in chunks of ``rows`` rows on ``executor`` (at most twice as many chunks
    as workers in memory) and write the CSV to ``output`` (atomically, or through ``-``/a device); the rows."""
    import sys

    from mftire.iotools.atomic import atomic_path

    task = EvaluateChunk(parameters, mode, path)
    seen: dict[str, None] = {}
    n = 0

    def write(fh: Any) -> None:
        nonlocal n
        for text, warned in executor.stream(task, evaluate_chunks(path, rows, required, optional),
                                            labels=lambda x: f"{path}: rows from {x[1]}"):  # fmt: skip
            fh.write(text)
            n += text.count(b"\n")
            for w in warned:
                if w not in seen:
                    seen[w] = None
                    warnings.warn(w, stacklevel=2)

    if output == "-":
        write(sys.stdout.buffer)
        sys.stdout.buffer.flush()
    else:
        with atomic_path(output) as tmp, open(tmp, "wb") as fh:
            write(fh)
    return n


# ------------------------------------------------------------------------------------ FE design of experiments

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


def _campaign_task(run: tuple[str, Any, bool]) -> tuple[Any, Any]:
    """One design's campaign in one task (the designs spread over the workers)."""
    from mftire.fe.sweeps import campaign

    _name, tyre, quick = run
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return campaign(tyre, quick=quick, progress=False)


def run_designs(executor: Executor, runs: list[tuple[str, Any, bool]], output: str) -> list[str]:
    """Every run of a design table into ``output/<design>/`` (sweeps.csv, free_rolling.csv).  As many designs
    as workers or more: one task per design; fewer: the designs one after the other, each campaign's
    chunks of points spread over every worker.  The tables are the same either way (bit for bit)."""
    from mftire.fe.sweeps import campaign, write_csv_atomic
    from mftire.iotools.atomic import staged_folder

    lines = []
    with executor.session() as ex, staged_folder(output) as stage:
        if len(runs) >= ex.workers:
            results = ex.stream(_campaign_task, runs, labels=lambda r: f"design {r[0]}", total=len(runs),
                                progress=progress_printer("mftire fe", "designs done"))
        else:
            results = (campaign(t, quick=q, progress=False, executor=ex) for _n, t, q in runs)
        for (name, _tyre, quick), (table, free) in zip(runs, results, strict=True):
            write_csv_atomic(table, os.path.join(stage, name, "sweeps.csv"))
            write_csv_atomic(free, os.path.join(stage, name, "free_rolling.csv"))
            lines.append(f"{name}/: {len(table)} rows{' (quick)' if quick else ''}")
    return lines
