"""Options shared by the sub-commands of the command line (the CLI layer; nothing below imports it)."""

from __future__ import annotations

import argparse
from typing import Any

from mftire.iotools.output import FORCE_HELP

__all__ = ["add_force_option", "add_parallel_options", "add_quiet_option", "progress_of"]


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
    """Add ``--jobs N`` and ``--scheduler ADDRESS`` to an argparse parser (``what`` runs in parallel)."""
    parser.add_argument("--jobs", type=int, default=0, metavar="N",
                        help=f"local worker processes for {what} (default 0: all cores; 1: no pool); "
                        "the result does not depend on it")  # fmt: skip
    parser.add_argument("--scheduler", metavar="ADDRESS",
                        help=f"run {what} on a Dask distributed cluster at ADDRESS (e.g. tcp://host:8786; "
                        "needs pip install 'mftire[dask]' here and on the workers)")  # fmt: skip
