"""FE surrogate: physical steady-state rolling-contact (brush) model.

A discretised contact patch of Kelvin-Voigt tread elements on a flexible carcass, with the
pressure- and sliding-velocity-dependent friction law of van der Steen (2010).  See
docs/fe_surrogate.md for the model and the solution scheme.

>>> from mftire.fe import load_tyre, sweep
>>> tyre = load_tyre("default")
>>> df = sweep(tyre, "braking", 0.8 * tyre.load_index_load, 60 / 3.6, tyre.size.nominal_pressure)  # doctest: +SKIP
"""

from mftire.fe.config import TyreConfig, load_tyre
from mftire.fe.identify import IdentifiedFriction, identify_velocity_law
from mftire.fe.solver import SteadyStateResult, solve
from mftire.fe.sweeps import campaign, free_rolling, sweep

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
