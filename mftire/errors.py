"""Exception classes shared across mftire."""

from __future__ import annotations


class MftireError(Exception):
    """Base class of every error mftire raises on purpose (the CLI exits 2 on these)."""


class MftireInputError(MftireError, ValueError):
    """Bad user input: a missing column, a non-numeric cell, a NaN, an out-of-range value."""


class MftireWarning(UserWarning):
    """Base class of the warnings mftire issues on purpose (the CLI prints them as one line)."""


class MftireTirWarning(MftireWarning):
    """A ``.tir`` file that loads but is suspicious: optional sections missing, implausible values."""


class MftireUnitWarning(MftireWarning):
    """Inputs that look like the wrong unit (degrees for radians, kN for N); see :mod:`mftire.tyre`."""


class Terminated(KeyboardInterrupt):
    """SIGTERM during a command (:func:`mftire.cli.main`): raised like Ctrl-C's KeyboardInterrupt so that
    workers, compilers and temporary folders are cleaned up on the way out."""
