"""File input/output: ``.tir`` tyre property files (:mod:`mftire.iotools.tir`)."""

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
