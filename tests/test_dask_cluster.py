"""Issue 27: every batch job on a Dask cluster, results written by the client, clean failures.

One LocalCluster (2 worker processes, 1 thread each, started in a folder of its own so that a file a worker
wrote by mistake would land elsewhere) is shared by the tests of this module; each command runs once locally
and once with ``--scheduler`` on that cluster, with a *relative* output, and the two output folders must hold
the same bytes.  The failure test starts a scheduler and two nanny-less workers as processes and kills them.
"""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import time
import warnings
import zipfile
from pathlib import Path

import pytest

from mftire.cli import main

distributed = pytest.importorskip("distributed", reason="Dask distributed not installed (pip install "
                                  "'mftire[dask]'); the Dask paths are not tested")  # fmt: skip

ROOT = Path(__file__).resolve().parents[1]
#: what differs from run to run whatever runs the tasks: the rig stage's import and stage seconds, the thermal
#: stage's seconds and CPU seconds, the report's time stamp, and the FMU's size (its cross-compiled Windows DLL
#: carries the link time in its PE header)
_TIMINGS = re.compile(rb'("?(?:import_s|stage_s|stage_cpu_s)"?(?:</td><td>|: )|generated |bytes(?:&#x27;|"|\')?: )'
                      rb'[-+0-9.e:T ]+')


@pytest.fixture(scope="module")
def cluster(tmp_path_factory):
    elsewhere = tmp_path_factory.mktemp("workers_cwd")
    cwd = os.getcwd()
    os.chdir(elsewhere)  # the workers start here: a relative path written on a worker would land here
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            c = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None)
    finally:
        os.chdir(cwd)
    with c:
        yield c.scheduler_address, elsewhere


def _files(folder: Path) -> dict[str, bytes]:
    out = {}
    for p in sorted(folder.rglob("*")):
        if p.is_file():
            data = p.read_bytes()
            if p.suffix == ".fmu":  # a zip: the members, not the archive's time stamps; binaries are built here
                with zipfile.ZipFile(p) as z:  # in both runs, and the Windows DLL holds its link time
                    data = b"".join(n.encode() + z.read(n) for n in sorted(z.namelist())
                                    if not n.startswith("binaries/"))
            out[p.relative_to(folder).as_posix()] = _TIMINGS.sub(rb"\1<time>", data)
    return out


def _same_outputs(a: Path, b: Path) -> None:
    fa, fb = _files(a), _files(b)
    assert fa.keys() == fb.keys() and fa
    for name in fa:
        assert fa[name] == fb[name], name


def _run_here(folder: Path, argv: list[str]) -> int:
    cwd = os.getcwd()
    os.chdir(folder)
    try:
        return main(argv)
    finally:
        os.chdir(cwd)


def test_demo_on_the_cluster_with_a_relative_output_equals_the_local_run(cluster, quick_demo, tmp_path, capsys):
    address, workers_cwd = cluster
    # the reference: the session's local run on every core (its output does not depend on --jobs), which
    # tests/test_demo.py checks (tests/conftest.py: quick_demo)
    local, _, _ = quick_demo
    assert _run_here(tmp_path, ["demo", "--quick", "--output", "out", "--scheduler", address]) == 0
    assert "done: out/report.html" in capsys.readouterr().out
    _same_outputs(local, tmp_path / "out")
    assert list(workers_cwd.iterdir()) == []  # nothing written by the workers
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".")] == []  # no staging folder left


# ------------------------------------------------------------------------------------------------- failures


def _start(args: list[str], log: Path) -> subprocess.Popen:
    """A Dask process (mftire importable: the scheduler unpickles the task graph too) in its own session."""
    env = {**os.environ, "PYTHONPATH": f"{ROOT}{os.pathsep}{os.environ.get('PYTHONPATH', '')}"}
    return subprocess.Popen([sys.executable, *args], stdout=subprocess.DEVNULL, stderr=open(log, "wb"),
                            start_new_session=True, cwd=log.parent, env=env)  # fmt: skip


def _stop(p: subprocess.Popen) -> None:
    if p.poll() is None:
        os.killpg(p.pid, signal.SIGKILL)
    p.wait(timeout=30)


