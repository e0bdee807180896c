"""mftire: Magic Formula (Pacejka MF 6.1/6.2) tyre model toolkit.

The top level offers the parameter-file API and the tyre object:

* :func:`load` -> :class:`Tyre` with :meth:`Tyre.evaluate`;
* :func:`read_tir` / :func:`write_tir` for lossless ``.tir`` access;
* :class:`TirError` for bad property files.
"""

from mftire._lazy import lazy_names
from mftire.errors import MftireError, MftireInputError
from mftire.iotools.tir import TirError, TirParameters, read_tir, write_tir

# imported on first use (start-up of the command line, see mftire._lazy)
__getattr__, __dir__ = lazy_names(
    __name__, {"OUTPUT_NAMES": "mftire.mf.solver", "MFResult": "mftire.tyre", "Tyre": "mftire.tyre",
               "load": "mftire.tyre"}
)

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
