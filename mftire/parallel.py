"""One executor for embarrassingly parallel work: local processes, or a Dask cluster.

Used for the bootstrap refits of the prediction bands (:func:`mftire.fitting.bands.bootstrap_bands`),
the chunks of an FE campaign (:func:`mftire.fe.slip_sweeps.run_sweeps`), the figures of a comparison
(:meth:`mftire.compare.comparison.Comparison.plots`), ``mftire demo``, and the batch commands: ``fit --each``,
``diagnose --each`` (:func:`mftire.batch.run_batch`: one task per input file), ``fe campaign --designs``
(:mod:`mftire.fe.designs`) and ``evaluate --chunk-rows`` (:mod:`mftire.streaming`, :meth:`Executor.stream`).

* ``Executor(jobs=1)`` runs every task in this process, one after another (the library default).
* ``Executor(jobs=N)`` runs them in ``N`` local worker processes
  (:class:`concurrent.futures.ProcessPoolExecutor`); ``jobs=None`` or ``0`` uses every core
  this process may run on (the command-line default, ``--jobs``).
* ``Executor(scheduler="tcp://host:8786")`` sends them to a running Dask distributed scheduler
  (``--scheduler ADDRESS``; the optional extra ``pip install 'mftire[dask]'``). The workers and the
  scheduler (it unpickles the task graph) need mftire installed. No scheduler of our own: Dask does
  the scheduling, retries and data transfer.

**Sessions.** ``with executor.session() as ex:`` keeps the workers (a process pool, or a Dask
client) up for several batches, and ``ex.start_map(fn, items)`` starts a batch without waiting for
it, so that independent stages of a job overlap (``mftire demo`` runs its rig stage while this
process fits, then the diagnosis and the bootstrap refits side by side).  Outside a session, or with ``jobs=1``,
``start_map`` defers the batch to the moment its results are asked for: the serial order.

**Workers compute, the client writes.** A task returns data (arrays, tables, result objects,
figure bytes: :class:`FilesTask` runs a function that writes files into a scratch folder of the
worker and brings the files back as bytes); this process writes every output through
:mod:`mftire.iotools.output`/:mod:`mftire.iotools.atomic` (:func:`mftire.batch.write_files`). So ``--scheduler``
works with any ``--output``, relative included, on workers that share no filesystem with it.

**Failures** (Dask) end the run with one line and :class:`ClusterError` (the CLI's exit 2): the
address is checked before any work (:meth:`Executor.check`); no worker for ``worker_timeout``
seconds, tasks killed with their workers, or a lost scheduler are named as such; a task that raises
is reported with its input (:class:`TaskError`: the ``labels`` of :meth:`Executor.imap`, e.g. a file
name).  Commands write their outputs only after the tasks are done, so nothing partial is written.

**Worker memory allocator.** Dask's nanny starts workers with ``MALLOC_TRIM_THRESHOLD_=65536``,
which also freezes glibc's mmap threshold at 128 KiB: every large temporary array is then mapped
and unmapped again, and FE chunks run 4-6 times slower.  The client registers the worker plugin
:class:`mftire.dask_plugins.MallocTuning` on the cluster (glibc ``mallopt``: mmap
threshold 32 MiB, trim threshold 64 MiB), so the workers run at in-process speed; ``dask worker
--preload mftire.dask_plugins`` does the same from the worker's side.

**Determinism.** A task is a pure function of its argument: random draws are made before the tasks
are submitted (or from a seed the task carries), and results come back in submission order, so the
result is bit for bit the serial one whatever the executor, the number of workers or the order in
which tasks finish. (Workers on a different machine may differ in the last bits through another
BLAS or CPU instruction set; on one machine they do not.)
"""

from __future__ import annotations

import os
import threading
import time
from collections.abc import Callable, Iterable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any, Generic, TypeVar

from mftire.errors import MftireError, MftireInputError

__all__ = ["ClusterError", "Executor", "FilesTask", "Pending", "TaskError", "available_cores", "batch_names",
           "chunk_count", "expand_inputs", "progress_printer"]

