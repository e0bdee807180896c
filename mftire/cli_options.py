"""Options shared by the sub-commands of the command line (the CLI layer; nothing below imports it)."""

from __future__ import annotations

import argparse

__all__ = ["add_quiet_option", "progress_of"]


def add_quiet_option(parser: argparse.ArgumentParser) -> None:
    """``--quiet``: no progress lines (they go to stderr, and only when it is a terminal)."""
    parser.add_argument("--quiet", "-q", action="store_true",
                        help="no progress lines on stderr (shown only on a terminal anyway)")


def progress_of(args: argparse.Namespace) -> bool | None:
    """The ``progress=`` of the API for parsed ``args``: False with ``--quiet``, else None (on a terminal)."""
    return False if getattr(args, "quiet", False) else None
