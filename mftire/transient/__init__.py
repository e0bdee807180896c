"""Transient tyre block (public path ``mftire.transient``): the model lives in :mod:`mftire.transient.slip_dynamics`.

Its FMU export (C source, FMI wrappers) lives in :mod:`mftire.fmu`.
"""

from mftire.transient.slip_dynamics import *  # noqa: F403
from mftire.transient.slip_dynamics import FREE_ROLLING, TRANSIENT_OUTPUTS, __all__  # noqa: F401
