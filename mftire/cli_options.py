"""Options shared by the sub-commands of the command line (the CLI layer; nothing below imports it)."""

from __future__ import annotations

import argparse
from typing import Any

from mftire.iotools.output import FORCE_HELP

__all__ = ["SWEEP_DATA_HELP", "add_force_option", "add_parallel_options", "add_quiet_option", "add_sweep_command",
           "progress_of"]


#: What a sub-command reading slip sweeps takes as DATA.
SWEEP_DATA_HELP = "sweep files: CSV in the SI sweep schema, or TYDEX .tdx"


def add_sweep_command(subparsers: Any, name: str, **texts: str) -> argparse.ArgumentParser:
    """A sub-command on slip sweeps: its parser (``texts``: its help and description) with the positional
    ``DATA`` (one or more sweep files, :data:`SWEEP_DATA_HELP`)."""
    parser = subparsers.add_parser(name, **texts)
    parser.add_argument("data", nargs="+", metavar="DATA", help=SWEEP_DATA_HELP)
    return parser


def add_quiet_option(parser: argparse.ArgumentParser) -> None:
    """``--quiet``: no progress lines (they go to stderr, and only when it is a terminal)."""
    parser.add_argument("--quiet", "-q", action="store_true",
                        help="no progress lines on stderr (shown only on a terminal anyway)")


def progress_of(args: argparse.Namespace) -> bool | None:
    """The ``progress=`` of the API for parsed ``args``: False with ``--quiet``, else None (on a terminal)."""
    return False if getattr(args, "quiet", False) else None


def add_force_option(parser: argparse.ArgumentParser) -> None:
    """Add the common ``--force`` option to a sub-command (the output policy: :mod:`mftire.iotools.output`)."""
    parser.add_argument("--force", "-f", action="store_true", help=FORCE_HELP)


def add_parallel_options(parser: Any, what: str) -> None:
    """Add ``--jobs N``, ``--scheduler ADDRESS`` and ``--worker-timeout S`` to an argparse parser (``what`` runs
    in parallel; :meth:`mftire.parallel.Executor.from_args` reads them)."""
    from mftire.parallel import WORKER_TIMEOUT_S

    parser.add_argument("--jobs", type=int, default=0, metavar="N",
                        help=f"local worker processes for {what} (default 0: all cores; 1: no pool); "
                        "the result does not depend on it")  # fmt: skip
    parser.add_argument("--scheduler", metavar="ADDRESS",
                        help=f"run {what} on a Dask distributed cluster at ADDRESS (e.g. tcp://host:8786; "
                        "needs pip install 'mftire[dask]' here, on the scheduler and on the workers; the outputs "
                        "are written here, the workers need no shared folder)")  # fmt: skip
    parser.add_argument("--worker-timeout", type=float, default=WORKER_TIMEOUT_S, metavar="S",
                        help=f"with --scheduler: end the run (exit 2, nothing written) when the cluster has had "
                        f"no worker for S seconds (default {WORKER_TIMEOUT_S:g})")  # fmt: skip
