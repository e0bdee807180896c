"""Read and write TYDEX measurement files (``.tdx``) as sweep tables.

TYDEX ("TYDEX-Format Description and Reference Manual, Release 1.3", Unrau and Zamow,
1997) is the plain-text exchange format for tyre measurements. A file is a sequence of
blocks opened by ``**KEYWORD`` lines:

``**HEADER``          release, supplier, date, time
``**COMMENTS``        free text
``**CONSTANTS``       key, comment, unit, value (one per line)
``**MEASURCHANNELS``  key, comment, unit, conversion factor, offset (one per channel)
``**MEASURDATA``      one row of numbers per measured point, channels in order
``**MODEL...``        model blocks (ignored here)
``**END``

Lines starting with ``!`` are comments; ``!---!---!`` rulers, when present, give the
field columns. The fields are fixed-width (key 10, comment 30, unit 10 characters, then
the values) but many files are only whitespace-aligned, so both are accepted.

:func:`read_tydex` maps the standard W-axis channel names to the sweep schema of
:mod:`mftire.iotools.sweeps` and converts the file's own units to SI:

=========== ============ ===========================================
TYDEX       column       SI unit
=========== ============ ===========================================
LONGSLIP    kappa        - (``%`` is divided by 100)
SLIPANGL    alpha        rad
INCLANGL    gamma        rad
RUNSPEED    Vx           m/s
INFLPRES    P            Pa
FZW, FZ     Fz           N
FXW, FX     Fx           N
FYW, FY     Fy           N
MXW, MX     Mx           N·m
MYW, MY     My           N·m
MZW, MZ     Mz           N·m
MEASNUMB    meas_no      -
RUNTIME     time         s
TYREDEFL    deflection   m
ROLLRADI    Re           m (effective rolling radius)
LOADRADI    Rl           m (loaded radius)
TYRESPED    omega        rad/s (wheel angular speed)
=========== ============ ===========================================

W-suffixed names win when both forms are present; the other one is kept under its own
name. Other axis systems (``FXH``, ``FYC``, ...) are kept unconverted under their names.
"""

from __future__ import annotations

import io
import math
import os
import re
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from datetime import datetime
from typing import Any

import numpy as np
import pandas as pd

from mftire.errors import MftireInputError
from mftire.iotools.atomic import write_text_atomic
from mftire.iotools.sweeps import convert_from_si, to_numbers, validate_sweeps
from mftire.iotools.units import DIMENSIONS, SI_UNITS, is_known_unit, unit_factor

__all__ = ["TYDEX_CHANNELS", "TYDEX_VARIABLES", "read_tydex", "write_tydex", "parse_tydex"]

PathLike = str | os.PathLike[str]

#: The one variable map of TYDEX: schema column -> (TYDEX keys, best name first; the comment of the
#: first key as :func:`write_tydex` writes it).  The order is the order of the written channels.
TYDEX_VARIABLES: dict[str, tuple[tuple[str, ...], str]] = {
    "meas_no": (("MEASNUMB",), "Measurement point number"),
    "time": (("RUNTIME",), "Time"),
    "kappa": (("LONGSLIP",), "Longitudinal slip"),
    "alpha": (("SLIPANGL",), "Slip angle"),
    "gamma": (("INCLANGL",), "Inclination angle"),
    "Vx": (("RUNSPEED",), "Running speed"),
    "P": (("INFLPRES",), "Inflation pressure"),
    "Fz": (("FZW", "FZ"), "Vertical force W-axis"),
    "Fx": (("FXW", "FX"), "Longitudinal force W-axis"),
    "Fy": (("FYW", "FY"), "Lateral force W-axis"),
    "Mx": (("MXW", "MX"), "Overturning moment W-axis"),
    "My": (("MYW", "MY"), "Rolling resistance moment W"),
    "Mz": (("MZW", "MZ"), "Aligning moment W-axis"),
    "deflection": (("TYREDEFL",), "Tyre deflection"),
    "Re": (("ROLLRADI",), "Effective rolling radius"),
    "Rl": (("LOADRADI",), "Loaded radius"),
    "omega": (("TYRESPED",), "Wheel angular speed"),
}
#: Schema column for each known TYDEX key, best name first (from :data:`TYDEX_VARIABLES`).
TYDEX_CHANNELS: dict[str, tuple[str, ...]] = {col: keys for col, (keys, _) in TYDEX_VARIABLES.items()}
_KEY_TO_COLUMN: dict[str, tuple[str, int]] = {
    key: (col, rank) for col, keys in TYDEX_CHANNELS.items() for rank, key in enumerate(keys)
}
_MODEL_BLOCKS = {"MODELDEFINITION", "MODELPARAMETERS", "MODELCOEFFICIENTS", "MODELCHANNELS",
                 "MODELOUTPUTS", "MODELEND"}
