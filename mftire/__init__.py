"""mftire: Magic Formula (Pacejka MF 6.1/6.2) tyre model toolkit."""

__version__ = "0.1.0"
