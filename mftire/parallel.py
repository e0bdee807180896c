"""One executor for embarrassingly parallel work: local processes, or a Dask cluster.

Used for the bootstrap refits of the prediction bands (:func:`mftire.fitting.bands.bootstrap_bands`),
the chunks of an FE campaign (:func:`mftire.fe.slip_sweeps.run_sweeps`), the figures of a comparison
(:meth:`mftire.compare.comparison.Comparison.plots`) and ``mftire demo``.

* ``Executor(jobs=1)`` runs every task in this process, one after another (the library default).
* ``Executor(jobs=N)`` runs them in ``N`` local worker processes
  (:class:`concurrent.futures.ProcessPoolExecutor`); ``jobs=None`` or ``0`` uses every core
  this process may run on (the command-line default, ``--jobs``).
* ``Executor(scheduler="tcp://host:8786")`` sends them to a running Dask distributed scheduler
  (``--scheduler ADDRESS``; the optional extra ``pip install 'mftire[dask]'``). The workers need
  mftire installed. No scheduler of our own: Dask does the scheduling, retries and data transfer.

**Sessions.** ``with executor.session() as ex:`` keeps the workers (a process pool, or a Dask
client) up for several batches, and ``ex.start_map(fn, items)`` starts a batch without waiting for
it, so that independent stages of a job overlap (``mftire demo`` runs its rig stage while this
process fits, then the diagnosis and the bootstrap refits side by side).  Outside a session, or with ``jobs=1``,
``start_map`` defers the batch to the moment its results are asked for: the serial order.

**Determinism.** A task is a pure function of its argument: random draws are made before the tasks
are submitted (or from a seed the task carries), and results come back in submission order, so the
result is bit for bit the serial one whatever the executor, the number of workers or the order in
which tasks finish. (Workers on a different machine may differ in the last bits through another
BLAS or CPU instruction set; on one machine they do not.)
"""

from __future__ import annotations

import os
from collections.abc import Callable, Iterable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any, Generic, TypeVar

from mftire.errors import MftireInputError

__all__ = ["Executor", "Pending", "available_cores"]

T = TypeVar("T")
R = TypeVar("R")


def available_cores() -> int:
    """Cores this process may run on (the CPU affinity mask where the platform has one)."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # macOS, Windows
        return max(1, os.cpu_count() or 1)


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
    """

    jobs: int | None = 1
    scheduler: str | None = None

    def __post_init__(self) -> None:
        if self.jobs is not None and (not isinstance(self.jobs, int) or self.jobs < 0):
            raise MftireInputError(f"--jobs must be a whole number >= 0 (0: all cores), got {self.jobs!r}")
        if self.scheduler is not None and not str(self.scheduler).strip():
            raise MftireInputError("--scheduler needs an address, e.g. tcp://host:8786")

    @property
    def workers(self) -> int:
        """Local worker processes (1: this process)."""
        return available_cores() if not self.jobs else self.jobs

    def describe(self) -> str:
        """One line for logs and reports."""
        if self.scheduler:
            return f"Dask scheduler {self.scheduler}"
        return "this process" if self.workers == 1 else f"{self.workers} local processes"

    def imap(self, fn: Callable[[T], R], items: Iterable[T]) -> Iterator[R]:
        """Results of ``fn`` on each item, yielded in the order of ``items`` as they are ready.

        ``fn`` and the items must be picklable (a module-level function or a dataclass
        instance with ``__call__``) unless the tasks run in this process.
        """
        items = list(items)
        pool = getattr(self, "_pool", None)
        if pool is not None:  # a session: the workers are up already
            yield from _collect(_submit_all(pool, fn, items))
            return
        if self.scheduler:
            yield from _dask_imap(str(self.scheduler), fn, items)
            return
        n = min(self.workers, len(items))
        if n <= 1:
            for x in items:
                yield fn(x)
            return
        from concurrent.futures import ProcessPoolExecutor

        with ProcessPoolExecutor(max_workers=n) as pool:
            yield from pool.map(fn, items)

    def start_map(self, fn: Callable[[T], R], items: Iterable[T]) -> Pending[R]:
        """Start ``fn`` on each item now and return at once; :meth:`Pending.result` gives the results
        in the order of ``items``.  In a :meth:`session` with workers the tasks are sent to them
        straight away; otherwise they run when the results are first asked for (as :meth:`map`)."""
        items = list(items)
        pool = getattr(self, "_pool", None)
        if pool is None:
            return Pending(lambda: self.imap(fn, items))
        futures = _submit_all(pool, fn, items)
        return Pending(lambda: _collect(futures), futures)

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
            pool: Any = _dask_client(str(self.scheduler))
        else:
            from concurrent.futures import ProcessPoolExecutor

            pool = ProcessPoolExecutor(max_workers=self.workers)
        ex = Executor(jobs=self.jobs, scheduler=self.scheduler)
        object.__setattr__(ex, "_pool", pool)  # frozen: the open pool is not a field (not compared, not in repr)
        try:
            yield ex
        finally:
            object.__setattr__(ex, "_pool", None)
            if self.scheduler:
                pool.close()
            else:
                pool.shutdown(wait=True, cancel_futures=True)

    def map(self, fn: Callable[[T], R], items: Iterable[T]) -> list[R]:
        """``list(self.imap(fn, items))``: all results, in the order of ``items``."""
        return list(self.imap(fn, items))

    @classmethod
    def from_args(cls, args: Any) -> Executor:
        """From the ``--jobs``/``--scheduler`` options of :func:`mftire.cli_options.add_parallel_options`."""
        return cls(jobs=getattr(args, "jobs", None), scheduler=getattr(args, "scheduler", None))


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


def _submit_all(pool: Any, fn: Callable[[T], R], items: list[T]) -> list:
    """Futures of ``fn`` on each item: a process pool or a Dask client."""
    if hasattr(pool, "gather"):  # a Dask client; pure=False: no hashing of large arguments
        return list(pool.map(fn, items, pure=False)) if items else []
    return [pool.submit(fn, x) for x in items]


def _collect(futures: list) -> Iterator:
    try:
        for fut in futures:
            yield fut.result()
    finally:
        for fut in futures:
            fut.cancel()


def _dask_client(address: str) -> Any:
    try:
        from distributed import Client
    except ImportError as exc:
        raise MftireInputError("--scheduler needs Dask distributed: pip install 'mftire[dask]'") from exc
    try:  # set_as_default=False: connecting must not change the caller's global Dask configuration
        return Client(address, set_as_default=False, timeout="20s")
    except (OSError, ValueError) as exc:
        raise MftireInputError(f"cannot use the Dask scheduler at {address!r}: {exc}") from exc


def _dask_imap(address: str, fn: Callable[[T], R], items: list[T]) -> Iterator[R]:
    with _dask_client(address) as client:
        yield from _collect(_submit_all(client, fn, items))