T = TypeVar("T")
R = TypeVar("R")

#: Seconds between two looks at the cluster while waiting for a task.
_POLL_S = 1.0
#: Default of ``Executor.worker_timeout`` and ``--worker-timeout``.
WORKER_TIMEOUT_S = 60.0


class ClusterError(MftireError):
    """The Dask cluster cannot run the tasks: scheduler lost, every worker lost, tasks killed with workers."""


class TaskError(MftireError):
    """A task raised; the message names its input (``labels`` of :meth:`Executor.imap`) and the error."""


def available_cores() -> int:
    """Cores this process may run on (the CPU affinity mask where the platform has one)."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # macOS, Windows
        return max(1, os.cpu_count() or 1)


def chunk_count(n_items: int, workers: int, seconds_per_item: float, target_s: float = 20.0) -> int:
    """How many chunks of equal size (``ceil(n_items / chunks)``) to cut ``n_items`` into: each about ``target_s``
    seconds of work or less (a lost worker costs little, progress shows, the scheduler's ~1.5 ms per task stays
    negligible), their number a multiple of ``workers`` (they finish together), never more than the items."""
    if n_items <= 0:
        return 1
    workers = max(1, workers)
    per_chunk = max(1, int(target_s // seconds_per_item)) if seconds_per_item > 0 else n_items  # items
    k = -(-n_items // per_chunk)
    k = workers * -(-k // workers)
    return max(1, min(n_items, k))


def _label(labels: Sequence[str] | Callable[[Any], str] | None, i: int, item: Any, n: int) -> str:
    if labels is None:
        return f"task {i + 1} of {n}"
    return str(labels(item) if callable(labels) else labels[i])


@dataclass(frozen=True)
class Executor:
    """Where independent tasks run: this process, local worker processes or a Dask cluster.

    Parameters
    ----------
    jobs : int or None
        Local worker processes; ``1`` runs the tasks in this process (no pool), ``None`` or ``0``
        uses :func:`available_cores`. Ignored when ``scheduler`` is given.
    scheduler : str, optional
        Address of a running Dask distributed scheduler, e.g. ``tcp://10.0.0.5:8786``.
    worker_timeout : float
        Seconds [s] the cluster may have no worker at all before the run ends with :class:`ClusterError`.
    quiet : bool
        Silence Dask's own log lines while connected (the CLI: errors are one line of ours).
    tune_workers : bool
        Register :class:`MallocTuning` on the cluster's workers (default; ``False`` leaves them as they are).
    """

    jobs: int | None = 1
    scheduler: str | None = None
    worker_timeout: float = WORKER_TIMEOUT_S
    quiet: bool = False
    tune_workers: bool = True

    def __post_init__(self) -> None:
        if self.jobs is not None and (not isinstance(self.jobs, int) or self.jobs < 0):
            raise MftireInputError(f"--jobs must be a whole number >= 0 (0: all cores), got {self.jobs!r}")
        if self.scheduler is not None and not str(self.scheduler).strip():
            raise MftireInputError("--scheduler needs an address, e.g. tcp://host:8786")
        if not self.worker_timeout > 0:
            raise MftireInputError(f"--worker-timeout must be > 0 s, got {self.worker_timeout!r}")

    @property
    def workers(self) -> int:
        """Local worker processes (1: this process); on a Dask cluster its worker threads now."""
        if self.scheduler:
            pool = getattr(self, "_pool", None)
            if pool is not None:
                return max(1, sum(pool.nthreads().values()))
            with _dask_client(str(self.scheduler), self.quiet, self.tune_workers) as client:
                return max(1, sum(client.nthreads().values()))
        return available_cores() if not self.jobs else self.jobs

    def describe(self) -> str:
        """One line for logs and reports."""
        if self.scheduler:
            return f"Dask scheduler {self.scheduler}"
        return "this process" if self.workers == 1 else f"{self.workers} local processes"

    def check(self) -> Executor:
        """Check the scheduler address (form, host, a scheduler answering, at least one worker) before any
        work; :class:`MftireInputError` or :class:`ClusterError` naming what is wrong.  Returns self."""
        if self.scheduler:
            with _dask_client(str(self.scheduler), self.quiet, self.tune_workers) as client:
                if not client.nthreads():
                    _wait_for_workers(client, str(self.scheduler), self.worker_timeout)
        return self

    def imap(self, fn: Callable[[T], R], items: Iterable[T], *, labels: Sequence[str] | Callable | None = None,
             progress: Callable[[int, int], None] | None = None) -> Iterator[R]:
        """Results of ``fn`` on each item, yielded in the order of ``items`` as they are ready.

        ``fn`` and the items must be picklable (a module-level function or a dataclass
        instance with ``__call__``) unless the tasks run in this process.  ``labels`` names each
        item's input in the error of a task that raises (a list, or a function of the item; default
        "task i of n"); ``progress(done, total)`` is called as each task finishes (in any order).
        """
        items = list(items)
        pool = getattr(self, "_pool", None)
        if pool is not None:  # a session: the workers are up already
            yield from _collect(self, pool, _submit_all(pool, fn, items, progress), items, labels)
            return
        if self.scheduler:
            with _dask_client(str(self.scheduler), self.quiet, self.tune_workers) as client:
                yield from _collect(self, client, _submit_all(client, fn, items, progress), items, labels)
            return
        n = min(self.workers, len(items))
        if n <= 1:
            for i, x in enumerate(items):
                yield fn(x) if labels is None else _run_labelled(fn, x, _label(labels, i, x, len(items)))
                if progress is not None:
                    progress(i + 1, len(items))
            return
        with _pool_cm(n) as pool:  # Ctrl-C, SIGTERM, an error, the consumer gone: workers stopped
            yield from _collect(self, pool, _submit_all(pool, fn, items, progress), items, labels)

    def start_map(self, fn: Callable[[T], R], items: Iterable[T], *, labels: Sequence[str] | Callable | None = None,
                  progress: Callable[[int, int], None] | None = None) -> Pending[R]:
        """Start ``fn`` on each item now and return at once; :meth:`Pending.result` gives the results
        in the order of ``items``.  In a :meth:`session` with workers the tasks are sent to them
        straight away; otherwise they run when the results are first asked for (as :meth:`map`)."""
        items = list(items)
        pool = getattr(self, "_pool", None)
        if pool is None:
            return Pending(lambda: self.imap(fn, items, labels=labels, progress=progress))
        futures = _submit_all(pool, fn, items, progress)
        return Pending(lambda: _collect(self, pool, futures, items, labels), futures)

    @contextmanager
    def session(self) -> Iterator[Executor]:
        """This executor with its workers kept up until the ``with`` block ends.

        Inside, :meth:`imap`/:meth:`map` reuse the same worker processes (or Dask client) for every
        batch and :meth:`start_map` sends tasks without waiting for them.  With one worker and no
        scheduler the session is this executor itself (everything runs in this process, in order).
        Tasks still running when the block ends are waited for; tasks not started are cancelled.
        """
        if not self.scheduler and self.workers <= 1:
            yield self
            return
        if self.scheduler:
            cm: Any = _dask_client(str(self.scheduler), self.quiet, self.tune_workers)
        else:
            cm = _pool_cm(self.workers)
        with cm as pool:
            ex = Executor(jobs=self.jobs, scheduler=self.scheduler, worker_timeout=self.worker_timeout,
                          quiet=self.quiet, tune_workers=self.tune_workers)
            object.__setattr__(ex, "_pool", pool)  # frozen: the open pool is not a field (not compared, not in repr)
            try:
                yield ex
            finally:
                object.__setattr__(ex, "_pool", None)

    def map(self, fn: Callable[[T], R], items: Iterable[T], *, labels: Sequence[str] | Callable | None = None,
            progress: Callable[[int, int], None] | None = None) -> list[R]:
        """``list(self.imap(fn, items))``: all results, in the order of ``items``."""
        return list(self.imap(fn, items, labels=labels, progress=progress))

    def stream(self, fn: Callable[[T], R], items: Iterable[T], *, window: int | None = None,
               labels: Sequence[str] | Callable | None = None, progress: Callable[[int, int], None] | None = None,
               total: int | None = None) -> Iterator[R]:
        """As :meth:`imap`, but ``items`` is consumed lazily and at most ``window`` tasks (default twice the
        workers) are in flight at once: memory stays bounded however many items there are.  ``total`` (the
        number of items, when known) is passed to ``progress``."""
        if not self.scheduler and self.workers <= 1:
            for i, x in enumerate(items):
                yield fn(x) if labels is None else _run_labelled(fn, x, _label(labels, i, x, total or 0))
                if progress is not None:
                    progress(i + 1, total or 0)
            return
        if getattr(self, "_pool", None) is not None:
            yield from _stream(self, self._pool, fn, items, max(1, window or 2 * self.workers), labels, progress,
                               total)
            return
        with self.session() as ex:
            yield from _stream(ex, ex._pool, fn, items, max(1, window or 2 * ex.workers), labels, progress, total)

    @classmethod
    def from_args(cls, args: Any, check: bool = True) -> Executor:
        """From the ``--jobs``/``--scheduler``/``--worker-timeout`` options of
        :func:`mftire.cli_options.add_parallel_options`;
        with ``check`` a scheduler's address is checked at once (:meth:`check`), before any work."""
        ex = cls(jobs=getattr(args, "jobs", None), scheduler=getattr(args, "scheduler", None),
                 worker_timeout=getattr(args, "worker_timeout", None) or WORKER_TIMEOUT_S, quiet=True)
        return ex.check() if check else ex