_KNOWN_BLOCKS = {"HEADER", "COMMENTS", "CONSTANTS", "MEASURCHANNELS", "MEASURDATA", "END"}
#: Unit names as TYDEX files write them, where they differ from mftire's one spelling.
_TYDEX_SPELLING = {"N.m": "Nm"}
_NA_TOKENS = ["NOTAVAIL", "NaN", "nan", "NAN", "N/A", "NA", "-"]
_DEFAULT_CUTS = (10, 40, 50)
_NUMBER_RE = re.compile(r"NOTAVAIL|[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?")


@dataclass
class _Field:
    key: str
    comment: str
    unit: str
    values: list[str]
    line: int
    unit_guess: str = ""


@dataclass
class TydexFile:
    """Parsed content of one TYDEX file (before conversion)."""

    path: str
    header: dict[str, str] = field(default_factory=dict)
    comments: list[str] = field(default_factory=list)
    constants: list[_Field] = field(default_factory=list)
    channels: list[_Field] = field(default_factory=list)
    data: pd.DataFrame | None = None
    warnings: list[str] = field(default_factory=list)


def _is_number(token: str) -> bool:
    try:
        float(token)
    except ValueError:
        return False
    return True


def _known_unit(unit: str) -> bool:
    return is_known_unit(unit)


def _ruler_cuts(line: str) -> tuple[int, int, int] | None:
    """Field boundaries from a ``!----!----!`` ruler or ``! Key ! Comment !`` line."""
    bangs = [i for i, ch in enumerate(line) if ch == "!"]
    if len(bangs) >= 4 and bangs[0] == 0:
        return bangs[1], bangs[2], bangs[3]
    return None


def _straddles(line: str, cut: int) -> bool:
    """True when a token runs across column ``cut``."""
    return 0 < cut < len(line) and not line[cut - 1].isspace() and not line[cut].isspace()


def _split_fixed(line: str, cuts: tuple[int, int, int]) -> tuple[str, str, str, str] | None:
    c0, c1, c2 = cuts
    tokens = line.split()
    if len(line) <= c2 or line[:c0].split() != tokens[:1] or not tokens:
        return None
    if _straddles(line, c0) or _straddles(line, c1) or _straddles(line, c2):
        return None
    rest = line[c2:].strip()
    if not rest:
        return None
    return tokens[0], line[c0:c1].strip(), line[c1:c2].strip(), rest


def _split_whitespace(tokens: list[str], n_values: int | None) -> tuple[str, str, list[str], str]:
    """(comment, unit, values, unit_guess) from whitespace tokens after the key.

    ``n_values=None``: values are the trailing numbers (up to 3); otherwise the last
    ``n_values`` tokens.
    """
    body = tokens[1:]
    if n_values is None:
        nums: list[str] = []
        while body and len(nums) < 3 and _is_number(body[-1]):
            nums.insert(0, body.pop())
        values = nums
    else:
        values = body[-n_values:] if len(body) >= n_values else body[:]
        body = body[: len(body) - len(values)]
    unit = ""
    guess = body[-1] if body else ""
    if len(body) >= 2 and _known_unit(" ".join(body[-2:])) and not _known_unit(body[-1]):
        unit = " ".join(body[-2:])
        body = body[:-2]
    elif body and _known_unit(body[-1]):
        unit = body[-1]
        body = body[:-1]
    return " ".join(body), unit, values, guess


