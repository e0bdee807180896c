"""Model codes of the evaluator: which equation family a flat parameter dict selects.

The evaluator dispatches on ``p["FITTYP"]``.  A file's own ``FITTYP`` (6, 61, 62) is
used as it is.  A PAC2002 file has no ``FITTYP``; :class:`mftire.tyre.Tyre` marks its
flat dict with :data:`PAC2002_CODE` instead.  That number is an internal model code of
the evaluator (it is never written to a ``.tir`` file and never reported as the
file's FITTYP: :attr:`mftire.tyre.Tyre.fittyp` is None and
:attr:`mftire.tyre.Tyre.format` is ``'PAC2002'``).

PAC2002 shares the MF 5.2 (FITTYP 6) code paths; :mod:`mftire.mf.pac2002` holds its
differences (see ``docs/pac2002.md``).
"""

from __future__ import annotations

#: Internal model code of a PAC2002 property file (no FITTYP in the file).
PAC2002_CODE = 2002.0

#: Model codes that take the MF 5.2 equations (FITTYP 6 as MFeval, and PAC2002).
MF52_FAMILY = (6.0, PAC2002_CODE)


def is_mf52(p: dict) -> bool:
    """True for the MF 5.2 equation family (FITTYP 6 and PAC2002)."""
    return p["FITTYP"] in MF52_FAMILY


def is_pac2002(p: dict) -> bool:
    """True for a PAC2002 parameter set (model code :data:`PAC2002_CODE`)."""
    return p.get("FITTYP") == PAC2002_CODE