@contextmanager
def _pool_cm(n: int) -> Iterator[Any]:
    """A local pool of ``n`` worker processes for a session: shut down at the end, its workers stopped at once
    on an error or an interrupt (:func:`_stop`).  The workers' temporary files go into one scratch folder of
    this process, removed after the workers are gone: a worker killed before its own clean-up ran (stuck in a
    C call past :data:`STOP_SECONDS`, or stopped while removing a folder) leaves nothing behind."""
    import shutil
    import tempfile

    scratch = tempfile.mkdtemp(prefix="mftire-pool-")
    try:
        pool = _process_pool(n, scratch)
        interrupted = True
        try:
            yield pool
            interrupted = False
        finally:
            _stop(pool, interrupted)
    finally:
        shutil.rmtree(scratch, ignore_errors=True)


class Pending(Generic[R]):
    """Results of a batch started by :meth:`Executor.start_map`, in the order of its items."""

    def __init__(self, run: Callable[[], Iterable[R]], futures: list | None = None) -> None:
        self._run, self._futures, self._results = run, futures, None

    def __iter__(self) -> Iterator[R]:
        """The results one by one, each as soon as it (and every one before it) is ready."""
        if self._results is not None:
            yield from self._results
            return
        results = []
        for r in self._run():
            results.append(r)
            yield r
        self._results = results

    def result(self) -> list[R]:
        """All results (waits for them)."""
        if self._results is None:
            for _ in self:
                pass
        return list(self._results or [])

    def cancel(self) -> None:
        """Cancel the tasks not started yet (results are then not available)."""
        for f in self._futures or ():
            f.cancel()


