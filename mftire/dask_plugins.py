"""Dask worker set-up for mftire (imported only where Dask distributed is installed).

* :class:`MallocTuning`, the worker plugin that :class:`mftire.parallel.Executor` registers when it connects to a
  scheduler: :func:`tune_malloc` on every worker, present and future.
* As a preload, ``dask worker --preload mftire.dask_plugins tcp://HOST:8786`` runs the same when the worker
  starts (:func:`dask_setup`), for clusters whose workers are started by other clients too.
"""

from __future__ import annotations

from typing import Any

from distributed.diagnostics.plugin import WorkerPlugin

__all__ = ["MallocTuning", "dask_setup", "tune_malloc"]


def tune_malloc() -> bool:
    """glibc's allocator back to its in-process behaviour in a Dask worker started by a nanny (see the module
    docstring): mmap threshold 32 MiB, trim threshold 64 MiB (``mallopt``; what glibc's dynamic rule reaches
    for large arrays).  False where the C library has no ``mallopt`` (musl, macOS, Windows): nothing done.
    Run on the workers by :class:`MallocTuning`."""
    import ctypes
    import ctypes.util

    try:
        libc = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6")
        mallopt = libc.mallopt
    except (OSError, AttributeError):
        return False
    m_trim_threshold, m_mmap_threshold = -1, -3  # glibc malloc.h
    return bool(mallopt(m_mmap_threshold, 32 * 1024 * 1024)) and bool(mallopt(m_trim_threshold, 64 * 1024 * 1024))


class MallocTuning(WorkerPlugin):
    """Worker plugin: :func:`tune_malloc` when the worker starts (or when registered)."""

    idempotent = True
    name = "mftire-malloc"

    def __init__(self) -> None:
        import os

        self.client_pid = os.getpid()

    def setup(self, worker: Any) -> None:
        import os

        if os.getpid() != self.client_pid:  # a worker in the client's own process is left alone
            tune_malloc()


def dask_setup(worker: Any) -> None:
    """``dask worker --preload mftire.dask_plugins``: tune the worker's allocator as it starts."""
    tune_malloc()
