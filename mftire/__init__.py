"""mftire: Magic Formula (Pacejka MF 6.1/6.2) tyre model toolkit.

The top level offers the parameter-file API and the tyre object:

* :func:`load` -> :class:`Tyre` with :meth:`Tyre.evaluate`;
* :func:`read_tir` / :func:`write_tir` for lossless ``.tir`` access;
* :class:`TirError` for bad property files.
"""

from mftire.errors import MftireError, MftireInputError
from mftire.iotools.tir import TirError, TirParameters, read_tir, write_tir
from mftire.mf.solver import OUTPUT_NAMES
from mftire.tyre import MFResult, Tyre, load

__version__ = "0.1.0"

__all__ = [
    "OUTPUT_NAMES",
    "MFResult",
    "MftireError",
    "MftireInputError",
    "TirError",
    "TirParameters",
    "Tyre",
    "load",
    "read_tir",
    "write_tir",
]