# ------------------------------------------------------------------ local workers and interrupts
#
# Ctrl-C reaches every process of the terminal's group and SIGTERM the parent only; either way the
# parent (mftire.cli.main turns SIGTERM into a KeyboardInterrupt) stops the workers at once: each is
# sent SIGTERM, which a worker turns into an exception, so its own clean-up runs (temporary build
# folders, a compiler it started), then it exits; one still alive after STOP_SECONDS is killed.

#: Seconds a stopped worker gets to clean up before it is killed.
STOP_SECONDS = 1.5
_IN_TASK = False  # in a worker process: a task is running (a stop request unwinds it)


class _Stopped(BaseException):
    """SIGTERM in a worker process: unwinds the task (its ``finally`` blocks run), then the worker exits."""


def _worker_init(scratch: str) -> None:
    import signal
    import tempfile

    # this worker's temporaries (its own and its compiler's) in the pool's scratch folder
    os.environ["TMPDIR"] = scratch
    tempfile.tempdir = scratch

    signal.signal(signal.SIGINT, signal.SIG_IGN)  # the parent handles Ctrl-C and stops the workers

    def stop(signum, frame):
        if _IN_TASK:
            raise _Stopped()
        os._exit(143)  # idle: nothing to clean up

    signal.signal(signal.SIGTERM, stop)


