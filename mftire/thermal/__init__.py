"""Thermal tyre: a lumped three-node model (tread surface, tread bulk/carcass, inflation gas) whose
temperatures feed the Magic Formula's temperature laws and whose gas law gives the hot pressure.

Temperatures are in °C throughout (differences in K); everything else SI.

Modules:

- :mod:`mftire.thermal.heat`: heat sources, heat paths, gas law, the implicit step (pure functions);
- :mod:`mftire.thermal.thermal_section`: the ``[MFTIRE_THERMAL]`` section of a ``.tir``;
- :mod:`mftire.thermal.simulation`: node temperatures along a series, :func:`replay` of a measured series;
- :mod:`mftire.thermal.thermal_fit`: ``fit_thermal`` (thermal parameters, laws and their nodes);
- :mod:`mftire.thermal.cli`: ``mftire fit-thermal`` and ``mftire replay``.
"""

from mftire.thermal.heat import friction_power, hot_pressure, steady_state
from mftire.thermal.simulation import Replay, replay, simulate_nodes, thermal_of
from mftire.thermal.thermal_fit import ThermalResult, fit_thermal, fit_thermal_parameters
from mftire.thermal.thermal_section import SECTION, ThermalParameters, parse_thermal

__all__ = ["SECTION", "Replay", "ThermalParameters", "ThermalResult", "fit_thermal", "fit_thermal_parameters",
           "friction_power", "hot_pressure", "parse_thermal", "replay", "simulate_nodes", "steady_state",
           "thermal_of"]
