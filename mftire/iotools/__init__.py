"""File input/output and the data layer, the lowest layer of mftire (imports nothing above it).

``.tir`` tyre property files (:mod:`~mftire.iotools.tir`, re-exported here), the sweep
table (:mod:`~mftire.iotools.sweeps`: schema, column aliases, validation, grouping),
TYDEX (:mod:`~mftire.iotools.tydex`), the shared loaders (:mod:`~mftire.iotools.loaders`),
the unit table (:mod:`~mftire.iotools.units`), the label columns
(:mod:`~mftire.iotools.columns`) and atomic writes (:mod:`~mftire.iotools.atomic`).
"""

from mftire.iotools.tir import (
    DuplicateKeyError,
    EmptyFileError,
    FittypError,
    MalformedLineError,
    MissingFittypError,
    NonNumericValueError,
    TirError,
    TirParameters,
    TirTable,
    UnknownFittypError,
    UnknownUnitError,
    format_tir,
    parse_tir,
    read_tir,
    write_tir,
)

__all__ = [
    "DuplicateKeyError",
    "EmptyFileError",
    "FittypError",
    "MalformedLineError",
    "MissingFittypError",
    "NonNumericValueError",
    "TirError",
    "TirParameters",
    "TirTable",
    "UnknownFittypError",
    "UnknownUnitError",
    "format_tir",
    "parse_tir",
    "read_tir",
    "write_tir",
]