def _parse_channel(line: str, lineno: int, cuts: tuple[int, int, int]) -> _Field:
    tokens = line.split()
    fixed = _split_fixed(line, cuts)
    if fixed is not None:
        key, comment, unit, rest = fixed
        vals = rest.split()
        ok = 1 <= len(vals) <= 3 and all(_is_number(v) for v in vals)
        ok = ok and (unit == "" or _known_unit(unit) or " " not in unit)
        if ok:
            ws = _split_whitespace(tokens, None)
            if _known_unit(unit) or unit == "" or not _known_unit(ws[1]):
                return _Field(key, comment, unit, vals, lineno, unit_guess=unit)
    comment, unit, vals, guess = _split_whitespace(tokens, None)
    return _Field(tokens[0], comment, unit, vals, lineno, unit_guess=guess)


def _parse_constant(line: str, lineno: int, cuts: tuple[int, int, int]) -> _Field | None:
    tokens = line.split()
    if len(tokens) < 2:
        return None
    fixed = _split_fixed(line, cuts)
    if fixed is not None:
        key, comment, unit, rest = fixed
        ws = _split_whitespace(tokens, 1)
        if _known_unit(unit) or unit == "" or not _known_unit(ws[1]):
            return _Field(key, comment, unit, [rest], lineno, unit_guess=unit)
    comment, unit, vals, guess = _split_whitespace(tokens, 1)
    return _Field(tokens[0], comment, unit, vals, lineno, unit_guess=guess)


def _read_lines(path: str) -> list[str]:
    try:
        with open(path, encoding="utf-8") as fh:
            text = fh.read()
    except UnicodeDecodeError:
        with open(path, encoding="latin-1") as fh:
            text = fh.read()
    except OSError as exc:
        raise MftireInputError(f"cannot read TYDEX file {path}: {exc}") from exc
    return [ln.rstrip("\r\n").expandtabs(8) for ln in text.splitlines()]


def _parse_data(path: str, rows: list[tuple[int, str]], keys: list[str]) -> pd.DataFrame:
    n = len(keys)
    texts: list[str] = []
    for lineno, text in rows:
        count = len(text.split())
        if count != n:
            # fixed-width numbers may touch ("-12.000-0.500"): split on number patterns
            tokens = _NUMBER_RE.findall(text)
            if len(tokens) != n or "".join(tokens) != "".join(text.split()):
                raise MftireInputError(
                    f"{path}:{lineno}: **MEASURDATA row has {count} values, expected {n} "
                    f"(one per channel in **MEASURCHANNELS)"
                )
            text = " ".join(tokens)
        texts.append(text)
    table = pd.read_csv(io.StringIO("\n".join(texts)), sep=r"\s+", header=None, names=keys,
                        na_values=_NA_TOKENS, dtype=str, engine="c")
    out = pd.DataFrame(index=table.index)
    for j, key in enumerate(keys):
        raw = table.iloc[:, j]
        num, i = to_numbers(raw)
        if i is not None:
            raise MftireInputError(
                f"{path}:{rows[i][0]}: channel {key!r} value {raw.iloc[i]!r} is not a number"
            )
        out[key] = num.astype(float)
    return out


