"""JSON for reports: numpy and pandas values to plain JSON, written atomically."""

from __future__ import annotations

import datetime as _dt
import json
import os
from collections.abc import Mapping
from typing import Any

import numpy as np
import pandas as pd

from mftire.iotools.atomic import write_text_atomic


def jsonable(x: Any) -> Any:
    """Plain-JSON copy of ``x``: numpy scalars and arrays to Python, NaN/inf to None,
    dates to ISO strings, mapping keys to strings."""
    if isinstance(x, Mapping):
        return {str(k): jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [jsonable(v) for v in x]
    if isinstance(x, np.ndarray):
        return jsonable(x.tolist())
    if isinstance(x, (float, np.floating)):
        return float(x) if np.isfinite(x) else None
    if isinstance(x, np.integer):
        return int(x)
    if isinstance(x, np.bool_):
        return bool(x)
    if isinstance(x, (pd.Timestamp, _dt.datetime, _dt.date)):
        return x.isoformat()
    if x is pd.NA or x is None:
        return None
    return x


def write_json_atomic(path: str | os.PathLike, obj: Any, indent: int = 1) -> None:
    """Write ``jsonable(obj)`` as strict JSON (no NaN) to ``path`` atomically."""
    write_text_atomic(path, json.dumps(jsonable(obj), indent=indent, allow_nan=False) + "\n")
