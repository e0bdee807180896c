"""Exception classes shared across mftire."""

from __future__ import annotations


class MftireError(Exception):
    """Base class of every error mftire raises on purpose (the CLI exits 2 on these)."""


class MftireInputError(MftireError, ValueError):
    """Bad user input: a missing column, a non-numeric cell, a NaN, an out-of-range value."""