def parse_tydex(path: PathLike) -> TydexFile:
    """Parse one TYDEX file into its blocks, without unit conversion.

    Returns
    -------
    TydexFile
        ``header`` (key -> value text), ``comments`` (lines), ``constants`` and
        ``channels`` (key, comment, unit, values as text, line number) and ``data``
        (raw numbers, one column per channel key, NaN for ``NOTAVAIL``).

    Raises
    ------
    MftireInputError
        Naming the file and line: content before the first ``**`` keyword, a channel
        line without a key, duplicate channels, a row with the wrong number of values,
        a non-numeric value, missing ``**MEASURCHANNELS`` or ``**MEASURDATA`` blocks, or
        no data rows.
    """
    p = os.fspath(path)
    lines = _read_lines(p)
    out = TydexFile(path=p)
    block: str | None = None
    seen: set[str] = set()
    cuts = _DEFAULT_CUTS
    data_rows: list[tuple[int, str]] = []
    ended = False
    for lineno, line in enumerate(lines, start=1):
        stripped = line.strip()
        if not stripped:
            continue
        if stripped.startswith("**"):
            name = stripped[2:].split()[0].upper() if stripped[2:].split() else ""
            if name not in _KNOWN_BLOCKS and name not in _MODEL_BLOCKS:
                out.warnings.append(f"line {lineno}: unknown block **{name} ignored")
            if name in seen and name in ("MEASURCHANNELS", "MEASURDATA"):
                raise MftireInputError(f"{p}:{lineno}: second **{name} block")
            seen.add(name)
            block = name
            cuts = _DEFAULT_CUTS
            if name == "END":
                ended = True
                break
            continue
        if stripped.startswith("!"):
            if block in ("HEADER", "CONSTANTS", "MEASURCHANNELS"):
                found = _ruler_cuts(line)
                if found is not None:
                    cuts = found
            if block == "COMMENTS":
                out.comments.append(stripped[1:].strip())
            continue
        if block is None:
            raise MftireInputError(
                f"{p}:{lineno}: text before the first ** keyword: {stripped[:40]!r} "
                "(is this a TYDEX file?)"
            )
        if block == "HEADER":
            f = _parse_constant(line, lineno, cuts)
            if f is not None:
                out.header[f.key] = f.values[0] if f.values else ""
        elif block == "COMMENTS":
            out.comments.append(stripped)
        elif block == "CONSTANTS":
            f = _parse_constant(line, lineno, cuts)
            if f is None:
                out.warnings.append(f"line {lineno}: constant without a value ignored: {stripped!r}")
            else:
                out.constants.append(f)
        elif block == "MEASURCHANNELS":
            ch = _parse_channel(line, lineno, cuts)
            if _is_number(ch.key):
                raise MftireInputError(
                    f"{p}:{lineno}: **MEASURCHANNELS line starts with a number, not a channel "
                    f"name: {stripped[:40]!r} (is **MEASURDATA missing?)"
                )
            out.channels.append(ch)
        elif block == "MEASURDATA":
            data_rows.append((lineno, line))
        # model blocks and unknown blocks: ignored
    if not ended:
        out.warnings.append("no **END keyword")
    if "MEASURCHANNELS" not in seen:
        raise MftireInputError(f"{p}: no **MEASURCHANNELS block (is this a TYDEX measurement file?)")
    if "MEASURDATA" not in seen:
        raise MftireInputError(f"{p}: no **MEASURDATA block")
    if not out.channels:
        raise MftireInputError(f"{p}: **MEASURCHANNELS block lists no channels")
    keys = [c.key for c in out.channels]
    dups = sorted({k for k in keys if keys.count(k) > 1})
    if dups:
        line = next(c.line for c in out.channels if c.key == dups[0])
        raise MftireInputError(f"{p}:{line}: channel {dups[0]!r} listed twice in **MEASURCHANNELS")
    if not data_rows:
        raise MftireInputError(f"{p}: **MEASURDATA block has no data rows")
    out.data = _parse_data(p, data_rows, keys)
    return out


def _si_factor(path: str, f: _Field, column: str) -> float:
    """SI factor for a mapped channel/constant, with a file:line error on a bad unit."""
    dim = DIMENSIONS[column]
    if dim == "count":
        return 1.0
    unit = f.unit
    if unit == "" and dim != "ratio":
        shown = f" (found {f.unit_guess!r})" if f.unit_guess else ""
        raise MftireInputError(
            f"{path}:{f.line}: no known unit for {f.key} ({column}, SI unit {SI_UNITS[column]}){shown}"
        )
    try:
        return unit_factor(unit, dim)
    except MftireInputError as exc:
        raise MftireInputError(f"{path}:{f.line}: {f.key}: {exc}") from None


