"""Model extensions (public path): see :mod:`mftire.mf.extensions`, their one home."""

from mftire.mf.extensions import *  # noqa: F403
from mftire.mf.extensions import __all__  # noqa: F401
