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


# ------------------------------------------------------------------------------------
# diagnosis figures (issue 26): sorted ranking, labelled axes with units, a legend, every held-out sweep
# ------------------------------------------------------------------------------------


def test_ranking_figure_sorted_and_labelled():
    from types import SimpleNamespace

    from mftire.diagnosis.report import ranking_figure

    ranking = [SimpleNamespace(variable=v, channel="Fx", score=s, significant=s > 0.3)
               for v, s in (("Vx", 0.5), ("Vs", 0.7), ("Fz_dev", -0.01), ("sequence", 0.2))]
    fig = ranking_figure(ranking)
    ax = fig.axes[0]
    names = [t.get_text() for t in ax.get_yticklabels()]
    assert names == ["Fz_dev (Fx)", "sequence (Fx)", "Vx (Fx)", "Vs (Fx)"]  # bottom to top: highest on top
    widths = [p.get_width() for p in ax.patches]
    assert widths == sorted(widths)
    assert ax.get_xlabel().endswith("[-]") and ax.get_ylabel()
    assert [t.get_text() for t in ax.get_legend().get_texts()] == ["significant (permutation test)",
                                                                  "not significant"]


def test_before_after_figure_shows_every_heldout_sweep_with_units():
    from types import SimpleNamespace

    from mftire.diagnosis.report import before_after_figure

    rows = []
    for sid in range(8):  # eight held-out sweeps (no "first six" any more)
        k = np.linspace(-0.3, 0.0, 7)
        rows.append(pd.DataFrame({"sweep_id": sid, "kappa": k, "alpha": 0.0, "Fz": 3000.0 + 100 * sid, "Vx": 22.2,
                                  "P": 2.2e5, "Fx": 1e4 * k, "residual_Fx": 50.0, "residual_after_Fx": 5.0}))
    df = pd.concat(rows, ignore_index=True)
    result = SimpleNamespace(effect=object(), train=np.zeros(len(df), bool), data=df,
                             errors=[SimpleNamespace(channel="Fx")])
    fig = before_after_figure(result)
    ax = fig.axes[0]
    assert ax.get_xlabel() == "κ [-]" and ax.get_ylabel() == "Fx [N]"
    legend = [t.get_text() for t in fig.legends[0].get_texts()]
    assert sum(t.startswith("sweep ") for t in legend) == 8
    assert {"data (held out)", "model before (MF fit)", "model after (MF + effect)"} <= set(legend)
    assert len(ax.lines) == 3 * 8


def test_axis_labels_carry_units_from_the_unit_table():
    from mftire.iotools.units import PLOT_UNITS, axis_label

    assert axis_label("Vs") == "Vs [m/s]" and axis_label("Mz") == "Mz [N·m]" and axis_label("energy") == "energy [J]"
    assert axis_label("TSTC") == "TSTC [unit of the data]"
    assert PLOT_UNITS["Fz_dev"] == "N"
