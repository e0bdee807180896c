"""The ``.tir`` keys the evaluator reads, taken from the evaluator's own source.

The reader (:mod:`mftire.iotools.tir`) is tolerant of a blank or non-numeric value
on a key the evaluator does not use (a warning, the key treated as absent) and
strict on a key it uses (an error).  So that this set cannot drift from the code, it
is collected from the ``p["KEY"]`` / ``p.get("KEY")`` look-ups in the modules of
:mod:`mftire.mf` and :mod:`mftire.extensions`, plus the keys the PAC2002
preparation reads through tables (:mod:`mftire.mf.pac2002`).
"""

from __future__ import annotations

import functools
import re
from pathlib import Path

_LOOKUP = re.compile(r"""\bp(?:\[|\.get\()\s*["']([A-Z][A-Z0-9_]*)["']""")


@functools.cache
def evaluator_keys() -> frozenset[str]:
    """Upper-case keys read by the steady-state evaluator (any model family)."""
    from mftire.mf import pac2002

    here = Path(__file__).resolve().parent
    sources = [*sorted(here.glob("*.py")), here.parent / "extensions.py"]
    keys: set[str] = {"FITTYP", "PROPERTY_FILE_FORMAT"}
    for path in sources:
        try:
            keys.update(_LOOKUP.findall(path.read_text(encoding="utf-8")))
        except OSError:  # pragma: no cover - source not shipped
            continue
    for factor, coefficients in pac2002._CAMBER_FOLD.items():
        keys.add(factor)
        keys.update(k for k, _ in coefficients)
    keys.update(pac2002._PRESSURE)
    keys.update(pac2002._RENAMED)
    keys.update(pac2002._UNUSED_ROLLING)
    return frozenset(keys)