@dataclass(frozen=True)
class _Task(Generic[T, R]):
    """A task as a worker runs it: a stop request ends the worker process after the task's clean-up (a
    worker would otherwise report the exception and wait for the next task)."""

    fn: Callable[[T], R]

    def __call__(self, x: T) -> R:
        global _IN_TASK
        _IN_TASK = True
        try:
            return self.fn(x)
        except _Stopped:
            os._exit(143)
        finally:
            _IN_TASK = False


def _process_pool(n: int, scratch: str) -> Any:
    from concurrent.futures import ProcessPoolExecutor

    return ProcessPoolExecutor(max_workers=n, initializer=_worker_init, initargs=(scratch,))


def _stop(pool: Any, interrupted: bool) -> None:
    """Shut a process pool down: wait for its tasks, or (``interrupted``) stop its workers now."""
    if not interrupted:
        pool.shutdown(wait=True, cancel_futures=True)
        return
    import time

    procs = list((getattr(pool, "_processes", None) or {}).values())
    pool.shutdown(wait=False, cancel_futures=True)
    for p in procs:
        with _suppress():
            p.terminate()
    deadline = time.monotonic() + STOP_SECONDS
    for p in procs:
        with _suppress():
            p.join(max(0.0, deadline - time.monotonic()))
    for p in procs:
        with _suppress():
            if p.is_alive():
                p.kill()
                p.join(1.0)


def _suppress():
    import contextlib

    return contextlib.suppress(OSError, ValueError, AttributeError)


def _run_labelled(fn: Callable[[T], R], x: T, label: str) -> R:
    try:
        return fn(x)
    except (KeyboardInterrupt, SystemExit, MemoryError):
        raise
    except Exception as exc:  # noqa: BLE001 - any error of a task is reported with its input
        raise _labelled(exc, label) from exc


def _labelled(exc: BaseException, label: str, explicit: bool = True) -> BaseException:
    """``exc`` of the task ``label`` as one line naming it: an mftire error keeps its class (an input error
    stays an input error), anything else becomes a :class:`TaskError` with the error's class name.  Without
    ``explicit`` labels (the caller gave none: "task i of n") an mftire error, which names its input itself,
    is returned unchanged."""
    if isinstance(exc, MftireError) and not explicit:
        return exc
    if isinstance(exc, MftireError):
        try:
            return type(exc)(f"{label}: {exc}")
        except Exception:  # noqa: BLE001 - an error class with another signature
            return TaskError(f"{label}: {exc}")
    return TaskError(f"{label}: {type(exc).__name__}: {exc}")


def _submit_all(pool: Any, fn: Callable[[T], R], items: list[T], progress: Callable[[int, int], None] | None) -> list:
    """Futures of ``fn`` on each item: a process pool or a Dask client."""
    if not items:
        return []
    if hasattr(pool, "gather"):  # a Dask client; pure=False: no hashing of large arguments
        futures = list(pool.map(fn, items, pure=False))
    else:
        task = _Task(fn)  # a stop request ends the worker after the task's clean-up
        futures = [pool.submit(task, x) for x in items]
    if progress is not None:
        lock, done = threading.Lock(), [0]

        def tick(_f: Any) -> None:
            with lock:
                done[0] += 1
                n = done[0]
            try:
                progress(n, len(futures))
            except Exception:  # noqa: BLE001 - progress output must never stop the run
                pass

        for f in futures:
            f.add_done_callback(tick)
    return futures


