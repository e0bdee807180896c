"""``mftire evaluate --chunk-rows N``: a large table streamed in chunks that keep their neighbour rows, on the
local pool or a Dask cluster (:mod:`mftire.parallel`), within bounded memory; the client writes the CSV."""

from __future__ import annotations

import warnings
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from typing import Any

from mftire.parallel import Executor, progress_printer

#: Rows per chunk when ``--chunk-rows`` is not given (≈ 60 MB of output text per chunk, 2.5 s of a worker's
#: time: benchmarks/bench_dask.py), and the input size from which a local run streams by default.
DEFAULT_CHUNK_ROWS = 100_000
STREAM_FROM_BYTES = 64 * 1024 * 1024


def chunk_rows(given: int | None, path: str, cluster: bool) -> int:
    """Rows per chunk for ``evaluate``: ``given`` (0: the whole table), or by default
    :data:`DEFAULT_CHUNK_ROWS` on a cluster or for an input file larger than :data:`STREAM_FROM_BYTES`, else 0.
    Standard input is always read whole."""
    import os

    from mftire.errors import MftireInputError

    if given is not None and given < 0:
        raise MftireInputError(f"--chunk-rows must be >= 0 (0: the whole table), got {given}")
    if path == "-":
        return 0
    if given is not None:
        return given
    try:
        big = os.path.getsize(path) > STREAM_FROM_BYTES
    except OSError:
        big = False  # a missing file is reported by the reader
    return DEFAULT_CHUNK_ROWS if cluster or big else 0


@dataclass(frozen=True)
class EvaluateChunk:
    """``mftire evaluate`` of one chunk of rows: the rows ``keep`` of ``frame`` as CSV text (the header with the
    first chunk).  ``frame`` holds one row before and one after the chunk where the table has them: the
    instantaneous cornering stiffness ``instKya`` is a difference of neighbouring rows (mftire.mf.solver), so a
    chunk's rows get exactly the values of the whole table.  Warnings come back as text."""

    parameters: Any  #: TirParameters
    mode: int
    name: str
    columns: Callable[[Any, int], Any]  #: the output columns from (inputs + outputs, number of inputs): the CLI's

    def __call__(self, item: tuple) -> tuple[bytes, list[str]]:
        import pandas as pd

        from mftire.tyre import Tyre

        frame, lo, hi, header = item
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            out = Tyre(self.parameters).evaluate_frame(frame, mode=self.mode, name=self.name)
        result = pd.concat([frame, out], axis=1).iloc[lo:hi]
        text = self.columns(result, len(frame.columns)).to_csv(index=False, header=header)
        return text.encode(), list(dict.fromkeys(str(w.message) for w in caught))


def evaluate_chunks(path: str, rows: int, required: Sequence[str], optional: Sequence[str]) -> Iterator[tuple]:
    """The table of ``path`` read ``rows`` rows at a time, checked as :func:`read_numeric_csv` checks the whole
    table, each chunk with its neighbour rows: ``(frame, lo, hi, header)`` for :class:`EvaluateChunk`."""
    import pandas as pd

    from mftire.errors import MftireInputError
    from mftire.iotools.loaders import check_numeric_columns

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
                      required: Sequence[str], optional: Sequence[str],
                      columns: Callable[[Any, int], Any]) -> int:
    """Evaluate the table of ``path`` in chunks of ``rows`` rows on ``executor`` (at most twice as many chunks
    as workers in memory) and write the CSV to ``output`` (atomically, or through ``-``/a device); returns the
    rows written.  ``columns`` names the output columns (:func:`mftire.cli.evaluate_columns`)."""
    import sys

    from mftire.iotools.atomic import atomic_path

    task = EvaluateChunk(parameters, mode, path, columns)
    seen: dict[str, None] = {}
    n = 0

    def write(fh: Any) -> None:
        nonlocal n
        show = progress_printer("mftire evaluate", "rows written")
        for text, warned in executor.stream(task, evaluate_chunks(path, rows, required, optional),
                                            labels=lambda x: f"{path}: a chunk of {x[2] - x[1]} rows"):  # fmt: skip
            fh.write(text)
            n += text.count(b"\n")
            show(n - 1, 0)  # rows so far (the header line is not a row)
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
