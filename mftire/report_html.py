"""A self-contained HTML report: headings, text, tables, figures (embedded base64 PNG).

Every number shown is also written to a JSON sidecar (tables in full, even when the
HTML shows only their first rows), so a report can be checked or post-processed
without parsing HTML.

>>> rep = HtmlReport("Fit of tyre X")
>>> rep.add_heading("Errors")
>>> rep.add_text("RMS error per channel.")
>>> rep.add_table(pd.DataFrame({"channel": ["Fx"], "rms": [12.5]}), key="errors")
>>> rep.add_figure("curves.png", caption="Fx against κ")                  # doctest: +SKIP
>>> rep.write("report.html")                                              # doctest: +SKIP
('report.html', 'report.json')
"""

from __future__ import annotations

import base64
import datetime as _dt
import html
import io
import json
import os
import re
import sys
from collections.abc import Mapping
from typing import Any

import numpy as np
import pandas as pd

from mftire.iotools.atomic import write_text_atomic
from mftire.iotools.jsonutil import jsonable

__all__ = ["HtmlReport"]

_CSS = """
body{font-family:system-ui,-apple-system,'Segoe UI',Roboto,sans-serif;margin:2em auto;max-width:1200px;
color:#222;line-height:1.45;padding:0 1em}
h1{border-bottom:2px solid #446;padding-bottom:.2em}h2{margin-top:1.6em;border-bottom:1px solid #ccd}
table{border-collapse:collapse;margin:.6em 0 1.2em;font-size:.85em}
th,td{border:1px solid #ccd;padding:.2em .55em;text-align:right}th{background:#eef}
td.s,th.s{text-align:left}caption{caption-side:top;text-align:left;font-weight:600;padding:.3em 0}
figure{margin:1em 0}figure img{max-width:100%;border:1px solid #eee}figcaption{font-size:.9em;color:#555}
.note{color:#666;font-size:.85em}.meta{color:#777;font-size:.85em}
"""


def _slug(text: str) -> str:
    s = re.sub(r"[^A-Za-z0-9]+", "_", text).strip("_").lower()
    return s or "item"