def _collect(ex: Executor, pool: Any, futures: list, items: list, labels: Any) -> Iterator:
    """The results of ``futures`` in order; errors become one-line :class:`TaskError`/:class:`ClusterError`."""
    try:
        for i, fut in enumerate(futures):
            yield _result(ex, pool, fut, lambda i=i: _label(labels, i, items[i], len(items)), labels is not None)
    finally:
        for fut in futures:
            fut.cancel()


def _result(ex: Executor, pool: Any, fut: Any, label: Callable[[], str], explicit: bool = True) -> Any:
    """The result of one future of a process pool or a Dask client, errors as one line naming the task."""
    if hasattr(pool, "gather"):
        return _dask_result(pool, fut, ex, label, explicit)
    try:
        return fut.result()
    except Exception as exc:  # noqa: BLE001
        from concurrent.futures.process import BrokenProcessPool

        if isinstance(exc, BrokenProcessPool):
            raise ClusterError(f"a local worker process died ({exc}); nothing written") from None
        err = _labelled(exc, label(), explicit)
        if err is exc:
            raise
        raise err from exc


def _stream(ex: Executor, pool: Any, fn: Callable, items: Iterable, window: int, labels: Any,
            progress: Callable[[int, int], None] | None, total: int | None) -> Iterator:
    """Results of ``fn`` on ``items`` in order, with at most ``window`` tasks in flight (bounded memory)."""
    from collections import deque

    inflight: deque = deque()
    done = [0]
    n = total if total is not None else 0

    def tick(_f: Any) -> None:
        done[0] += 1
        if progress is not None:
            try:
                progress(done[0], n)
            except Exception:  # noqa: BLE001
                pass

    dask = hasattr(pool, "gather")
    try:
        for i, x in enumerate(items):
            fut = pool.submit(fn, x, pure=False) if dask else pool.submit(_Task(fn), x)
            fut.add_done_callback(tick)
            inflight.append((fut, _label(labels, i, x, n) if labels is not None else f"task {i + 1}"))
            while len(inflight) >= window:
                f, lab = inflight.popleft()
                yield _result(ex, pool, f, lambda lab=lab: lab, labels is not None)
        while inflight:
            f, lab = inflight.popleft()
            yield _result(ex, pool, f, lambda lab=lab: lab, labels is not None)
    finally:
        for f, _ in inflight:
            f.cancel()


# ----------------------------------------------------------------------------------------------------- Dask


def _dask_result(client: Any, fut: Any, ex: Executor, label: Callable[[], str], explicit: bool = True) -> Any:
    """Wait for one Dask future, looking at the cluster every second: no worker for ``worker_timeout``
    seconds, or the scheduler gone, end the wait with :class:`ClusterError`."""
    address = str(ex.scheduler)
    no_worker_since = None
    done = threading.Event()
    fut.add_done_callback(lambda _f: done.set())
    while not done.wait(_POLL_S):
        if client.status not in ("running", "connecting"):
            raise ClusterError(f"lost the Dask scheduler at {address}")
        try:
            n = len(client.sync(client.scheduler.ncores, callback_timeout=10))
        except Exception as exc:  # noqa: BLE001 - OSError, CommClosedError, TimeoutError: all mean no scheduler
            raise ClusterError(f"lost the Dask scheduler at {address} ({type(exc).__name__})") from None
        if n:
            no_worker_since = None
        elif no_worker_since is None:
            no_worker_since = time.monotonic()
        elif time.monotonic() - no_worker_since > ex.worker_timeout:
            raise ClusterError(f"lost every Dask worker of the scheduler at {address}: none for "
                               f"{ex.worker_timeout:g} s (--worker-timeout); nothing written")
    status = fut.status
    if status == "finished":
        return fut.result()
    if status == "error":
        exc = fut.exception()
        if type(exc).__name__ == "KilledWorker":
            raise ClusterError(f"lost Dask workers: {label()} was running on workers that died "
                               f"({exc}); nothing written") from None
        err = _labelled(exc, label(), explicit)
        if err is exc:  # an mftire error, which names its input itself
            raise exc
        raise err from None
    raise ClusterError(f"lost the Dask scheduler at {address} (task {status})")