@pytest.mark.parametrize("lost", ["workers", "scheduler"])
def test_killing_the_cluster_mid_run_is_one_line_exit_2_and_no_output(tmp_path, lost):
    port = _free_port()
    address = f"tcp://127.0.0.1:{port}"
    sched = _start(["-m", "distributed.cli.dask_scheduler", "--host", "127.0.0.1", "--port", str(port),
                    "--dashboard-address", ":0", "--no-show"], tmp_path / "scheduler.log")  # fmt: skip
    workers: list[subprocess.Popen] = []
    try:
        env_path = f"{ROOT}{os.pathsep}{os.environ.get('PYTHONPATH', '')}"
        for i in range(2):  # no nanny: a killed worker stays dead
            workers.append(_start(["-m", "distributed.cli.dask_worker", address, "--no-nanny", "--nthreads", "1",
                                   "--no-dashboard"], tmp_path / f"worker{i}.log"))  # fmt: skip
        with distributed.Client(address, timeout="60s", set_as_default=False) as client:
            client.wait_for_workers(2, timeout=60)
            run = subprocess.Popen(
                [sys.executable, "-m", "mftire.cli", "fe", "campaign", "--output", "out", "--scheduler", address,
                 "--worker-timeout", "3"], cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                env={**os.environ, "PYTHONPATH": env_path})  # fmt: skip
            t0 = time.monotonic()
            while not any(client.processing().values()):  # the tasks are on the workers
                assert time.monotonic() - t0 < 60 and run.poll() is None, run.communicate()
                time.sleep(0.2)
        t_kill = time.monotonic()
        for p in workers if lost == "workers" else [sched]:
            os.killpg(p.pid, signal.SIGKILL)
        out, err = run.communicate(timeout=120)
        elapsed = time.monotonic() - t_kill
    finally:
        for p in (*workers, sched):
            _stop(p)
    lines = err.decode().strip().splitlines()
    assert run.returncode == 2, err
    assert len(lines) == 1, lines
    if lost == "workers":  # none left: the run ends after --worker-timeout
        assert lines[0].startswith("mftire fe: error: lost every Dask worker") and "3 s" in lines[0], lines
    else:
        assert lines[0].startswith(f"mftire fe: error: lost the Dask scheduler at {address}"), lines
    assert elapsed < 30
    assert not (tmp_path / "out").exists() and not any(p.name.startswith(".out") for p in tmp_path.iterdir())


def _free_port() -> int:
    import socket

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_a_lost_scheduler_and_a_bad_address_are_one_line_and_exit_2(tmp_path, capsys):
    # nothing listens there: refused at once, before any work (the output folder is never made)
    port = _free_port()
    t0 = time.monotonic()
    rc = main(["fe", "campaign", "--quick", "--output", str(tmp_path / "o"), "--scheduler", f"tcp://127.0.0.1:{port}"])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(err) == 1 and "cannot reach the Dask scheduler" in err[0]
    assert time.monotonic() - t0 < 15 and not (tmp_path / "o").exists()
    rc = main(["fe", "campaign", "--quick", "--output", str(tmp_path / "o"), "--scheduler", "127.0.0.1"])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(err) == 1 and "tcp://host:port" in err[0]


# --------------------------------------------------------------------------------------------- batch commands


@pytest.fixture(scope="module")
def sweep_files(tmp_path_factory):
    """Three small sweep files of the MF 6.1 reference tyre (braking and cornering, noise of its own seed)."""
    import numpy as np
    from conftest import REFERENCE_TYRES

    from mftire.fitting.synthetic import synthetic_sweeps
    from mftire.iotools.tir import read_tir
    from mftire.parameters import with_defaults

    folder = tmp_path_factory.mktemp("runs")
    tyre = read_tir(REFERENCE_TYRES["MF61"])
    f0 = with_defaults(tyre)["FNOMIN"]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for i in range(3):
            df = synthetic_sweeps(tyre, [0.5 * f0, f0, 1.5 * f0], np.radians([0.0]), n_kappa=15, n_alpha=11,
                                  n_combined=5, noise=0.02, seed=10 + i, channels=("Fx", "Fy"))
            df.to_csv(folder / f"tyre_{i}.csv", index=False)
    return folder, REFERENCE_TYRES["MF61"], f0