def _conversion_numbers(path: str, ch: _Field) -> tuple[float, float, float]:
    nums = [float(v) for v in ch.values]
    factor = nums[0] if nums else 1.0
    offset = nums[1] if len(nums) > 1 else 0.0
    offset2 = nums[2] if len(nums) > 2 else 0.0
    if factor == 0 or not all(math.isfinite(v) for v in nums):
        raise MftireInputError(f"{path}:{ch.line}: channel {ch.key}: bad conversion factor {ch.values}")
    return factor, offset, offset2


def _tydex_to_frame(tf: TydexFile) -> tuple[pd.DataFrame, dict[str, str], dict[str, str]]:
    """Convert a parsed file to a sweep table: (frame, units_read, channel_map)."""
    assert tf.data is not None
    p = tf.path
    columns: dict[str, pd.Series] = {}
    units: dict[str, str] = {}
    cmap: dict[str, str] = {}
    # best TYDEX key for each schema column among the channels
    best: dict[str, tuple[int, str]] = {}
    for ch in tf.channels:
        hit = _KEY_TO_COLUMN.get(ch.key.upper())
        if hit is not None and (hit[0] not in best or hit[1] < best[hit[0]][0]):
            best[hit[0]] = (hit[1], ch.key)
    chosen = {key: col for col, (_, key) in best.items()}
    for ch in tf.channels:
        factor, offset, offset2 = _conversion_numbers(p, ch)
        values = tf.data[ch.key] * factor + offset + offset2
        col = chosen.get(ch.key)
        if col is not None:
            values = values * _si_factor(p, ch, col)
        else:
            col = ch.key
        columns[col] = values
        units[col] = ch.unit
        cmap[col] = ch.key
    n = len(tf.data)
    for c in tf.constants:
        raw = c.values[0] if c.values else ""
        hit = _KEY_TO_COLUMN.get(c.key.upper())
        if hit is not None and _is_number(raw):
            col = hit[0]
            value: Any = float(raw) * _si_factor(p, c, col)
            if col in columns:
                col = f"{col}_nominal"
        else:
            col = c.key if c.key not in columns else f"{c.key}_const"
            value = float(raw) if _is_number(raw) else raw
        if col in columns:
            tf.warnings.append(f"line {c.line}: constant {c.key} repeated; first value kept")
            continue
        columns[col] = pd.Series([value] * n, index=tf.data.index)
        units[col] = c.unit
        cmap[col] = c.key
    frame = pd.DataFrame(columns)
    frame["file"] = p
    return frame, units, cmap


