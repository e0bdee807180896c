"""Curve comparison: MF models from ``.tir`` files against FE-surrogate and measured sweeps.

=============  ====================================================================
``data``       loading (measured + FE), grouping, curve families, plotting grids
``models``     model evaluation at the data's exact operating points and on grids
``tables``     RMS / peak errors per curve, stiffness vs load, trail vs α, free rolling
``plots``      one figure per family (+ stiffness, trail, free rolling), bands drawn
``comparison`` :func:`compare`, :class:`Comparison`, :func:`write_comparison`
``cli``        ``mftire compare``
=============  ====================================================================

>>> from mftire.compare import compare, load_comparison_data, write_comparison
>>> data = load_comparison_data(["rig.csv"], fe=["fe/sweeps.csv"])      # doctest: +SKIP
>>> comp = compare(["fitted.tir", "template.tir"], data)                 # doctest: +SKIP
>>> write_comparison(comp, "compare_out")                                # doctest: +SKIP
"""

from mftire._lazy import lazy_names

# imported on first use (see mftire._lazy)
__getattr__, __dir__ = lazy_names(
    __name__, {"Comparison": "mftire.compare.comparison", "bands_frame": "mftire.compare.comparison",
     "compare": "mftire.compare.comparison", "write_comparison": "mftire.compare.comparison",
     "curve_grid": "mftire.compare.data", "load_comparison_data": "mftire.compare.data",
     "prepare_comparison_data": "mftire.compare.data", "evaluate_at": "mftire.compare.models",
     "load_models": "mftire.compare.models", "curve_errors": "mftire.compare.tables",
     "error_summary": "mftire.compare.tables", "free_rolling_table": "mftire.compare.tables",
     "linear_stiffness": "mftire.compare.tables", "stiffness_table": "mftire.compare.tables",
     "trail_points": "mftire.compare.tables", "trail_summary": "mftire.compare.tables"}
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
