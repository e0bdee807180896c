"""FMU export: the Magic Formula as a self-contained FMI 2.0 / 3.0 block in C.

>>> from mftire.fmu import export_fmu
>>> export_fmu("tyre.tir", "tyre.fmu")            # doctest: +SKIP
"""

from mftire._lazy import lazy_names

# imported on first use (see mftire._lazy)
__getattr__, __dir__ = lazy_names(
    __name__, {"FMUExportError": "mftire.fmu.export", "export_fmu": "mftire.fmu.export"}
)

__all__ = ["FMUExportError", "export_fmu"]