def _wait_for_workers(client: Any, address: str, timeout: float) -> None:
    t0 = time.monotonic()
    while not client.nthreads():
        if time.monotonic() - t0 > timeout:
            raise ClusterError(f"the Dask scheduler at {address} has no worker (waited {timeout:g} s, "
                               "--worker-timeout)")
        time.sleep(min(_POLL_S, timeout))


def check_address(address: str) -> tuple[str, str, int]:
    """(scheme, host, port) of a scheduler address ``[tcp://]host:port``; :class:`MftireInputError` for a
    malformed address or a host name that does not resolve (before Dask would retry for a long time)."""
    import socket

    a = address.strip()
    scheme, sep, rest = a.partition("://")
    if not sep:
        scheme, rest = "tcp", a
    if scheme == "inproc":  # a cluster in this very process (tests)
        return scheme, rest, 0
    if scheme not in ("tcp", "tls", "ws", "wss"):
        raise MftireInputError(f"--scheduler {address!r}: unknown protocol {scheme!r} (use tcp://host:port, or "
                               "tls://, ws://, wss://)")
    host, sep, port_s = rest.rstrip("/").rpartition(":")
    host = host.strip("[]")
    if not sep or not host or not port_s.isdigit() or not 0 < int(port_s) < 65536:
        raise MftireInputError(f"--scheduler {address!r}: not an address of the form tcp://host:port "
                               "(port 1-65535), e.g. tcp://10.0.0.5:8786")
    try:
        socket.getaddrinfo(host, int(port_s), type=socket.SOCK_STREAM)
    except OSError as exc:
        raise MftireInputError(f"--scheduler {address!r}: host {host!r} not found ({exc.strerror or exc})") from None
    return scheme, host, int(port_s)


def _probe(address: str, host: str, port: int, timeout: float = 10.0) -> None:
    """A Dask scheduler at ``host:port``, or :class:`MftireInputError` at once: a refused connection (Dask would
    retry for its whole timeout), or a server that is not a Dask scheduler (Dask would wait for its handshake
    for ever; a scheduler sends one as soon as a connection opens: a frame header, 8 bytes little-endian)."""
    import socket
    import struct

    try:
        with socket.create_connection((host, port), timeout=timeout) as sock:
            data = b""
            while len(data) < 8:
                got = sock.recv(8 - len(data))
                if not got:
                    break
                data += got
    except TimeoutError:
        raise MftireInputError(f"no Dask scheduler at {address!r}: the server there sent nothing in {timeout:g} s "
                               "(a Dask scheduler greets at once)") from None
    except OSError as exc:
        raise MftireInputError(f"cannot reach the Dask scheduler at {address!r}: "
                               f"{exc.strerror or type(exc).__name__}") from None
    if len(data) < 8 or not 0 < struct.unpack("<Q", data)[0] < 1 << 20:
        raise MftireInputError(f"no Dask scheduler at {address!r}: the server there does not speak Dask's protocol")


@contextmanager
def _dask_client(address: str, quiet: bool = False, tune: bool = True) -> Iterator[Any]:
    """A Dask client of the scheduler at ``address`` with :class:`MallocTuning` on its workers; closed (within
    seconds, also when the scheduler is gone) when the block ends."""
    try:
        from distributed import Client
    except ImportError as exc:
        raise MftireInputError("--scheduler needs Dask distributed: pip install 'mftire[dask]'") from exc
    scheme, host, port = check_address(address)
    if scheme == "tcp":
        _probe(address, host, port)
    with _quiet_dask(quiet):
        try:  # set_as_default=False: connecting must not change the caller's global Dask configuration
            client = Client(address, set_as_default=False, timeout="20s")
        except (OSError, ValueError, TimeoutError) as exc:
            raise MftireInputError(f"cannot use the Dask scheduler at {address!r}: {exc}") from None
        try:
            if tune:
                from mftire.dask_plugins import MallocTuning

                try:
                    client.register_plugin(MallocTuning(), name=MallocTuning.name)
                except (OSError, TimeoutError):  # the scheduler went away: the first task will say so
                    pass
            yield client
        finally:
            try:
                client.close(timeout=5)
            except Exception:  # noqa: BLE001 - the scheduler may be gone already
                pass


