"""Issue 27, properties of the chunking (no cluster needed): how work is cut, and that a table streamed in
chunks gives the whole table's output byte for byte, instKya (a difference of neighbouring rows) included."""

from __future__ import annotations

import warnings

import numpy as np
import pandas as pd
import pytest
from conftest import REFERENCE_TYRES
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from mftire.cli import EVALUATE_OPTIONAL, EVALUATE_REQUIRED, evaluate_columns
from mftire.errors import MftireInputError
from mftire.iotools.tir import read_tir
from mftire.parallel import batch_names, chunk_count, expand_inputs
from mftire.streaming import EvaluateChunk, evaluate_chunks
from mftire.tyre import Tyre

PARAMS = read_tir(REFERENCE_TYRES["MF61"])


@given(n=st.integers(0, 10**6), workers=st.integers(1, 200), cost=st.floats(1e-6, 10.0),
       target=st.floats(0.5, 60.0))  # fmt: skip
def test_chunk_count_follows_the_workers_and_the_target_duration(n, workers, cost, target):
    k = chunk_count(n, workers, cost, target)
    assert 1 <= k <= max(1, n)
    assert k % workers == 0 or k == max(n, 1)  # the workers finish together (unless there are fewer items)
    assert k >= min(n, workers)  # every worker gets work
    size = -(-n // k) if n else 0
    assert size * cost <= target * (1 + 1e-9) or size == 1  # each chunk the target or less (or one item)


def _table(n: int, seed: int) -> pd.DataFrame:
    rng = np.random.default_rng(seed)
    return pd.DataFrame({"Fz": rng.uniform(2000, 6000, n), "kappa": rng.uniform(-0.2, 0.2, n),
                         "alpha": np.sort(rng.uniform(-0.2, 0.2, n)), "gamma": 0.0, "note": rng.integers(0, 3, n)})


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(n=st.integers(1, 40), rows=st.integers(1, 45), seed=st.integers(0, 2**16))
def test_streamed_chunks_give_the_whole_table_byte_for_byte(tmp_path, n, rows, seed):
    path = tmp_path / "t.csv"
    _table(n, seed).to_csv(path, index=False)
    required = (*EVALUATE_REQUIRED,)
    whole = pd.read_csv(path)
    whole[list(required)] = whole[list(required)].astype(float)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        out = pd.concat([whole, Tyre(PARAMS).evaluate_frame(whole)], axis=1)
        expected = evaluate_columns(out, len(whole.columns)).to_csv(index=False).encode()
        task = EvaluateChunk(PARAMS, 111, str(path), evaluate_columns)
        chunks = list(evaluate_chunks(str(path), rows, required, EVALUATE_OPTIONAL))
        got = b"".join(task(c)[0] for c in chunks)
    assert got == expected
    assert len(chunks) == -(-n // rows)
    for frame, lo, hi, _ in chunks:  # each chunk carries the row before and the row after where there are such
        assert lo == (0 if frame is chunks[0][0] else 1) and len(frame) - hi in (0, 1)


def test_streamed_chunks_name_the_bad_cell_by_its_row_in_the_file(tmp_path):
    path = tmp_path / "t.csv"
    df = _table(10, 0)
    df["kappa"] = df["kappa"].astype(object)
    df.loc[7, "kappa"] = "x"
    df.to_csv(path, index=False)
    with pytest.raises(MftireInputError, match=r"column 'kappa', row 8 \(line 9\)"):
        list(evaluate_chunks(str(path), 3, EVALUATE_REQUIRED, EVALUATE_OPTIONAL))


def test_batch_inputs_globs_and_names(tmp_path):
    for name in ("b.csv", "a.csv.gz", "c.tdx"):
        (tmp_path / name).write_text("x")
    paths = expand_inputs([str(tmp_path / "*.csv*"), str(tmp_path / "c.tdx")])
    assert [p.rsplit("/", 1)[1] for p in paths] == ["a.csv.gz", "b.csv", "c.tdx"]
    assert batch_names(paths) == ["a", "b", "c"]
    with pytest.raises(MftireInputError, match="no file matches"):
        expand_inputs([str(tmp_path / "*.json")])
    with pytest.raises(MftireInputError, match="same output name 'b'"):
        batch_names([str(tmp_path / "b.csv"), str(tmp_path / "sub" / "b.tdx")])


def test_files_task_returns_the_files_and_write_files_writes_them(tmp_path):
    from mftire.batch import write_files
    from mftire.parallel import FilesTask

    def make(item, folder):
        import os

        os.makedirs(os.path.join(folder, "sub"))
        with open(os.path.join(folder, "sub", "x.bin"), "wb") as fh:
            fh.write(bytes([item]))
        return item * 2

    result, files = FilesTask(make)(7)
    assert result == 14 and files == {"sub/x.bin": b"\x07"}
    write_files(tmp_path / "out", files)
    assert (tmp_path / "out" / "sub" / "x.bin").read_bytes() == b"\x07"
    with pytest.raises(MftireInputError, match="outside its folder"):
        write_files(tmp_path / "out", {"../escape": b""})


def test_progress_of_tasks_goes_through_the_one_reporter(capsys):
    from mftire.parallel import progress_printer

    show = progress_printer("mftire fit", "fits done", enabled=True)
    for i in (1, 2, 3):
        show(i, 3)
    err = capsys.readouterr().err.splitlines()
    assert [e.split("] ", 1)[1] for e in err] == [f"mftire fit: {i}/3 fits done" for i in (1, 2, 3)]
    progress_printer("mftire fit", "fits done")(1, 3)  # not a terminal: quiet
    assert capsys.readouterr().err == ""
