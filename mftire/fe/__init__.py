"""FE surrogate: physical steady-state rolling-contact (brush) model.

A discretised contact patch of Kelvin-Voigt tread elements on a flexible carcass, with the
pressure- and sliding-velocity-dependent friction law of van der Steen (2010).  See
docs/fe_surrogate.md for the model and the solution scheme.

>>> from mftire.fe import load_tyre, sweep
>>> tyre = load_tyre("default")
>>> df = sweep(tyre, "braking", 0.8 * tyre.load_index_load, 60 / 3.6, tyre.size.nominal_pressure)  # doctest: +SKIP
"""

from mftire._lazy import lazy_names

# imported on first use (see mftire._lazy)
__getattr__, __dir__ = lazy_names(
    __name__, {"TyreConfig": "mftire.fe.config", "load_tyre": "mftire.fe.config",
     "IdentifiedFriction": "mftire.fe.friction_identify", "identify_velocity_law": "mftire.fe.friction_identify",
     "SteadyStateResult": "mftire.fe.rolling_contact", "solve": "mftire.fe.rolling_contact",
     "campaign": "mftire.fe.slip_sweeps", "free_rolling": "mftire.fe.slip_sweeps", "sweep": "mftire.fe.slip_sweeps"}
)

__all__ = [
    "IdentifiedFriction",
    "SteadyStateResult",
    "TyreConfig",
    "campaign",
    "free_rolling",
    "identify_velocity_law",
    "load_tyre",
    "solve",
    "sweep",
]
