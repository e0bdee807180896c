"""Column vocabulary beyond the sweep schema: the labels mftire adds, and what is not a variable.

The schema columns themselves (inputs, measured channels), their aliases and their units
are in :mod:`mftire.iotools.sweeps` and :mod:`mftire.iotools.units`.
"""

from __future__ import annotations

from mftire.iotools.sweeps import MEASURED_COLUMNS, OPTIONAL_INPUT_COLUMNS, REQUIRED_COLUMNS

__all__ = ["GROUPING_COLUMNS", "SET_POINT_COLUMNS", "CURVE_COLUMNS", "LABEL_COLUMNS", "NOT_VARIABLES"]

#: Columns :func:`mftire.segmentation.grouping.group_sweeps` adds: set points and sweep labels.
GROUPING_COLUMNS: tuple[str, ...] = ("Fz_set", "gamma_set", "P_set", "Vx_set", "sweep_id", "kind", "sweep_var",
                                     "kappa_set", "alpha_set", "sweep_dir", "direction")  # fmt: skip
#: The set-point column of each operating condition (the set points among :data:`GROUPING_COLUMNS`).
SET_POINT_COLUMNS: dict[str, str] = {"Fz": "Fz_set", "Vx": "Vx_set", "P": "P_set", "gamma": "gamma_set"}
#: Columns the comparison adds on top (see :mod:`mftire.compare.data`).
CURVE_COLUMNS: tuple[str, ...] = ("family", "var", "held", "curve_id")
#: Bookkeeping columns of loaders, campaigns and fits.
LABEL_COLUMNS: tuple[str, ...] = ("source", "file", "origin", "load_fraction", "meas_no", "weight", "fit_row",
                                  "drop_reason")  # fmt: skip
#: Columns that are never a model-extension variable (nor a diagnosis candidate): the MF
#: inputs (``omega`` included), the measured channels and every label above.
NOT_VARIABLES: frozenset[str] = frozenset({*REQUIRED_COLUMNS, *OPTIONAL_INPUT_COLUMNS, "omega", *MEASURED_COLUMNS,
                                           *GROUPING_COLUMNS, *CURVE_COLUMNS, *LABEL_COLUMNS})  # fmt: skip
