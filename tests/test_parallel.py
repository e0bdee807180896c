"""One executor (mftire.parallel): local processes and a Dask cluster give the serial result bit for bit."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest
from conftest import REFERENCE_TYRES

from mftire.errors import MftireInputError
from mftire.fe.config import load_tyre
from mftire.fe.measured import Artefacts, measured_campaign
from mftire.fe.slip_sweeps import KMH, Condition, run_sweeps
from mftire.fitting.bands import bootstrap_bands
from mftire.fitting.fitter import fit_tir
from mftire.fitting.synthetic import synthetic_sweeps
from mftire.iotools.tir import read_tir
from mftire.parallel import Executor, available_cores
from mftire.parameters import with_defaults

TIR = REFERENCE_TYRES["MF61"]
FE_TYRE = load_tyre(None).updated({"grid.nx": 12, "grid.ny": 5})  # coarse: the test is about the executor


def _fe(executor: Executor):
    """A small FE campaign cut into 4 chunks of 7 points."""
    li, pn = FE_TYRE.load_index_load, FE_TYRE.size.nominal_pressure
    jobs = [("braking", Condition(0.8 * li, 60 * KMH, pn)), ("cornering", Condition(0.4 * li, 20 * KMH, pn + 0.5e5))]
    return run_sweeps(FE_TYRE, jobs, n_kappa=14, n_alpha=13, chunk=7, progress=False, executor=executor)


@pytest.fixture(scope="module")
def fe_serial():
    return _fe(Executor(jobs=1))


@pytest.fixture(scope="module")
def fit():
    tyre = read_tir(TIR)
    f0 = with_defaults(tyre)["FNOMIN"]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        df = synthetic_sweeps(tyre, [0.5 * f0, f0], np.radians([0.0]), n_kappa=15, n_alpha=11, n_combined=5,
                              noise=0.02, seed=4, channels=("Fx", "Fy"))
        return fit_tir(df.assign(source="rig"), TIR, stages="1", progress=False)


def _bands(fit, executor: Executor):
    grid = fit.data[["Fz", "kappa", "alpha", "gamma", "Vx", "P"]].iloc[::4].reset_index(drop=True)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return bootstrap_bands(None, TIR, n=3, fit=fit, stages="1", seed=7, grid=grid, executor=executor)


@pytest.fixture(scope="module")
def bands_serial(fit):
    return _bands(fit, Executor(jobs=1))


def _same_bands(a, b) -> None:
    assert len(a.replicates) == len(b.replicates) == 3
    for ra, rb in zip(a.replicates, b.replicates, strict=True):
        va = np.array([ra.get(k) for k in a.keys], dtype=float)
        vb = np.array([rb.get(k) for k in b.keys], dtype=float)
        assert va.tobytes() == vb.tobytes()  # bit for bit
    assert a.grid.equals(b.grid)


def test_executor_options_and_errors():
    assert Executor().workers == 1 and Executor().describe() == "this process"
    assert Executor(jobs=0).workers == available_cores() == Executor(jobs=None).workers
    assert Executor(jobs=3).describe() == "3 local processes"
    assert Executor(scheduler="tcp://h:1").describe() == "Dask scheduler tcp://h:1"
    with pytest.raises(MftireInputError, match="--jobs"):
        Executor(jobs=-1)
    with pytest.raises(MftireInputError, match="--scheduler"):
        Executor(scheduler=" ")
    # results come back in the order of the items, whatever order the workers finish in
    assert Executor(jobs=2).map(abs, [-3, 2, -1, 0]) == [3, 2, 1, 0]


def test_fe_chunks_on_process_pool_match_serial_bit_for_bit(fe_serial):
    table, free = _fe(Executor(jobs=2))
    assert len(table) == 14 + 13 and len(free) == 2
    assert table.equals(fe_serial[0]) and free.equals(fe_serial[1])
    assert np.abs(table["Fx"]).max() > 1000.0  # real forces, not zeros


def test_measured_campaign_on_process_pool_matches_serial_bit_for_bit():
    li, pn = FE_TYRE.load_index_load, FE_TYRE.size.nominal_pressure
    jobs = [("braking", Condition(0.8 * li, 60 * KMH, pn)), ("cornering", Condition(0.8 * li, 60 * KMH, pn)),
            ("braking", Condition(0.4 * li, 20 * KMH, pn))]

    def run(ex):
        return measured_campaign(FE_TYRE, jobs, Artefacts(noise=0.01), n_kappa=9, n_alpha=9, seed=3, executor=ex)

    serial, pooled = run(Executor(jobs=1)), run(Executor(jobs=2))
    assert len(serial) == 27 and serial.equals(pooled)
    assert serial["run"].tolist() == [0] * 9 + [1] * 9 + [2] * 9


def test_bootstrap_on_process_pool_matches_serial_bit_for_bit(fit, bands_serial):
    serial = bands_serial
    _same_bands(serial, _bands(fit, Executor(jobs=2)))
    # the replicates differ from each other (a resampling that did nothing would pass the above)
    assert len({r.get(serial.keys[0]) for r in serial.replicates}) >= 2


def test_dask_local_cluster_matches_serial_bit_for_bit(fe_serial, fit, bands_serial):
    distributed = pytest.importorskip("distributed", reason="Dask distributed not installed (pip install "
                                      "'mftire[dask]'); the Dask path of mftire.parallel is not tested")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the cluster's own start-up chatter
        with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=False,
                                      dashboard_address=None) as cluster:
            ex = Executor(scheduler=cluster.scheduler_address)
            table, free = _fe(ex)
            bands = _bands(fit, ex)
            with ex.session() as open_ex:  # one client for several batches, one started ahead
                pending = open_ex.start_map(abs, [-2, 3])
                table2, _ = _fe(open_ex)
                assert pending.result() == [2, 3]
    assert table.equals(fe_serial[0]) and free.equals(fe_serial[1]) and table2.equals(fe_serial[0])
    _same_bands(bands_serial, bands)


def test_bad_scheduler_address_is_a_clear_error():
    pytest.importorskip("distributed", reason="Dask distributed not installed")
    # a malformed address, an unknown host, a refused connection: one clear line at once, before any work
    for address, match in (("nonsense://x", "unknown protocol 'nonsense'"), ("127.0.0.1", "tcp://host:port"),
                           ("tcp://127.0.0.1:99999", "port 1-65535"), ("tcp://no-such-host.invalid:8786", "not found"),
                           ("tcp://127.0.0.1:1", "cannot reach the Dask scheduler")):
        with pytest.raises(MftireInputError, match=match):
            Executor(scheduler=address).check()


def test_session_reuses_workers_and_start_map_returns_at_once():
    # in a session the batches share one pool; start_map hands the tasks out without waiting
    with Executor(jobs=2).session() as ex:
        first = ex.start_map(abs, [-3, 2, -1])
        second = ex.start_map(abs, [-5, 4])
        assert ex.map(abs, [-7]) == [7]
        assert second.result() == [5, 4] and first.result() == [3, 2, 1]
        assert list(first) == [3, 2, 1]  # the results stay available
    # one worker: the session is the executor itself, and a batch runs when its results are asked for
    ran = []
    ex1 = Executor(jobs=1)
    with ex1.session() as same:
        assert same is ex1
        pending = same.start_map(ran.append, [1, 2])
        assert ran == []
        assert pending.result() == [None, None] and ran == [1, 2]


def test_bootstrap_started_in_a_session_matches_serial_bit_for_bit(fit, bands_serial):
    from mftire.fitting.bands import start_bootstrap_bands

    grid = fit.data[["Fz", "kappa", "alpha", "gamma", "Vx", "P"]].iloc[::4].reset_index(drop=True)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with Executor(jobs=2).session() as ex:
            pending = start_bootstrap_bands(None, TIR, n=3, fit=fit, stages="1", seed=7, grid=grid, executor=ex)
            assert ex.map(abs, [-1]) == [1]  # the pool takes other work while the replicates run
            bands = pending.result()
    _same_bands(bands_serial, bands)


def test_a_server_that_is_not_a_dask_scheduler_is_refused_at_once():
    # a server that answers with something else, or stays silent (Dask itself would wait for its handshake for ever)
    import socket
    import threading

    from mftire.parallel import _probe

    def serve(sock: socket.socket, greeting: bytes) -> None:
        conn, _ = sock.accept()
        conn.sendall(greeting)
        threading.Event().wait(1.0)
        conn.close()

    for greeting, match, timeout in ((b"HTTP/1.0 400 Bad Request\r\n\r\n", "does not speak Dask", 5.0),
                                     (b"", "sent nothing in 0.5 s", 0.5)):  # fmt: skip
        with socket.socket() as srv:
            srv.bind(("127.0.0.1", 0))
            srv.listen(1)
            port = srv.getsockname()[1]
            t = threading.Thread(target=serve, args=(srv, greeting), daemon=True)
            t.start()
            with pytest.raises(MftireInputError, match=match):
                _probe(f"tcp://127.0.0.1:{port}", "127.0.0.1", port, timeout=timeout)
            t.join(5)


def _stuck_or_waiting(item: tuple[int, str]) -> int:
    """Task 1 ignores the stop request, makes a temporary folder, says so and hangs; task 0 returns once it has."""
    import os
    import signal
    import tempfile
    import time

    i, marks = item
    if i == 1:
        signal.signal(signal.SIGTERM, signal.SIG_IGN)  # as a task stuck in a C call: the stop never reaches it
        folder = tempfile.mkdtemp(prefix="stuck-")
        with open(os.path.join(marks, "made"), "w") as fh:
            fh.write(folder)
        time.sleep(60)
    deadline = time.monotonic() + 60
    while not os.path.exists(os.path.join(marks, "made")) and time.monotonic() < deadline:
        time.sleep(0.01)
    return i


def test_a_worker_killed_before_its_clean_up_leaves_no_temporary(tmp_path, monkeypatch):
    # the pool's workers make their temporaries in one scratch folder of the parent, removed once they are gone:
    # a worker killed after STOP_SECONDS (its own clean-up never ran) leaves nothing in the temporary folder
    import os
    import tempfile
    import time

    from mftire.parallel import STOP_SECONDS

    tmp, marks = tmp_path / "tmp", tmp_path / "marks"
    tmp.mkdir()
    marks.mkdir()
    monkeypatch.setenv("TMPDIR", str(tmp))
    monkeypatch.setattr(tempfile, "tempdir", str(tmp))
    results = Executor(jobs=2).imap(_stuck_or_waiting, [(0, str(marks)), (1, str(marks))])
    assert next(results) == 0
    made = (marks / "made").read_text()
    assert os.path.isdir(made) and Path(made).resolve().is_relative_to(tmp.resolve())
    t0 = time.monotonic()
    results.close()  # the consumer gone: the workers are stopped, the stuck one killed
    assert STOP_SECONDS <= time.monotonic() - t0 < STOP_SECONDS + 2.0
    assert list(tmp.iterdir()) == []