class HtmlReport:
    """Build a one-file HTML report with a JSON sidecar of every number.

    Parameters
    ----------
    title : str
        Page title and first heading.
    subtitle : str, optional
        A line under the title (e.g. the command that made the report).
    float_format : str
        Format of floats in HTML tables (the JSON keeps full precision).
    """

    def __init__(self, title: str, subtitle: str | None = None, float_format: str = "{:.4g}") -> None:
        self.title = title
        self.subtitle = subtitle
        self.float_format = float_format
        self._parts: list[str] = []
        self.tables: dict[str, list[dict]] = {}
        self.numbers: dict[str, Any] = {}
        self.figures: list[str] = []
        self.headings: list[str] = []
        self._section = "report"

    # -- content ---------------------------------------------------------------------

    def add_heading(self, text: str, level: int = 2) -> HtmlReport:
        """A heading (``level`` 2..4); it also names the following tables' default JSON keys."""
        level = min(max(int(level), 2), 4)
        self._parts.append(f'<h{level} id="{_slug(text)}">{html.escape(text)}</h{level}>')
        self.headings.append(text)
        self._section = _slug(text)
        return self

    def add_text(self, text: str, note: bool = False) -> HtmlReport:
        """Paragraph(s) of plain text (escaped; blank lines separate paragraphs; ``note`` in small grey)."""
        cls = ' class="note"' if note else ""
        for para in re.split(r"\n\s*\n", text.strip()):
            self._parts.append(f"<p{cls}>{html.escape(para).replace(chr(10), '<br>')}</p>")
        return self

    def add_numbers(self, key: str, values: Mapping[str, Any], show: bool = True) -> HtmlReport:
        """Named numbers (headline figures): a two-column table in the page and ``numbers[key]`` in JSON."""
        self.numbers[key] = dict(values)
        if show:
            rows = "".join(f'<tr><td class="s">{html.escape(str(k))}</td><td>{html.escape(self._fmt(v))}</td></tr>'
                           for k, v in values.items())
            self._parts.append(f"<table>{rows}</table>")
        return self

    def add_table(self, df: pd.DataFrame, caption: str | None = None, key: str | None = None,
                  max_rows: int | None = 200, index: bool = False) -> HtmlReport:
        """A DataFrame as an HTML table (first ``max_rows`` rows) and in full under ``tables[key]`` in JSON.

        ``key`` defaults to the caption's or current heading's slug (made unique).
        """
        d = df.reset_index() if index else df
        base = key or (_slug(caption) if caption else self._section)
        k, i = base, 2
        while k in self.tables:
            k, i = f"{base}_{i}", i + 1
        self.tables[k] = d.to_dict(orient="records")
        shown = d if max_rows is None else d.head(max_rows)
        numeric = [pd.api.types.is_numeric_dtype(shown[c]) and not pd.api.types.is_bool_dtype(shown[c])
                   for c in shown.columns]
        head = "".join(f'<th{"" if n else " class=s"}>{html.escape(str(c))}</th>'
                       for c, n in zip(shown.columns, numeric, strict=True))
        body = []
        for row in shown.itertuples(index=False):
            cells = "".join(f'<td{"" if n else " class=s"}>{html.escape(self._fmt(v))}</td>'
                            for v, n in zip(row, numeric, strict=True))
            body.append(f"<tr>{cells}</tr>")
        cap = f"<caption>{html.escape(caption)}</caption>" if caption else ""
        more = (f'<p class="note">{len(d) - len(shown)} more rows in the JSON sidecar (table "{k}").</p>'
                if len(shown) < len(d) else "")
        self._parts.append(f'<table data-key="{html.escape(k)}">{cap}<thead><tr>{head}</tr></thead>'
                           f"<tbody>{''.join(body)}</tbody></table>{more}")
        return self

    def add_figure(self, fig, caption: str | None = None, dpi: int = 100) -> HtmlReport:
        """A matplotlib figure or a PNG file (path or bytes), embedded as base64.

        A figure is rendered to PNG at ``dpi`` (and closed if it was made with pyplot).
        """
        if isinstance(fig, (bytes, bytearray)):
            png = bytes(fig)
            name = "figure"
        elif isinstance(fig, (str, os.PathLike)):
            with open(fig, "rb") as fh:
                png = fh.read()
            name = os.path.basename(os.fspath(fig))
        else:
            buf = io.BytesIO()
            fig.savefig(buf, format="png", dpi=dpi)
            png = buf.getvalue()
            name = "figure"
            plt = sys.modules.get("matplotlib.pyplot")  # a pyplot figure: release it; never import pyplot here
            if plt is not None:
                plt.close(fig)
        if png[:8] != b"\x89PNG\r\n\x1a\n":
            raise ValueError(f"add_figure: {name} is not a PNG image")
        b64 = base64.b64encode(png).decode("ascii")
        alt = html.escape(caption or name)
        cap = f"<figcaption>{html.escape(caption)}</figcaption>" if caption else ""
        self._parts.append(f'<figure><img alt="{alt}" src="data:image/png;base64,{b64}">{cap}</figure>')
        self.figures.append(caption or name)
        return self

    # -- output ----------------------------------------------------------------------

    def _fmt(self, v: Any) -> str:
        if isinstance(v, (bool, np.bool_)):
            return str(bool(v))
        if isinstance(v, (float, np.floating)):
            return "–" if not np.isfinite(v) else self.float_format.format(v)
        if v is None or v is pd.NA:
            return "–"
        return str(v)

    def to_html(self) -> str:
        """The whole page."""
        stamp = _dt.datetime.now().strftime("%Y-%m-%d %H:%M")
        sub = f'<p class="meta">{html.escape(self.subtitle)}</p>' if self.subtitle else ""
        body = "\n".join(self._parts)
        return (f"<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
                f"<title>{html.escape(self.title)}</title><style>{_CSS}</style></head>\n<body>\n"
                f"<h1>{html.escape(self.title)}</h1>{sub}<p class=\"meta\">generated {stamp} by mftire</p>\n"
                f"{body}\n</body></html>\n")

    def to_dict(self) -> dict[str, Any]:
        """The JSON sidecar: title, headings, figure captions, named numbers and every table in full."""
        return jsonable({"title": self.title, "subtitle": self.subtitle, "headings": self.headings,
                          "figures": self.figures, "numbers": self.numbers, "tables": self.tables})

    def write(self, path: str | os.PathLike, json_path: str | os.PathLike | None = None) -> tuple[str, str]:
        """Write the HTML page and its JSON sidecar (default: same name, ``.json``), atomically.

        Returns ``(html_path, json_path)``.
        """
        path = os.fspath(path)
        json_path = os.fspath(json_path) if json_path else os.path.splitext(path)[0] + ".json"
        for p in (path, json_path):
            d = os.path.dirname(os.path.abspath(p))
            os.makedirs(d, exist_ok=True)
        write_text_atomic(path, self.to_html())
        write_text_atomic(json_path, json.dumps(self.to_dict(), indent=1, allow_nan=False) + "\n")
        return path, json_path