def read_tydex(
    path_or_paths: PathLike | Iterable[PathLike],
    *,
    validate: bool = False,
    source: str | None = None,
    defaults: Mapping[str, float] | None = None,
) -> pd.DataFrame:
    """Read one or many TYDEX ``.tdx`` files into one sweep table (SI units).

    Parameters
    ----------
    path_or_paths : path-like or iterable of path-like
        One file or several (e.g. one per sweep).
    validate : bool
        Run :func:`mftire.iotools.sweeps.validate_sweeps` on the result (report stored
        in ``df.attrs["report"]``).
    source, defaults
        Passed to :func:`~mftire.iotools.sweeps.validate_sweeps` when ``validate``; e.g.
        ``defaults={"kappa": 0.0}`` for lateral files without a LONGSLIP channel.

    Returns
    -------
    DataFrame
        One row per measured point. Known channels (see module docstring) are renamed
        and converted to SI after applying the channel's conversion factor and offset
        (``value = factor * stored + offset``; a third number is added as a further
        offset). Other channels keep their TYDEX key and values in the file's unit.
        Every constant becomes a column: a known quantity fills its schema column in SI
        when no channel gives it (otherwise it goes to ``<column>_nominal``); others keep
        their key and value (number or text). A ``file`` column names the source file.

        ``df.attrs`` holds ``units_read`` (column -> unit as written in the file,
        ``"deg|rad"`` when files differ), ``channel_map`` (column -> TYDEX key) and
        ``tydex`` (per file: header, comments, warnings).

    Raises
    ------
    MftireInputError
        Naming file and line: malformed blocks, a row with the wrong number of values, a
        non-numeric value, an unknown unit of a known quantity, missing
        ``**MEASURCHANNELS``/``**MEASURDATA``.
    """
    if isinstance(path_or_paths, (str, os.PathLike)):
        paths = [path_or_paths]
    else:
        paths = list(path_or_paths)
    if not paths:
        raise MftireInputError("read_tydex: no files given")
    frames: list[pd.DataFrame] = []
    units_all: dict[str, set[str]] = {}
    cmap_all: dict[str, str] = {}
    meta: list[dict[str, Any]] = []
    for path in paths:
        tf = parse_tydex(path)
        frame, units, cmap = _tydex_to_frame(tf)
        frames.append(frame)
        for col, u in units.items():
            units_all.setdefault(col, set()).add(u)
        cmap_all.update(cmap)
        meta.append({
            "file": tf.path,
            "header": dict(tf.header),
            "comments": list(tf.comments),
            "units_read": dict(units),
            "warnings": list(tf.warnings),
        })
    df = pd.concat(frames, ignore_index=True, sort=False) if len(frames) > 1 else frames[0]
    df.attrs = {}
    if validate:
        name = ", ".join(m["file"] for m in meta)
        df, report = validate_sweeps(df, name, source=source, defaults=defaults)
        df.attrs["report"] = report.to_dict()
    df.attrs["units_read"] = {c: "|".join(sorted(u)) for c, u in units_all.items()}
    df.attrs["channel_map"] = cmap_all
    df.attrs["tydex"] = meta
    return df


def _fmt_field(text: str, width: int) -> str:
    text = str(text)
    if len(text) >= width:
        text = text[: width - 1]
    return f"{text:<{width}}"


def _check_key(key: str) -> str:
    if not key or any(ch.isspace() for ch in key) or len(key) > 9 or key.startswith(("!", "*")):
        raise MftireInputError(
            f"write_tydex: {key!r} cannot be a TYDEX key (1-9 characters, no blanks, "
            "not starting with ! or *); rename the column"
        )
    return key


