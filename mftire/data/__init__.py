"""Data shipped with mftire (see NOTICE.md): the default ``.tir``."""

from __future__ import annotations

from importlib import resources


def default_tir() -> str:
    """Path of the shipped default ``.tir`` (MF 6.1, 255/55 R20, MFeval example; see NOTICE.md)."""
    return str(resources.files(__name__) / "default.tir")
