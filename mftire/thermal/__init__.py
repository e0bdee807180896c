"""Thermal tyre: a lumped three-node model (tread surface, tread bulk/carcass, inflation gas) whose
temperatures feed the Magic Formula's temperature laws and whose gas law gives the hot pressure.

Temperatures are in °C throughout (differences in K); everything else SI.

Modules (the ``[MFTIRE_THERMAL]`` section itself is read by :mod:`mftire.mf.thermal_section`, so that
:class:`~mftire.tyre.Tyre` validates it on load):

- :mod:`mftire.thermal.heat`: heat sources, heat paths, gas law, the implicit step (pure functions);
- :mod:`mftire.thermal.simulation`: node temperatures along a series, :func:`replay` of a measured series;
- :mod:`mftire.thermal.thermal_fit`: ``fit_thermal`` (thermal parameters, laws and their nodes);
- :mod:`mftire.thermal.heldout`: the held-out check of a thermal fit (fit on the first part of a series,
  replay the rest, against the model fed the measured temperature and an isothermal fit);
- :mod:`mftire.thermal.series`: reading the series (raw rig file or imported CSV);
- :mod:`mftire.thermal.cli`: ``mftire fit-thermal`` and ``mftire replay``.
"""

from mftire._lazy import lazy_names

# imported on first use (see mftire._lazy); mftire.tyre reads the section module without loading the rest
__getattr__, __dir__ = lazy_names(
    __name__, {"friction_power": "mftire.thermal.heat", "hot_pressure": "mftire.thermal.heat",
               "steady_state": "mftire.thermal.heat", "Replay": "mftire.thermal.simulation",
               "replay": "mftire.thermal.simulation", "simulate_nodes": "mftire.thermal.simulation",
               "thermal_of": "mftire.thermal.simulation", "ThermalResult": "mftire.thermal.thermal_fit",
               "fit_thermal": "mftire.thermal.thermal_fit", "fit_thermal_parameters": "mftire.thermal.thermal_fit",
               "SECTION": "mftire.mf.thermal_section", "ThermalParameters": "mftire.mf.thermal_section",
               "parse_thermal": "mftire.mf.thermal_section"}
)

__all__ = ["SECTION", "Replay", "ThermalParameters", "ThermalResult", "fit_thermal", "fit_thermal_parameters",
           "friction_power", "hot_pressure", "parse_thermal", "replay", "simulate_nodes", "steady_state",
           "thermal_of"]
