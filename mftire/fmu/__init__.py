"""FMU export: the Magic Formula as a self-contained FMI 2.0 / 3.0 block in C.

>>> from mftire.fmu import export_fmu
>>> export_fmu("tyre.tir", "tyre.fmu")            # doctest: +SKIP
"""

from mftire.fmu.export import FMUExportError, export_fmu

__all__ = ["FMUExportError", "export_fmu"]
