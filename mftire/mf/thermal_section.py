"""The ``[MFTIRE_THERMAL]`` section of a ``.tir``: the thermal model's parameters and the node each
temperature law reads.

The section is our own (other MF tools ignore it; the ``.tir`` reader keeps it and the writer writes
it back bit for bit, as it does ``[MFTIRE_EXTENSIONS]``).  Temperatures are in °C, everything else
SI.  Every key is optional except that a section must hold at least the heat capacities:

========================  ==========  =====================================================================
key                       unit        meaning
========================  ==========  =====================================================================
``TH_CAP_SURFACE``        J/K         heat capacity of the tread surface node
``TH_CAP_BULK``           J/K         heat capacity of the tread bulk/carcass node
``TH_CAP_GAS``            J/K         heat capacity of the inflation gas node
``TH_G_SURFACE_BULK``     W/K         conductance surface ↔ bulk
``TH_G_BULK_GAS``         W/K         conductance bulk ↔ gas
``TH_G_BULK_AMBIENT``     W/K         conductance bulk (sidewall) → ambient air
``TH_H_AIR0``             W/K         convective conductance surface → air at standstill
``TH_H_AIR1``             W/K/(m/s)^0.8  its speed term: ``G_air = H_AIR0 + H_AIR1·|Vx|^0.8``
``TH_G_ROAD``             W/K         conductance surface → road (at the road temperature)
``TH_SLIP_SHARE``         -           share of the sliding friction power heating the surface (default 1)
``TH_ROLL_LOSS``          -           rolling-loss coefficient: bulk power ``c·Fz·|Vx|``
``TH_HYSTERESIS``         -           hysteresis coefficient: bulk power ``c·|Vx|·(Fx² + Fy²)/Fz``
``TH_COLD_PRESSURE``      Pa          gauge pressure set cold (default ``INFLPRES``)
``TH_COLD_TEMPERATURE``   °C          temperature at which it was set (default 20)
``TH_ATMOSPHERE``         Pa          atmospheric pressure of the gas law (default 101325)
``TH_PRESSURE``           -           1: the gas law's hot pressure is the MF's ``P`` input (default);
                                      0: the pressure input is taken as given
``TH_T_INIT_SURFACE``...  °C          initial node temperatures (``_SURFACE``, ``_BULK``, ``_GAS``;
                                      default: the ambient temperature at the start)
``TH_TEMPERATURE``        °C          the temperature a steady-state evaluation uses when none is given
``EXTn_NODE``             -           the node (``surface``, ``bulk``, ``gas``) feeding the temperature law
                                      ``EXTn`` of ``[MFTIRE_EXTENSIONS]`` in the thermal model
========================  ==========  =====================================================================

A law of ``[MFTIRE_EXTENSIONS]`` whose term has an ``EXTn_NODE`` here reads that node's temperature in
the thermal model (:mod:`mftire.thermal.simulation`); in a steady-state evaluation it reads its own
variable (``temperature`` …), a uniform tyre temperature.  Bad values raise
:class:`~mftire.errors.MftireInputError` naming the section and key.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping
from dataclasses import dataclass, field, fields

from mftire.errors import MftireInputError

#: The ``.tir`` section of the thermal model.
SECTION = "MFTIRE_THERMAL"
#: The temperature nodes, in state order.
NODES: tuple[str, ...] = ("surface", "bulk", "gas")
#: The variable name of each node's temperature in the thermal model's evaluation.
NODE_VARIABLES: dict[str, str] = {"surface": "T_surface", "bulk": "T_bulk", "gas": "T_gas"}

_NODE_KEY = re.compile(r"^EXT(\d+)_NODE$")


@dataclass(frozen=True)
class ThermalParameters:
    """The numbers of ``[MFTIRE_THERMAL]`` (module docstring; °C, SI).  ``nodes`` maps an extension
    term's index to the node it reads."""

    cap_surface: float = 2000.0
    cap_bulk: float = 12000.0
    cap_gas: float = 150.0
    g_surface_bulk: float = 150.0
    g_bulk_gas: float = 10.0
    g_bulk_ambient: float = 10.0
    h_air0: float = 10.0
    h_air1: float = 8.0
    g_road: float = 40.0
    slip_share: float = 1.0
    roll_loss: float = 0.01
    hysteresis: float = 0.005
    cold_pressure: float | None = None
    cold_temperature: float = 20.0
    atmosphere: float = 101325.0
    pressure: int = 1
    t_init_surface: float | None = None
    t_init_bulk: float | None = None
    t_init_gas: float | None = None
    temperature: float | None = None
    nodes: dict[int, str] = field(default_factory=dict)

    @property
    def caps(self) -> tuple[float, float, float]:
        return (self.cap_surface, self.cap_bulk, self.cap_gas)

    def replace(self, **changes) -> ThermalParameters:
        from dataclasses import replace

        return replace(self, **changes)

    def section(self) -> dict[str, object]:
        """The ``[MFTIRE_THERMAL]`` entries (optional ones only when set)."""
        out: dict[str, object] = {}
        for f in fields(self):
            if f.name == "nodes":
                continue
            v = getattr(self, f.name)
            if v is not None:
                out["TH_" + f.name.upper()] = int(v) if f.name == "pressure" else float(v)
        for n in sorted(self.nodes):
            out[f"EXT{n}_NODE"] = self.nodes[n]
        return out