def write_tydex(
    df: pd.DataFrame,
    path: PathLike,
    *,
    constants: Mapping[str, Any] | None = None,
    units: Mapping[str, str] | None = None,
    columns: Sequence[str] | None = None,
    header: Mapping[str, str] | None = None,
    comments: str | Sequence[str] | None = None,
    precision: int = 10,
) -> None:
    """Write a sweep table to a TYDEX file (fixed-width, W-axis names), atomically.

    Parameters
    ----------
    df : DataFrame
        Sweep table in SI. Schema and known extra columns present (``meas_no, time,
        kappa, alpha, gamma, Vx, P, Fz, Fx, Fy, Mx, My, Mz, deflection, Re, Rl, omega``)
        are written as channels under their TYDEX names.
    path : path-like
        Output file; written to a temporary file in the same folder, then moved into
        place with :func:`os.replace` (:func:`mftire.iotools.atomic.write_text_atomic`).
    constants : dict, optional
        ``{KEY: value}``, ``{KEY: (value, unit)}`` or ``{KEY: (value, unit, comment)}``;
        written verbatim in the ``**CONSTANTS`` block (values in the unit given).
    units : dict, optional
        Unit to write for a schema column, e.g. ``{"alpha": "deg", "kappa": "%",
        "Fz": "kN", "Vx": "km/h", "P": "bar"}``; default SI. Values are converted.
        For extra columns the unit label is written as given (values unchanged).
    columns : sequence of str, optional
        Extra numeric columns to write as channels under their own names (1-9
        characters, no blanks).
    header : dict, optional
        Extra or replacement ``**HEADER`` entries (``RELEASE``, ``SUPPLIER``, ...).
    comments : str or sequence of str, optional
        Lines for the ``**COMMENTS`` block.
    precision : int
        Significant digits of the data values.
    """
    units = dict(units or {})
    chans: list[tuple[str, str, str, np.ndarray]] = []  # key, comment, unit, values
    for col, ((key, *_), comment) in TYDEX_VARIABLES.items():
        if col not in df.columns:
            continue
        unit = units.get(col) or _TYDEX_SPELLING.get(SI_UNITS[col], SI_UNITS[col])
        values = pd.to_numeric(df[col], errors="raise").to_numpy(dtype=float)
        if DIMENSIONS[col] != "count":
            values = convert_from_si(values, unit, col)
        chans.append((key, comment, unit, values))
    for col in columns or ():
        if col not in df.columns:
            raise MftireInputError(f"write_tydex: column {col!r} not found")
        if col in TYDEX_VARIABLES:
            continue
        try:
            values = pd.to_numeric(df[col], errors="raise").to_numpy(dtype=float)
        except (ValueError, TypeError) as exc:
            raise MftireInputError(f"write_tydex: column {col!r} is not numeric") from exc
        chans.append((_check_key(str(col)), str(col), units.get(col, ""), values))
    if not chans:
        raise MftireInputError("write_tydex: no channel to write (no schema column in the table)")
    keys = [c[0] for c in chans]
    if len(set(keys)) != len(keys):
        raise MftireInputError(f"write_tydex: duplicate channel keys {keys}")

    now = datetime.now()
    head = {"RELEASE": "1.3", "SUPPLIER": "mftire", "DATE": now.strftime("%d-%m-%Y"),
            "CLCKTIME": now.strftime("%H:%M:%S")}
    head.update({k: str(v) for k, v in (header or {}).items()})
    head_comments = {"RELEASE": "Release of TYDEX-Format", "SUPPLIER": "Data supplier",
                     "DATE": "Date", "CLCKTIME": "Clocktime", "MEASID": "Measurement ID"}
    ruler = "!" + "-" * 9 + "!" + "-" * 29 + "!" + "-" * 9 + "!" + "-" * 9 + "!"
    out: list[str] = ["**HEADER", ruler]
    for k, v in head.items():
        out.append(_fmt_field(_check_key(k), 10) + _fmt_field(head_comments.get(k, k), 30)
                   + " " * 10 + v)
    out += ["", "**COMMENTS"]
    if comments is not None:
        lines = [comments] if isinstance(comments, str) else list(comments)
        out += [ln for text in lines for ln in str(text).splitlines()]
    out += ["", "**CONSTANTS", ruler]
    for k, spec in (constants or {}).items():
        if isinstance(spec, tuple):
            value, unit, comment = (tuple(spec) + ("", ""))[:3]
        else:
            value, unit, comment = spec, "", ""
        if isinstance(value, float):
            value = f"{value:.{precision}g}"
        out.append(_fmt_field(_check_key(str(k)), 10) + _fmt_field(comment or k, 30)
                   + _fmt_field(unit, 10) + str(value))
    out += ["", "**MEASURCHANNELS", ruler]
    for key, comment, unit, _ in chans:
        if len(unit) > 9 or any(ch.isspace() for ch in unit.strip()):
            raise MftireInputError(f"write_tydex: unit {unit!r} of {key} is too long or has blanks")
        out.append(_fmt_field(key, 10) + _fmt_field(comment, 30) + _fmt_field(unit, 10)
                   + f"{1:<10d}{0:<10d}")
    out += ["", "**MEASURDATA"]
    width = precision + 8
    cols = []
    for _, _, _, values in chans:
        text = np.char.mod(f"%{width}.{precision}g", values)
        text = np.where(np.isfinite(values), text, f"{'NOTAVAIL':>{width}}")
        cols.append(text)
    body = ["".join(row) for row in zip(*cols, strict=True)]
    out += body
    out += ["**END", ""]

    write_text_atomic(path, "\n".join(out))
