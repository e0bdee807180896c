"""Data shipped with mftire (see NOTICE.md): the default ``.tir`` and the simulated raw rig runs."""

from __future__ import annotations

from importlib import resources


def default_tir() -> str:
    """Path of the shipped default ``.tir`` (MF 6.1, 255/55 R20, MFeval example; see NOTICE.md)."""
    return str(resources.files(__name__) / "default.tir")


def rig_run() -> str:
    """Path of the shipped SIMULATED raw rig run file (TTC-style layout, metric units, SAE axes,
    100 Hz, gzipped), written by ``validation/make_rig_file.py``; see NOTICE.md."""
    return str(resources.files(__name__) / "simulated_ttc_run.dat.gz")


def thermal_run() -> str:
    """Path of the shipped SIMULATED continuous thermal rig run (TTC layout, metric units, SAE axes, 10 Hz,
    680 s: a warm-up and load steps until ET = 470 s, then a stint of repeated cornering; gzipped), written by
    ``validation/make_thermal_runs.py``; see NOTICE.md."""
    return str(resources.files(__name__) / "simulated_thermal_run.dat.gz")