def test_batch_fit_and_diagnose_on_the_cluster_equal_the_local_runs(cluster, sweep_files, tmp_path, capsys):
    address, workers_cwd = cluster
    runs, tir, f0 = sweep_files
    pattern = str(runs / "tyre_*.csv")  # a glob, expanded by mftire
    fit = ["fit", pattern, "--each", "--template", str(tir), "--stages", "1,2"]
    assert _run_here(tmp_path, [*fit, "--output", "fit_local", "--jobs", "1"]) == 0
    assert _run_here(tmp_path, [*fit, "--output", "fit_dask", "--scheduler", address]) == 0
    printed = capsys.readouterr()
    assert "tyre_2.tir: " in printed.out and printed.err == ""  # progress lines only on a terminal
    _same_outputs(tmp_path / "fit_local", tmp_path / "fit_dask")
    assert sorted(p.name for p in (tmp_path / "fit_dask").iterdir()) == ["tyre_0.tir", "tyre_1.tir", "tyre_2.tir"]
    # each fitted file is the one a fit of that file alone gives
    assert main(["fit", str(runs / "tyre_1.csv"), "--template", str(tir), "--stages", "1,2",
                 "--output", str(tmp_path / "single.tir")]) == 0  # fmt: skip
    assert (tmp_path / "single.tir").read_bytes() == (tmp_path / "fit_dask" / "tyre_1.tir").read_bytes()

    # diagnose two of them, each with its own fitted .tir from the folder fit --each wrote
    diag = ["diagnose", str(runs / "tyre_0.csv"), str(runs / "tyre_2.csv"), "--each", "--tir", "fit_local",
            "--permutations", "9", "--holdout", f"Fz={f0:g}"]  # fmt: skip
    assert _run_here(tmp_path, [*diag, "--output", "diag_local", "--jobs", "1"]) == 0
    assert _run_here(tmp_path, [*diag, "--output", "diag_dask", "--scheduler", address]) == 0
    _same_outputs(tmp_path / "diag_local", tmp_path / "diag_dask")
    for name in ("tyre_0", "tyre_2"):
        assert (tmp_path / "diag_dask" / name / "diagnosis.json").exists()
    assert list(workers_cwd.iterdir()) == []


def test_a_task_that_raises_is_reported_with_its_input(cluster, sweep_files, tmp_path, capsys):
    address, _ = cluster
    runs, tir, _ = sweep_files
    bad = tmp_path / "broken.csv"
    bad.write_text("Fz,kappa\n1,2\n")
    rc = main(["fit", str(runs / "tyre_0.csv"), str(bad), "--each", "--template", str(tir), "--stages", "1",
               "--output", str(tmp_path / "o"), "--scheduler", address])  # fmt: skip
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and err[-1].startswith("mftire fit: error: broken.csv: "), err
    assert not (tmp_path / "o").exists()


def test_streamed_evaluate_in_chunks_equals_the_whole_table(cluster, tmp_path):
    # 5e4 rows here (CSV formatting costs ~70 s per 1e6 rows on the CI machine; benchmarks/bench_dask.py runs
    # 1e6), chunks of an odd size so that the last chunk has one row; alpha sorted: instKya needs neighbours
    import numpy as np
    import pandas as pd
    from conftest import REFERENCE_TYRES

    address, _ = cluster
    rng = np.random.default_rng(3)
    n = 50_000
    pd.DataFrame({"Fz": rng.uniform(2000, 6000, n), "kappa": rng.uniform(-0.2, 0.2, n),
                  "alpha": np.sort(rng.uniform(-0.2, 0.2, n)), "gamma": 0.01, "Vx": 16.0}).to_csv(
        tmp_path / "points.csv", index=False)  # fmt: skip
    tir = str(REFERENCE_TYRES["MF61"])
    base = ["evaluate", tir, "--input", "points.csv", "--output"]
    assert _run_here(tmp_path, [*base, "whole.csv", "--jobs", "1"]) == 0
    assert _run_here(tmp_path, [*base, "dask.csv", "--chunk-rows", "16667", "--scheduler", address]) == 0
    assert _run_here(tmp_path, [*base, "pool.csv", "--chunk-rows", "24999", "--jobs", "2"]) == 0
    whole = (tmp_path / "whole.csv").read_bytes()
    assert (tmp_path / "dask.csv").read_bytes() == whole
    assert (tmp_path / "pool.csv").read_bytes() == whole
    ky = pd.read_csv(tmp_path / "dask.csv", usecols=["instKya"])["instKya"].to_numpy()
    assert np.isfinite(ky[24990:25010]).all() and np.ptp(ky) > 0  # real differences across chunk edges