@contextmanager
def _quiet_dask(quiet: bool) -> Iterator[None]:
    """Dask's loggers at CRITICAL inside the block (``quiet``), restored after."""
    if not quiet:
        yield
        return
    import logging

    names = ("distributed", "tornado", "asyncio")
    loggers = [logging.getLogger(n) for n in names]
    loggers += [lg for n, lg in list(logging.root.manager.loggerDict.items())
                if isinstance(lg, logging.Logger) and n.startswith(tuple(f"{x}." for x in names))]
    levels = [lg.level for lg in loggers]
    for lg in loggers:
        lg.setLevel(logging.CRITICAL)
    try:
        yield
    finally:
        for lg, lv in zip(loggers, levels, strict=True):
            lg.setLevel(lv)


# ------------------------------------------------------------------------------------------- client writes


@dataclass(frozen=True)
class FilesTask:
    """``fn(item, folder)`` run with a fresh scratch folder of the worker: returns ``(result, files)``, ``files``
    mapping the path (relative to the folder, ``/``-separated) of every file ``fn`` wrote to its bytes.
    The client writes them with :func:`mftire.batch.write_files`.  ``fn`` must return no path inside the folder."""

    fn: Callable[[Any, str], Any]

    def __call__(self, item: Any) -> tuple[Any, dict[str, bytes]]:
        import contextvars
        import tempfile

        with tempfile.TemporaryDirectory(prefix="mftire-task-") as folder:
            # in a fresh context, as on a worker: the task writes its own scratch folder, outside the running
            # command's output scope (the client writes the files under that policy)
            result = contextvars.Context().run(self.fn, item, folder)
            files: dict[str, bytes] = {}
            for root, _dirs, names in os.walk(folder):
                for name in sorted(names):
                    p = os.path.join(root, name)
                    with open(p, "rb") as fh:
                        files[os.path.relpath(p, folder).replace(os.sep, "/")] = fh.read()
        return result, dict(sorted(files.items()))


def expand_inputs(patterns: Sequence[str]) -> list[str]:
    """Input files of a batch command: each argument that is not an existing file but a glob pattern
    (``runs/*.csv``, for shells that do not expand it) is replaced by its matches, sorted; a pattern that
    matches nothing is an error."""
    import glob

    out: list[str] = []
    for p in patterns:
        if os.path.exists(p) or not glob.has_magic(p):
            out.append(p)
            continue
        found = sorted(glob.glob(p))
        if not found:
            raise MftireInputError(f"{p}: no file matches this pattern")
        out.extend(found)
    return list(dict.fromkeys(out))


def batch_names(paths: Sequence[str]) -> list[str]:
    """One output name per input of a batch command: the file name without its suffix(es) (``a.csv.gz`` ->
    ``a``); two inputs of the same name are refused (their outputs would collide)."""
    names = []
    seen: dict[str, str] = {}
    for p in paths:
        base = os.path.basename(os.fspath(p))
        name = base.split(".")[0] or base
        if name in seen:
            raise MftireInputError(f"{p}: same output name {name!r} as {seen[name]}; rename one of them")
        seen[name] = p
        names.append(name)
    return names


def progress_printer(prefix: str, what: str, enabled: bool | None = None) -> Callable[[int, int], None]:
    """A ``progress(done, total)`` for :meth:`Executor.imap` through the one progress reporter
    (:mod:`mftire.progress`: standard error, only on a terminal unless ``enabled``): ``prefix: done/total what``
    rewritten in place (``total`` 0: unknown, ``prefix: done what``)."""
    from mftire.progress import Progress

    rep = Progress(prefix, enabled)

    def show(done: int, total: int) -> None:
        rep.update(f"{done}/{total} {what}" if total else f"{done} {what}")
        if total and done == total:
            rep.done()

    return show
