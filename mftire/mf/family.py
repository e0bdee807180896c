"""Model codes of the evaluator: which equation family a flat parameter dict selects.

The evaluator dispatches on ``p["FITTYP"]``.  :class:`mftire.tyre.Tyre` writes there the
model code of the file's model (:data:`MODEL_CODES`, keyed by
:attr:`mftire.iotools.tir.TirParameters.model`): 6 for MF 5.2 (FITTYP 6 or 21, or a file
that says ``'MF_52'``), 61 and 62 for MF 6.1 / 6.2, and :data:`PAC2002_CODE` for a
PAC2002 file and for an MF-Tyre 5.0 file (FITTYP 5 / ``'MF_05'``, evaluated with the
PAC2002 equations: ``docs/pac2002.md``).  These numbers are internal model codes of the
evaluator: they are never written to a ``.tir`` file and never reported as the file's
FITTYP (:attr:`mftire.tyre.Tyre.fittyp` is the file's own, None when it has none, and
:attr:`mftire.tyre.Tyre.format` names what the file says).

PAC2002 shares the MF 5.2 (FITTYP 6) code paths; :mod:`mftire.mf.pac2002` holds its
differences (see ``docs/pac2002.md``).
"""

from __future__ import annotations

from mftire.mf.spec import FAMILIES, PAC2002_CODE

__all__ = ["MF52_FAMILY", "MODEL_CODES", "PAC2002_CODE", "is_mf52", "is_pac2002"]

#: Model codes that take the MF 5.2 equations (FITTYP 6 as MFeval, and PAC2002).
MF52_FAMILY = (6.0, PAC2002_CODE)


def is_mf52(p: dict) -> bool:
    """True for the MF 5.2 equation family (FITTYP 6 and PAC2002)."""
    return p["FITTYP"] in MF52_FAMILY


def is_pac2002(p: dict) -> bool:
    """True for a PAC2002 parameter set (model code :data:`PAC2002_CODE`)."""
    return p.get("FITTYP") == PAC2002_CODE


#: Model (:attr:`mftire.iotools.tir.TirParameters.model`) -> model code of the evaluator
#: (:data:`mftire.mf.spec.FAMILIES`; MF-Tyre 5.0, ``MF_05``, takes the PAC2002 equations: docs/pac2002.md).
MODEL_CODES: dict[str, float] = {f.name: f.code for f in FAMILIES}