def test_fe_design_of_experiments_on_the_cluster_equals_the_local_run(cluster, tmp_path, capsys):
    address, workers_cwd = cluster
    # three designs (a coarse grid: the test is about the batch, not the physics), the reduced programme
    (tmp_path / "doe.csv").write_text("design,grid.nx,grid.ny,tread.kx\n"
                                      "base,12,5,\nsoft,12,5,6e7\nstiff,12,5,1.2e8\n")  # fmt: skip
    base = ["fe", "campaign", "--designs", "doe.csv", "--quick", "--output"]
    assert _run_here(tmp_path, [*base, "local", "--jobs", "1"]) == 0
    assert _run_here(tmp_path, [*base, "dask", "--scheduler", address]) == 0
    assert "wrote 3 designs into dask" in capsys.readouterr().out
    _same_outputs(tmp_path / "local", tmp_path / "dask")
    assert sorted(p.name for p in (tmp_path / "dask").iterdir()) == ["base", "soft", "stiff"]
    a, b = ((tmp_path / "dask" / d / "sweeps.csv").read_bytes() for d in ("soft", "stiff"))
    assert a != b  # the designs differ
    # the workers got the allocator plugin (mftire.dask_plugins.MallocTuning), and it ran there
    with distributed.Client(address, set_as_default=False) as client:
        assert set(client.run(lambda dask_worker: "mftire-malloc" in dask_worker.plugins).values()) == {True}
        from mftire.dask_plugins import tune_malloc

        assert set(client.run(tune_malloc).values()) == {True}  # glibc's mallopt accepted both settings
    assert list(workers_cwd.iterdir()) == []


def test_fit_bands_checks_the_scheduler_before_fitting(sweep_files, tmp_path, capsys):
    runs, tir, _ = sweep_files
    out = tmp_path / "fitted.tir"
    rc = main(["fit", str(runs / "tyre_0.csv"), "--template", str(tir), "--stages", "1", "--output", str(out),
               "--bands", "3", "--scheduler", f"tcp://127.0.0.1:{_free_port()}"])  # fmt: skip
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(err) == 1 and "cannot reach the Dask scheduler" in err[0], err
    assert not out.exists()  # nothing fitted, nothing written


def test_batch_outputs_follow_the_output_policy(sweep_files, tmp_path, capsys):
    runs, tir, _ = sweep_files
    out = tmp_path / "fitted"
    out.mkdir()
    (out / "keep.txt").write_text("mine")
    args = ["fit", str(runs / "tyre_0.csv"), str(runs / "tyre_1.csv"), "--each", "--template", str(tir),
            "--stages", "1", "--output", str(out), "--jobs", "1"]  # fmt: skip
    assert main(args) == 2  # a non-empty folder needs --force, checked before any work
    assert "use --force" in capsys.readouterr().err and sorted(p.name for p in out.iterdir()) == ["keep.txt"]
    assert main([*args, "--force"]) == 0
    assert sorted(p.name for p in out.iterdir()) == ["keep.txt", "tyre_0.tir", "tyre_1.tir"]  # others left alone
    # an output folder implies --each (a folder cannot be one fitted .tir); so does diagnose --tir FOLDER
    assert main(["fit", str(runs / "tyre_2.csv"), "--template", str(tir), "--stages", "1", "--output",
                 str(tmp_path / "implied") + "/", "--jobs", "1"]) == 0  # fmt: skip
    assert (tmp_path / "implied" / "tyre_2.tir").is_file()
    assert main(["diagnose", str(runs / "tyre_2.csv"), "--tir", str(tmp_path / "implied"), "--output",
                 str(tmp_path / "d"), "--permutations", "9", "--jobs", "1"]) == 0  # fmt: skip
    assert (tmp_path / "d" / "tyre_2" / "diagnosis.json").is_file()
    # an input that is also an output is refused, even with --force: the template would be replaced by a fit
    rc = main(["fit", str(runs / "tyre_0.csv"), "--each", "--template", str(out / "tyre_0.tir"), "--stages", "1",
               "--output", str(out), "--force", "--jobs", "1"])  # fmt: skip
    assert rc == 2 and "output is the input file" in capsys.readouterr().err