#: The FMI unit of each numeric field (:data:`mftire.fmu.variables.UNITS`; None: dimensionless or not
#: expressible, the unit is in the module docstring).
UNITS: dict[str, str | None] = {
    "cap_surface": "J/K", "cap_bulk": "J/K", "cap_gas": "J/K", "g_surface_bulk": "W/K", "g_bulk_gas": "W/K",
    "g_bulk_ambient": "W/K", "h_air0": "W/K", "h_air1": None, "g_road": "W/K", "slip_share": None,
    "roll_loss": None, "hysteresis": None, "cold_pressure": "Pa", "cold_temperature": "degC", "atmosphere": "Pa",
    "pressure": None, "t_init_surface": "degC", "t_init_bulk": "degC", "t_init_gas": "degC", "temperature": "degC",
}  # fmt: skip

#: Keys that must be > 0 (capacities, the absolute temperature scale of the gas law).
_POSITIVE = ("cap_surface", "cap_bulk", "cap_gas", "atmosphere")
#: Keys that must be >= 0.
_NONNEGATIVE = ("g_surface_bulk", "g_bulk_gas", "g_bulk_ambient", "h_air0", "h_air1", "g_road", "slip_share",
                "roll_loss", "hysteresis")
#: Temperatures that must be above absolute zero [°C].
_TEMPERATURES = ("cold_temperature", "t_init_surface", "t_init_bulk", "t_init_gas", "temperature")
_NUMBER_NAMES = tuple(f.name for f in fields(ThermalParameters) if f.name != "nodes")


def bounds() -> list[tuple[str, str, float]]:
    """The bound of each numeric field: ``(field, op, bound)`` with op ``">"``, ``">="`` or ``"in"`` (0 or 1):
    what :func:`parse_thermal` checks, as a table (the transient FMU's C checks its parameters with it)."""
    out = [(n, ">", 0.0) for n in _POSITIVE] + [(n, ">=", 0.0) for n in _NONNEGATIVE]
    out += [(n, ">", -273.15) for n in _TEMPERATURES] + [("pressure", "in", 0.0)]
    return out


def parse_thermal(section: Mapping[str, object] | None) -> ThermalParameters | None:
    """Validate a ``[MFTIRE_THERMAL]`` section (None or empty: no thermal model)."""
    if not section:
        return None
    values: dict[str, object] = {}
    nodes: dict[int, str] = {}
    for key, value in section.items():
        k = str(key).upper()
        m = _NODE_KEY.match(k)
        if m:
            node = str(value).strip().lower()
            if node not in NODES:
                raise MftireInputError(f"[{SECTION}] {k} = {value!r}: must be one of {', '.join(NODES)}")
            nodes[int(m.group(1))] = node
            continue
        name = k[3:].lower() if k.startswith("TH_") else None
        if name not in _NUMBER_NAMES:
            raise MftireInputError(f"[{SECTION}] {k}: unknown key (expected TH_CAP_SURFACE, TH_G_ROAD, ..., "
                                   "EXTn_NODE; see mftire.mf.thermal_section)")  # fmt: skip
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(float(value)):
            raise MftireInputError(f"[{SECTION}] {k} = {value!r} must be a finite number")
        v = float(value)
        if name in _POSITIVE and not v > 0.0:
            raise MftireInputError(f"[{SECTION}] {k} = {value!r} must be > 0")
        if name in _NONNEGATIVE and v < 0.0:
            raise MftireInputError(f"[{SECTION}] {k} = {value!r} must be >= 0")
        if name == "pressure" and v not in (0.0, 1.0):
            raise MftireInputError(f"[{SECTION}] {k} = {value!r} must be 0 or 1")
        if name in _TEMPERATURES and v <= -273.15:
            raise MftireInputError(f"[{SECTION}] {k} = {value!r} °C is below absolute zero")
        if name == "cold_pressure" and v <= -101325.0:
            raise MftireInputError(f"[{SECTION}] {k} = {value!r} Pa: a gauge pressure below vacuum")
        values[name] = int(v) if name == "pressure" else v
    for req in ("cap_surface", "cap_bulk", "cap_gas"):
        if req not in values:
            raise MftireInputError(f"[{SECTION}] TH_{req.upper()} is missing")
    return ThermalParameters(**values, nodes=nodes)


def check_nodes(params: ThermalParameters, extension_indices) -> None:
    """Every ``EXTn_NODE`` must name a term of ``[MFTIRE_EXTENSIONS]``."""
    have = set(extension_indices)
    for n in params.nodes:
        if n not in have:
            raise MftireInputError(f"[{SECTION}] EXT{n}_NODE: [MFTIRE_EXTENSIONS] has no term EXT{n}")


__all__ = ["NODES", "NODE_VARIABLES", "SECTION", "UNITS", "ThermalParameters", "bounds", "check_nodes",
           "parse_thermal"]
