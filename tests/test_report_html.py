"""Self-contained HTML report: embedded images, every table, JSON sidecar."""

from __future__ import annotations

import base64
import json
import re

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402
import pytest  # noqa: E402

from mftire.report_html import HtmlReport  # noqa: E402


def test_report_embeds_figures_and_tables(tmp_path):
    fig, ax = plt.subplots()
    ax.plot([0, 1], [0, 1])
    png = tmp_path / "p.png"
    fig.savefig(png)
    rep = HtmlReport("Demo <report>", subtitle="mftire demo")
    rep.add_heading("Errors")
    rep.add_text("RMS error per channel.\n\nSecond paragraph & more.")
    errors = pd.DataFrame({"channel": ["Fx", "Fy"], "rms": [12.5, np.nan], "ok": [True, False]})
    big = pd.DataFrame({"i": np.arange(30), "x": np.linspace(0, 1, 30)})
    rep.add_table(errors, caption="Errors per channel")
    rep.add_table(big, key="big", max_rows=5)
    rep.add_numbers("headline", {"coverage": 0.951, "n": 688})
    rep.add_heading("Figures")
    rep.add_figure(fig, caption="a line")
    rep.add_figure(png, caption="from file")
    html_path, json_path = rep.write(tmp_path / "out" / "report.html")
    text = open(html_path, encoding="utf-8").read()
    imgs = re.findall(r'src="data:image/png;base64,([A-Za-z0-9+/=]+)"', text)
    assert len(imgs) == 2 and all(base64.b64decode(i)[:8] == b"\x89PNG\r\n\x1a\n" for i in imgs)
    assert "<img" in text and "http" not in text.split("<body>")[1].split("generated")[0]  # nothing external
    assert "Demo &lt;report&gt;" in text and "Second paragraph &amp; more." in text
    assert 'data-key="errors_per_channel"' in text and 'data-key="big"' in text
    assert "25 more rows" in text
    js = json.loads(open(json_path).read())
    assert js["tables"]["errors_per_channel"][1]["rms"] is None  # NaN -> null
    assert len(js["tables"]["big"]) == 30  # full table in JSON even when the page shows 5 rows
    assert js["numbers"]["headline"]["coverage"] == pytest.approx(0.951)
    assert js["headings"] == ["Errors", "Figures"] and js["figures"] == ["a line", "from file"]
    # every number of every table appears in the sidecar
    assert [r["x"] for r in js["tables"]["big"]] == pytest.approx(list(big["x"]))


def test_default_keys_and_bad_png(tmp_path):
    rep = HtmlReport("t")
    rep.add_heading("Stiffness")
    rep.add_table(pd.DataFrame({"a": [1]}))
    rep.add_table(pd.DataFrame({"a": [2]}))
    assert list(rep.tables) == ["stiffness", "stiffness_2"]
    bad = tmp_path / "x.png"
    bad.write_bytes(b"not a png")
    with pytest.raises(ValueError):
        rep.add_figure(bad)
