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


#: The lowest temperature a field may hold [°C] (absolute zero, excluded).
_ABSOLUTE_ZERO = -273.15


def _number(default: float | None, unit: str | None, text: str, op: str | None = None, bound: float = 0.0):
    """A number of the section: its default, its FMI unit (None: dimensionless or not expressible; the module
    docstring gives it), its one-line meaning (ASCII: the FMU's description) and the bound :func:`parse_thermal`
    checks, ``op`` ``">"``, ``">="`` or ``"in"`` (0 or 1) against ``bound`` (None: no bound of :func:`bounds`)."""
    return field(default=default, metadata={"unit": unit, "text": text, "bound": (op, bound) if op else None})


@dataclass(frozen=True)
class ThermalParameters:
    """The numbers of ``[MFTIRE_THERMAL]`` (module docstring; °C, SI).  ``nodes`` maps an extension
    term's index to the node it reads.  Each field's metadata: its unit, meaning and bound (:func:`_number`)."""

    cap_surface: float = _number(2000.0, "J/K", "heat capacity of the tread surface node", ">")
    cap_bulk: float = _number(12000.0, "J/K", "heat capacity of the bulk/carcass node", ">")
    cap_gas: float = _number(150.0, "J/K", "heat capacity of the inflation gas node", ">")
    g_surface_bulk: float = _number(150.0, "W/K", "conductance surface <-> bulk", ">=")
    g_bulk_gas: float = _number(10.0, "W/K", "conductance bulk <-> gas", ">=")
    g_bulk_ambient: float = _number(10.0, "W/K", "conductance bulk (sidewall) -> ambient air", ">=")
    h_air0: float = _number(10.0, "W/K", "convective conductance surface -> air at standstill", ">=")
    h_air1: float = _number(8.0, None, "its speed term [W/K/(m/s)^0.8]: G_air = TH_H_AIR0 + TH_H_AIR1*|Vx|^0.8",
                            ">=")
    g_road: float = _number(40.0, "W/K", "conductance surface -> road", ">=")
    slip_share: float = _number(1.0, None, "share of the sliding friction power heating the surface", ">=")
    roll_loss: float = _number(0.01, None, "rolling-loss coefficient: bulk power c*Fz*|Vx|", ">=")
    hysteresis: float = _number(0.005, None, "hysteresis coefficient: bulk power "
                                "c*|Vx|*(Fx^2 + Fy^2)/max(Fz, 0.1*FNOMIN)", ">=")  # fmt: skip
    # a gauge pressure, above vacuum (parse_thermal)
    cold_pressure: float | None = _number(None, "Pa", "cold set pressure of the file (the FMU's P input is the "
                                          "cold pressure; this is its start)")  # fmt: skip
    cold_temperature: float = _number(20.0, "degC", "temperature at which the cold pressure is set", ">",
                                      _ABSOLUTE_ZERO)
    atmosphere: float = _number(101325.0, "Pa", "atmospheric pressure", ">")
    pressure: int = _number(1, None, "1: the gas law's hot pressure is the MF's pressure; 0: the P input is", "in")
    t_init_surface: float | None = _number(None, "degC", "initial surface temperature", ">", _ABSOLUTE_ZERO)
    t_init_bulk: float | None = _number(None, "degC", "initial bulk temperature", ">", _ABSOLUTE_ZERO)
    t_init_gas: float | None = _number(None, "degC", "initial gas temperature", ">", _ABSOLUTE_ZERO)
    temperature: float | None = _number(None, "degC", "steady-state temperature of the file (not used by the "
                                        "block)", ">", _ABSOLUTE_ZERO)  # fmt: skip
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


_NUMBERS = tuple(f for f in fields(ThermalParameters) if f.name != "nodes")
_NUMBER_NAMES = tuple(f.name for f in _NUMBERS)
#: The FMI unit of each numeric field (:data:`mftire.fmu.variables.UNITS`; None: dimensionless or not
#: expressible, the unit is in the module docstring).
UNITS: dict[str, str | None] = {f.name: f.metadata["unit"] for f in _NUMBERS}
#: The one-line meaning of each numeric field (ASCII).
TEXTS: dict[str, str] = {f.name: f.metadata["text"] for f in _NUMBERS}
_BOUNDS: dict[str, tuple[str, float]] = {f.name: f.metadata["bound"] for f in _NUMBERS if f.metadata["bound"]}


def bounds() -> list[tuple[str, str, float]]:
    """The bound of each numeric field: ``(field, op, bound)`` with op ``">"``, ``">="`` or ``"in"`` (0 or 1):
    what :func:`parse_thermal` checks, as a table (the transient FMU's C checks its parameters with it)."""
    return [(name, op, bound) for name, (op, bound) in _BOUNDS.items()]


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
        op, bound = _BOUNDS.get(name, (None, 0.0))
        if op == "in" and v not in (0.0, 1.0):
            raise MftireInputError(f"[{SECTION}] {k} = {value!r} must be 0 or 1")
        if op == ">" and not v > bound:
            why = "°C is below absolute zero" if bound == _ABSOLUTE_ZERO else f"must be > {bound:g}"
            raise MftireInputError(f"[{SECTION}] {k} = {value!r} {why}")
        if op == ">=" and not v >= bound:
            raise MftireInputError(f"[{SECTION}] {k} = {value!r} must be >= {bound:g}")
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


__all__ = ["NODES", "NODE_VARIABLES", "SECTION", "TEXTS", "UNITS", "ThermalParameters", "bounds", "check_nodes",
           "parse_thermal"]
