"""Curve comparison: MF models from ``.tir`` files against FE-surrogate and measured sweeps.

=============  ====================================================================
``data``       loading (measured + FE), grouping, curve families, plotting grids
``models``     model evaluation at the data's exact operating points and on grids
``tables``     RMS / peak errors per curve, stiffness vs load, trail vs α, free rolling
``plots``      one figure per family (+ stiffness, trail, free rolling), bands drawn
``core``       :func:`compare`, :class:`Comparison`, :func:`write_comparison`
``cli``        ``mftire compare``
=============  ====================================================================

>>> from mftire.compare import compare, load_comparison_data, write_comparison
>>> data = load_comparison_data(["rig.csv"], fe=["fe/sweeps.csv"])      # doctest: +SKIP
>>> comp = compare(["fitted.tir", "template.tir"], data)                 # doctest: +SKIP
>>> write_comparison(comp, "compare_out")                                # doctest: +SKIP
"""

from mftire.compare.core import Comparison, bands_frame, compare, write_comparison
from mftire.compare.data import curve_grid, load_comparison_data, prepare_comparison_data
from mftire.compare.models import evaluate_at, load_models
from mftire.compare.tables import (
    curve_errors,
    error_summary,
    free_rolling_table,
    linear_stiffness,
    stiffness_table,
    trail_points,
    trail_summary,
)

__all__ = [
    "Comparison",
    "bands_frame",
    "compare",
    "write_comparison",
    "curve_grid",
    "load_comparison_data",
    "prepare_comparison_data",
    "evaluate_at",
    "load_models",
    "curve_errors",
    "error_summary",
    "free_rolling_table",
    "linear_stiffness",
    "stiffness_table",
    "trail_points",
    "trail_summary",
]
