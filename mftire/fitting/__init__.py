"""Magic Formula 6.1/6.2 parameter fitting to slip sweeps.

Small pure functions in the spirit of pvlib's ``ivtools``:

=================  ================================================================
``stages``         the seven stages: coefficients, bounds, identifiability needs
``identify``       which coefficients the data can identify (loads, cambers, ...)
``initial``        start values from the data (peak, slope at zero, shape, shifts)
``model``          fast channel predictions (only the equations a stage needs)
``weights``        per-source weights, noise estimate (loaders: :mod:`mftire.iotools.loaders`)
``fitter``         :func:`fit_tir`, :class:`FitResult`, :class:`StageResult`
``fit_report``     report.md, metrics.json and one PNG per sweep family
``synthetic``      synthetic sweeps from a ``.tir`` (tests, benchmark)
``bands``          bootstrap confidence and prediction bands over sweeps
``fit_batch``      one fit per input file as a task (``mftire fit --each``)
``cli``            ``mftire fit``
=================  ================================================================
"""

from mftire._lazy import lazy_names

# imported on first use (see mftire._lazy)
__getattr__, __dir__ = lazy_names(
    __name__, {"FitResult": "mftire.fitting.fitter", "StageResult": "mftire.fitting.fitter",
     "fit_tir": "mftire.fitting.fitter", "STAGES": "mftire.fitting.stages",
     "resolve_stages": "mftire.fitting.stages"}
)

__all__ = ["FitResult", "StageResult", "fit_tir", "STAGES", "resolve_stages"]
