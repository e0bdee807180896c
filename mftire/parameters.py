"""The table of Magic Formula (MF 5.2 / 6.1 / 6.2) ``.tir`` parameters.

:data:`PARAMETERS` is the one table of every standard ``.tir`` key that mftire
knows: its standard section, the default used when the key is absent from a file,
its physical unit (which drives the ``[UNITS]`` conversion in
:mod:`mftire.iotools.tir`) and a one-line description.

Provenance of the defaults
--------------------------
The defaults are the values the public reference evaluator MFeval 4.0
(Marco Furlan Tassara, BSD-3-Clause) assigns to a parameter before it reads the
``.tir`` file (its ``readTIR`` initialises every field, then overwrites the ones
found in the file).  The facts were read from MFeval's public MATLAB source and
cross-checked against ``tyre_parameters.csv`` of the reference outputs (for
example the MF 5.2 fixture without ``[OPERATING_CONDITIONS]`` and
``[INFLATION_PRESSURE_RANGE]`` ends with ``NOMPRES = INFLPRES = 220000``,
``PRESMIN = 10000``, ``PRESMAX = 1000000`` and ``Q_FZ2 = 1e-4``).  Notes:

* MFeval never derives one parameter from another: an absent ``INFLPRES`` is
  220000 Pa whatever ``NOMPRES`` is.  mftire's specification asks that the
  operating pressure default to ``NOMPRES`` when ``INFLPRES`` is absent, so
  :func:`with_defaults` fills ``INFLPRES`` from ``NOMPRES``.  The two rules agree
  whenever ``NOMPRES`` is absent too (both give 220000 Pa), which is the case of
  every reference tyre.  An absent ``NOMPRES`` is 220000 Pa, as in MFeval, even
  if ``INFLPRES`` is given.
* MFeval calls the ``[INERTIA]`` mass ``MASS1`` because ``MASS`` is also the mass
  unit in ``[UNITS]``; here it is ``MASS`` in section ``INERTIA``.
* Rows with ``mfeval=False`` are standard keys that MFeval 4.0 does not read
  (MF 5.2 / PAC2002 extras such as ``LGAX`` or ``QTZ1``).  Their default is the
  neutral value (1 for a scaling factor, 0 otherwise); an evaluator that agrees
  with MFeval does not use them.
* Shape coefficients are dimensionless or relate to angles in rad; they are never
  unit-converted (see :mod:`mftire.iotools.tir`).

Units column
------------
``"-"`` dimensionless, ``"str"`` a string, otherwise an SI unit built from
m, N, rad, kg, s and Pa (see :data:`UNIT_DIMENSIONS`).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass as _dataclass
from typing import Any, NamedTuple


class Parameter(NamedTuple):
    """One row of the parameter table.

    Attributes
    ----------
    key : str
        Upper-case ``.tir`` key, e.g. ``"PCX1"``.
    section : str
        Standard section without brackets, e.g. ``"LONGITUDINAL_COEFFICIENTS"``.
    default : float or str
        Value used when the key is absent (MFeval 4.0's value when ``mfeval``).
    unit : str
        SI unit of the value (``"-"`` dimensionless, ``"str"`` a string).
    description : str
        One-line description.
    mfeval : bool
        Whether MFeval 4.0 reads this key.
    """

    key: str
    section: str
    default: float | str
    unit: str
    description: str
    mfeval: bool = True


#: Exponents of the ``[UNITS]`` base quantities (LENGTH, FORCE, ANGLE, MASS, TIME,
#: PRESSURE) for each unit used in :data:`PARAMETERS`.
UNIT_DIMENSIONS: dict[str, dict[str, int]] = {
    "-": {},
    "m": {"LENGTH": 1},
    "N": {"FORCE": 1},
    "N/m": {"FORCE": 1, "LENGTH": -1},
    "N*s/m": {"FORCE": 1, "TIME": 1, "LENGTH": -1},
    "N*m/rad": {"FORCE": 1, "LENGTH": 1, "ANGLE": -1},
    "Pa": {"PRESSURE": 1},
    "kg": {"MASS": 1},
    "kg*m^2": {"MASS": 1, "LENGTH": 2},
    "m/s": {"LENGTH": 1, "TIME": -1},
    "m/s^2": {"LENGTH": 1, "TIME": -2},
    "rad": {"ANGLE": 1},
    "s": {"TIME": 1},
    "1/s": {"TIME": -1},
}


def _rows(section: str, rows: list[tuple]) -> list[Parameter]:
    out = []
    for row in rows:
        key, default, unit, description, *rest = row
        out.append(Parameter(key, section, default, unit, description, *rest))
    return out


_S = "str"
_TABLE: list[Parameter] = []
_TABLE += _rows("MDI_HEADER", [
    ("FILE_TYPE", "tir", _S, "File type"),
    ("FILE_VERSION", 3.0, "-", "File version"),
    ("FILE_FORMAT", "ASCII", _S, "File format"),
])
_TABLE += _rows("MODEL", [
    ("FITTYP", 0, "-", "Magic Formula version number (5, 6, 21, 61, 62)"),
    ("TYRESIDE", "LEFT", _S, "Mounted side of tyre at vehicle/test bench"),
    ("LONGVL", 16.7, "m/s", "Nominal (measurement) speed"),
    ("VXLOW", 1.0, "m/s", "Lower boundary of slip calculation"),
    ("ROAD_INCREMENT", 0.01, "m", "Increment in road sampling"),
    ("ROAD_DIRECTION", 1, "-", "Direction of travelled distance"),
    ("PROPERTY_FILE_FORMAT", "USER", _S, "Tyre property file format"),
    ("USER_SUB_ID", 815, "-", "User subroutine identifier"),
    ("N_TIRE_STATES", 4, "-", "Number of tyre states"),
    ("USE_MODE", 124, "-", "Tyre use mode switch (ADAMS only)"),
    ("HMAX_LOCAL", 2.5e-4, "s", "Local integration time step (ADAMS only)"),
    ("TIME_SWITCH_INTEG", 0.1, "s", "Time when local integrator is activated (ADAMS only)"),
    ("FUNCTION_NAME", "TNO_DelftTyre", _S, "Name of the tyre function (MF 6.2)"),
    ("SWITCH_INTEG", 0, "-", "Integration method switch (MF 6.2)"),
])
_TABLE += _rows("DIMENSION", [
    ("UNLOADED_RADIUS", 0.3135, "m", "Free tyre radius"),
    ("WIDTH", 0.205, "m", "Nominal section width of the tyre"),
    ("ASPECT_RATIO", 0.6, "-", "Nominal aspect ratio"),
    ("RIM_RADIUS", 0.1905, "m", "Nominal rim radius"),
    ("RIM_WIDTH", 0.152, "m", "Rim width"),
])
_TABLE += _rows("OPERATING_CONDITIONS", [
    ("INFLPRES", 220000.0, "Pa", "Tyre inflation pressure"),
    ("NOMPRES", 220000.0, "Pa", "Nominal tyre inflation pressure"),
])
_TABLE += _rows("INERTIA", [
    ("MASS", 9.3, "kg", "Tyre mass"),
    ("IXX", 0.391, "kg*m^2", "Tyre diametral moment of inertia"),
    ("IYY", 0.736, "kg*m^2", "Tyre polar moment of inertia"),
    ("BELT_MASS", 7.0, "kg", "Belt mass"),
    ("BELT_IXX", 0.34, "kg*m^2", "Belt diametral moment of inertia"),
    ("BELT_IYY", 0.6, "kg*m^2", "Belt polar moment of inertia"),
    ("GRAVITY", -9.81, "m/s^2", "Gravity acting on belt in Z direction"),
])
_TABLE += _rows("VERTICAL", [
    ("FNOMIN", 4000.0, "N", "Nominal wheel load"),
    ("VERTICAL_STIFFNESS", 200000.0, "N/m", "Tyre vertical stiffness"),
    ("VERTICAL_DAMPING", 50.0, "N*s/m", "Tyre vertical damping"),
    ("MC_CONTOUR_A", 0.5, "-", "Motorcycle contour ellipse A"),
    ("MC_CONTOUR_B", 0.5, "-", "Motorcycle contour ellipse B"),
    ("BREFF", 8.4, "-", "Low load stiffness of effective rolling radius"),
    ("DREFF", 0.27, "-", "Peak value of effective rolling radius"),
    ("FREFF", 0.07, "-", "High load stiffness of effective rolling radius"),
    ("Q_RE0", 1.0, "-", "Ratio of free tyre radius with nominal tyre radius"),
    ("Q_V1", 0.0, "-", "Tyre radius increase with speed"),
    ("Q_V2", 0.0, "-", "Vertical stiffness increase with speed"),
    ("Q_FZ2", 1.0e-4, "-", "Quadratic term in load vs. deflection"),
    ("Q_FCX", 0.0, "-", "Longitudinal force influence on vertical stiffness"),
    ("Q_FCY", 0.0, "-", "Lateral force influence on vertical stiffness"),
    ("Q_CAM", 0.0, "-", "Stiffness reduction due to camber"),
    ("PFZ1", 0.0, "-", "Pressure effect on vertical stiffness"),
    ("Q_FCY2", 0.0, "-", "Explicit load dependency of the lateral force influence on vertical stiffness"),
    ("Q_CAM1", 0.0, "-", "Linear load dependent camber angle influence on vertical stiffness"),
    ("Q_CAM2", 0.0, "-", "Quadratic load dependent camber angle influence on vertical stiffness"),
    ("Q_CAM3", 0.0, "-", "Linear load and camber angle dependent reduction on vertical stiffness"),
    ("Q_FYS1", 0.0, "-", "Combined camber and side slip angle effect on vertical stiffness (constant)"),
    ("Q_FYS2", 0.0, "-", "Combined camber and side slip angle linear effect on vertical stiffness"),
    ("Q_FYS3", 0.0, "-", "Combined camber and side slip angle quadratic effect on vertical stiffness"),
    ("BOTTOM_OFFST", 0.01, "m", "Distance to rim when bottoming starts to occur"),
    ("BOTTOM_STIFF", 2000000.0, "N/m", "Vertical stiffness of bottomed tyre"),
])
_TABLE += _rows("STRUCTURAL", [
    ("LONGITUDINAL_STIFFNESS", 300000.0, "N/m", "Tyre overall longitudinal stiffness"),
    ("LATERAL_STIFFNESS", 100000.0, "N/m", "Tyre overall lateral stiffness"),
    ("YAW_STIFFNESS", 5000.0, "N*m/rad", "Tyre overall yaw stiffness"),
    ("FREQ_LONG", 80.0, "1/s", "Undamped frequency fore/aft and vertical mode"),
    ("FREQ_LAT", 40.0, "1/s", "Undamped frequency lateral mode"),
    ("FREQ_YAW", 50.0, "1/s", "Undamped frequency yaw and camber mode"),
    ("FREQ_WINDUP", 70.0, "1/s", "Undamped frequency wind-up mode"),
    ("DAMP_LONG", 0.04, "-", "Dimensionless damping fore/aft and vertical mode"),
    ("DAMP_LAT", 0.04, "-", "Dimensionless damping lateral mode"),
    ("DAMP_YAW", 0.04, "-", "Dimensionless damping yaw and camber mode"),
    ("DAMP_WINDUP", 0.04, "-", "Dimensionless damping wind-up mode"),
    ("DAMP_RESIDUAL", 0.002, "s", "Residual damping (proportional to stiffness)"),
    ("DAMP_VLOW", 0.001, "s", "Additional low speed damping (proportional to stiffness)"),
    ("Q_BVX", 0.0, "-", "Load and speed influence on in-plane translation stiffness"),
    ("Q_BVT", 0.0, "-", "Load and speed influence on in-plane rotation stiffness"),
    ("PCFX1", 0.0, "-", "Longitudinal stiffness vertical deflection dependency, linear term"),
    ("PCFX2", 0.0, "-", "Longitudinal stiffness vertical deflection dependency, quadratic term"),
    ("PCFX3", 0.0, "-", "Longitudinal stiffness pressure dependency"),
    ("PCFY1", 0.0, "-", "Lateral stiffness vertical deflection dependency, linear term"),
    ("PCFY2", 0.0, "-", "Lateral stiffness vertical deflection dependency, quadratic term"),
    ("PCFY3", 0.0, "-", "Lateral stiffness pressure dependency"),
    ("PCMZ1", 0.0, "-", "Yaw stiffness pressure dependency"),
])
_TABLE += _rows("CONTACT_PATCH", [
    ("Q_RA1", 0.5, "-", "Square root term in contact length equation"),
    ("Q_RA2", 1.0, "-", "Linear term in contact length equation"),
    ("Q_RB1", 1.0, "-", "Root term in contact width equation"),
    ("Q_RB2", -1.0, "-", "Linear term in contact width equation"),
    ("ELLIPS_SHIFT", 0.8, "-", "Scaling of distance between front and rear ellipsoid"),
    ("ELLIPS_LENGTH", 1.0, "-", "Semi major axis of ellipsoid"),
    ("ELLIPS_HEIGHT", 1.0, "-", "Semi minor axis of ellipsoid"),
    ("ELLIPS_ORDER", 1.8, "-", "Order of ellipsoid"),
    ("ELLIPS_MAX_STEP", 0.025, "m", "Maximum height of road step"),
    ("ELLIPS_NWIDTH", 10, "-", "Number of parallel ellipsoids"),
    ("ELLIPS_NLENGTH", 10, "-", "Number of ellipsoids at sides of contact patch"),
    ("ENV_C1", 0.0, "-", "Effective height attenuation"),
    ("ENV_C2", 0.0, "-", "Effective plane angle attenuation"),
    ("Q_A1", 0.0, "-", "Square root load term in contact length (MF 5.2)"),
    ("Q_A2", 0.0, "-", "Linear load term in contact length (MF 5.2)"),
])
_TABLE += _rows("INFLATION_PRESSURE_RANGE", [
    ("PRESMIN", 10000.0, "Pa", "Minimum valid tyre inflation pressure"),
    ("PRESMAX", 1000000.0, "Pa", "Maximum valid tyre inflation pressure"),
])
_TABLE += _rows("VERTICAL_FORCE_RANGE", [
    ("FZMIN", 100.0, "N", "Minimum allowed wheel load"),
    ("FZMAX", 10000.0, "N", "Maximum allowed wheel load"),
])
_TABLE += _rows("LONG_SLIP_RANGE", [
    ("KPUMIN", -1.5, "-", "Minimum valid wheel slip"),
    ("KPUMAX", 1.5, "-", "Maximum valid wheel slip"),
])
_TABLE += _rows("SLIP_ANGLE_RANGE", [
    ("ALPMIN", -1.5, "rad", "Minimum valid slip angle"),
    ("ALPMAX", 1.5, "rad", "Maximum valid slip angle"),
])
_TABLE += _rows("INCLINATION_ANGLE_RANGE", [
    ("CAMMIN", -0.175, "rad", "Minimum valid camber angle"),
    ("CAMMAX", 0.175, "rad", "Maximum valid camber angle"),
])
_TABLE += _rows("SCALING_COEFFICIENTS", [
    ("LFZO", 1.0, "-", "Scale factor of nominal (rated) load"),
    ("LCX", 1.0, "-", "Scale factor of Fx shape factor"),
    ("LMUX", 1.0, "-", "Scale factor of Fx peak friction coefficient"),
    ("LEX", 1.0, "-", "Scale factor of Fx curvature factor"),
    ("LKX", 1.0, "-", "Scale factor of Fx slip stiffness"),
    ("LHX", 1.0, "-", "Scale factor of Fx horizontal shift"),
    ("LVX", 1.0, "-", "Scale factor of Fx vertical shift"),
    ("LCY", 1.0, "-", "Scale factor of Fy shape factor"),
    ("LMUY", 1.0, "-", "Scale factor of Fy peak friction coefficient"),
    ("LEY", 1.0, "-", "Scale factor of Fy curvature factor"),
    ("LKY", 1.0, "-", "Scale factor of Fy cornering stiffness"),
    ("LHY", 1.0, "-", "Scale factor of Fy horizontal shift"),
    ("LVY", 1.0, "-", "Scale factor of Fy vertical shift"),
    ("LTR", 1.0, "-", "Scale factor of peak of pneumatic trail"),
    ("LRES", 1.0, "-", "Scale factor for offset of residual torque"),
    ("LXAL", 1.0, "-", "Scale factor of alpha influence on Fx"),
    ("LYKA", 1.0, "-", "Scale factor of kappa influence on Fy"),
    ("LVYKA", 1.0, "-", "Scale factor of kappa induced Fy"),
    ("LS", 1.0, "-", "Scale factor of moment arm of Fx"),
    ("LKYC", 1.0, "-", "Scale factor of camber force stiffness"),
    ("LKZC", 1.0, "-", "Scale factor of camber torque stiffness"),
    ("LVMX", 1.0, "-", "Scale factor of Mx vertical shift"),
    ("LMX", 1.0, "-", "Scale factor of overturning couple"),
    ("LMY", 1.0, "-", "Scale factor of rolling resistance torque"),
    ("LMP", 1.0, "-", "Scale factor of parking moment"),
    ("LSGKP", 1.0, "-", "Scale factor of relaxation length of Fx (MF 5.2)"),
    ("LSGAL", 1.0, "-", "Scale factor of relaxation length of Fy (MF 5.2)"),
    ("LKXC", 1.0, "-", "Scale factor of camber influence on Fx slip stiffness", False),
    ("LGAX", 1.0, "-", "Scale factor of camber for Fx (MF 5.2)", False),
    ("LGAY", 1.0, "-", "Scale factor of camber for Fy (MF 5.2)", False),
    ("LGAZ", 1.0, "-", "Scale factor of camber for Mz (MF 5.2)", False),
    ("LGYR", 1.0, "-", "Scale factor of gyroscopic torque", False),
    ("LMUV", 0.0, "-", "Scale factor of friction decay with slip speed (MF 5.2 / PAC2002, eq 4.E7)", False),
])
_TABLE += _rows("LONGITUDINAL_COEFFICIENTS", [
    ("PCX1", 1.65, "-", "Shape factor Cfx for longitudinal force"),
    ("PDX1", 1.3, "-", "Longitudinal friction Mux at Fznom"),
    ("PDX2", -0.15, "-", "Variation of friction Mux with load"),
    ("PDX3", 0.0, "-", "Variation of friction Mux with camber squared"),
    ("PEX1", 0.0, "-", "Longitudinal curvature Efx at Fznom"),
    ("PEX2", 0.0, "-", "Variation of curvature Efx with load"),
    ("PEX3", 0.0, "-", "Variation of curvature Efx with load squared"),
    ("PEX4", 0.0, "-", "Factor in curvature Efx while driving"),
    ("PKX1", 20.0, "-", "Longitudinal slip stiffness Kfx/Fz at Fznom"),
    ("PKX2", 0.0, "-", "Variation of slip stiffness Kfx/Fz with load"),
    ("PKX3", 0.0, "-", "Exponent in slip stiffness Kfx/Fz with load"),
    ("PHX1", 0.0, "-", "Horizontal shift Shx at Fznom"),
    ("PHX2", 0.0, "-", "Variation of shift Shx with load"),
    ("PVX1", 0.0, "-", "Vertical shift Svx/Fz at Fznom"),
    ("PVX2", 0.0, "-", "Variation of shift Svx/Fz with load"),
    ("PPX1", 0.0, "-", "Linear influence of inflation pressure on longitudinal slip stiffness"),
    ("PPX2", 0.0, "-", "Quadratic influence of inflation pressure on longitudinal slip stiffness"),
    ("PPX3", 0.0, "-", "Linear influence of inflation pressure on peak longitudinal friction"),
    ("PPX4", 0.0, "-", "Quadratic influence of inflation pressure on peak longitudinal friction"),
    ("RBX1", 20.0, "-", "Slope factor for combined slip Fx reduction"),
    ("RBX2", 15.0, "-", "Variation of slope Fx reduction with kappa"),
    ("RBX3", 0.0, "-", "Influence of camber on stiffness for Fx combined"),
    ("RCX1", 1.0, "-", "Shape factor for combined slip Fx reduction"),
    ("REX1", 0.0, "-", "Curvature factor of combined Fx"),
    ("REX2", 0.0, "-", "Curvature factor of combined Fx with load"),
    ("RHX1", 0.0, "-", "Shift factor for combined slip Fx reduction"),
    ("PTX1", 0.0, "-", "Relaxation length SigKap0/Fz at Fznom (MF 5.2)"),
    ("PTX2", 0.0, "-", "Variation of SigKap0/Fz with load (MF 5.2)"),
    ("PTX3", 0.0, "-", "Variation of SigKap0/Fz with exponent of load (MF 5.2)"),
])
_TABLE += _rows("OVERTURNING_COEFFICIENTS", [
    ("QSX1", 0.0, "-", "Vertical shift of overturning moment"),
    ("QSX2", 0.0, "-", "Camber induced overturning couple"),
    ("QSX3", 0.0, "-", "Fy induced overturning couple"),
    ("QSX4", 5.0, "-", "Mixed load, lateral force and camber on Mx"),
    ("QSX5", 1.0, "-", "Load effect on Mx with lateral force and camber"),
    ("QSX6", 10.0, "-", "B-factor of load with Mx"),
    ("QSX7", 0.0, "-", "Camber with load on Mx"),
    ("QSX8", 0.0, "-", "Lateral force with load on Mx"),
    ("QSX9", 0.4, "-", "B-factor of lateral force with load on Mx"),
    ("QSX10", 0.0, "-", "Vertical force with camber on Mx"),
    ("QSX11", 5.0, "-", "B-factor of vertical force with camber on Mx"),
    ("QSX12", 0.0, "-", "Camber squared induced overturning moment"),
    ("QSX13", 0.0, "-", "Lateral force induced overturning moment"),
    ("QSX14", 0.0, "-", "Lateral force induced overturning moment with camber"),
    ("PPMX1", 0.0, "-", "Influence of inflation pressure on overturning moment"),
])
_TABLE += _rows("LATERAL_COEFFICIENTS", [
    ("PCY1", 1.3, "-", "Shape factor Cfy for lateral forces"),
    ("PDY1", 1.1, "-", "Lateral friction Muy"),
    ("PDY2", -0.15, "-", "Variation of friction Muy with load"),
    ("PDY3", 0.0, "-", "Variation of friction Muy with squared camber"),
    ("PEY1", 0.0, "-", "Lateral curvature Efy at Fznom"),
    ("PEY2", 0.0, "-", "Variation of curvature Efy with load"),
    ("PEY3", 0.0, "-", "Zero order camber dependency of curvature Efy"),
    ("PEY4", 0.0, "-", "Variation of curvature Efy with camber"),
    ("PEY5", 0.0, "-", "Variation of curvature Efy with camber squared"),
    ("PKY1", -20.0, "-", "Maximum value of stiffness Kfy/Fznom"),
    ("PKY2", 1.0, "-", "Load at which Kfy reaches maximum value"),
    ("PKY3", 0.0, "-", "Variation of Kfy/Fznom with camber"),
    ("PKY4", 2.0, "-", "Curvature of stiffness Kfy"),
    ("PKY5", 0.0, "-", "Peak stiffness variation with camber squared"),
    ("PKY6", -1.0, "-", "Fy camber stiffness factor"),
    ("PKY7", 0.0, "-", "Vertical load dependency of camber stiffness"),
    ("PHY1", 0.0, "-", "Horizontal shift Shy at Fznom"),
    ("PHY2", 0.0, "-", "Variation of shift Shy with load"),
    ("PHY3", 0.0, "-", "Variation of shift Shy with camber (MF 5.2)"),
    ("PVY1", 0.0, "-", "Vertical shift in Svy/Fz at Fznom"),
    ("PVY2", 0.0, "-", "Variation of shift Svy/Fz with load"),
    ("PVY3", 0.0, "-", "Variation of shift Svy/Fz with camber"),
    ("PVY4", 0.0, "-", "Variation of shift Svy/Fz with camber and load"),
    ("PPY1", 0.0, "-", "Influence of inflation pressure on cornering stiffness"),
    ("PPY2", 0.0, "-", "Influence of inflation pressure on load dependency of cornering stiffness"),
    ("PPY3", 0.0, "-", "Linear influence of inflation pressure on lateral peak friction"),
    ("PPY4", 0.0, "-", "Quadratic influence of inflation pressure on lateral peak friction"),
    ("PPY5", 0.0, "-", "Influence of inflation pressure on camber stiffness (MF 6.2)"),
    ("RBY1", 10.0, "-", "Slope factor for combined Fy reduction"),
    ("RBY2", 10.0, "-", "Variation of slope Fy reduction with alpha"),
    ("RBY3", 0.0, "-", "Shift term for alpha in slope Fy reduction"),
    ("RBY4", 0.0, "-", "Influence of camber on stiffness of Fy combined"),
    ("RCY1", 1.0, "-", "Shape factor for combined Fy reduction"),
    ("REY1", 0.0, "-", "Curvature factor of combined Fy"),
    ("REY2", 0.0, "-", "Curvature factor of combined Fy with load"),
    ("RHY1", 0.0, "-", "Shift factor for combined Fy reduction"),
    ("RHY2", 0.0, "-", "Shift factor for combined Fy reduction with load"),
    ("RVY1", 0.0, "-", "Kappa induced side force Svyk/Muy*Fz at Fznom"),
    ("RVY2", 0.0, "-", "Variation of Svyk/Muy*Fz with load"),
    ("RVY3", 0.0, "-", "Variation of Svyk/Muy*Fz with camber"),
    ("RVY4", 20.0, "-", "Variation of Svyk/Muy*Fz with alpha"),
    ("RVY5", 2.0, "-", "Variation of Svyk/Muy*Fz with kappa"),
    ("RVY6", 10.0, "-", "Variation of Svyk/Muy*Fz with atan(kappa)"),
    ("PTY1", 0.0, "-", "Peak value of relaxation length SigAlp0/R0 (MF 5.2)"),
    ("PTY2", 0.0, "-", "Value of Fz/Fznom where SigAlp0 is extreme (MF 5.2)"),
])
_TABLE += _rows("ROLLING_COEFFICIENTS", [
    ("QSY1", 0.01, "-", "Rolling resistance torque coefficient"),
    ("QSY2", 0.0, "-", "Rolling resistance torque depending on Fx"),
    ("QSY3", 4.0e-4, "-", "Rolling resistance torque depending on speed"),
    ("QSY4", 4.0e-5, "-", "Rolling resistance torque depending on speed ^4"),
    ("QSY5", 0.0, "-", "Rolling resistance torque depending on camber squared"),
    ("QSY6", 0.0, "-", "Rolling resistance torque depending on load and camber squared"),
    ("QSY7", 0.85, "-", "Rolling resistance torque coefficient load dependency"),
    ("QSY8", -0.4, "-", "Rolling resistance torque coefficient pressure dependency"),
])
_TABLE += _rows("ALIGNING_COEFFICIENTS", [
    ("QBZ1", 10.0, "-", "Trail slope factor for trail Bpt at Fznom"),
    ("QBZ2", 0.0, "-", "Variation of slope Bpt with load"),
    ("QBZ3", 0.0, "-", "Variation of slope Bpt with load squared"),
    ("QBZ4", 0.0, "-", "Variation of slope Bpt with camber"),
    ("QBZ5", 0.0, "-", "Variation of slope Bpt with absolute camber"),
    ("QBZ9", 10.0, "-", "Factor for scaling factors of slope factor Br of Mzr"),
    ("QBZ10", 0.0, "-", "Factor for dimensionless cornering stiffness of Br of Mzr"),
    ("QCZ1", 1.1, "-", "Shape factor Cpt for pneumatic trail"),
    ("QDZ1", 0.12, "-", "Peak trail Dpt = Dpt*(Fz/Fznom*R0)"),
    ("QDZ2", 0.0, "-", "Variation of peak Dpt with load"),
    ("QDZ3", 0.0, "-", "Variation of peak Dpt with camber"),
    ("QDZ4", 0.0, "-", "Variation of peak Dpt with camber squared"),
    ("QDZ6", 0.0, "-", "Peak residual torque Dmr = Dmr/(Fz*R0)"),
    ("QDZ7", 0.0, "-", "Variation of peak factor Dmr with load"),
    ("QDZ8", -0.05, "-", "Variation of peak factor Dmr with camber"),
    ("QDZ9", 0.0, "-", "Variation of peak factor Dmr with camber and load"),
    ("QDZ10", 0.0, "-", "Variation of peak factor Dmr with camber squared"),
    ("QDZ11", 0.0, "-", "Variation of Dmr with camber squared and load"),
    ("QEZ1", 0.0, "-", "Trail curvature Ept at Fznom"),
    ("QEZ2", 0.0, "-", "Variation of curvature Ept with load"),
    ("QEZ3", 0.0, "-", "Variation of curvature Ept with load squared"),
    ("QEZ4", 0.0, "-", "Variation of curvature Ept with sign of Alpha-t"),
    ("QEZ5", 0.0, "-", "Variation of Ept with camber and sign Alpha-t"),
    ("QHZ1", 0.0, "-", "Trail horizontal shift Sht at Fznom"),
    ("QHZ2", 0.0, "-", "Variation of shift Sht with load"),
    ("QHZ3", 0.0, "-", "Variation of shift Sht with camber"),
    ("QHZ4", 0.0, "-", "Variation of shift Sht with camber and load"),
    ("PPZ1", 0.0, "-", "Effect of inflation pressure on length of pneumatic trail"),
    ("PPZ2", 0.0, "-", "Influence of inflation pressure on residual aligning torque"),
    ("SSZ1", 0.0, "-", "Nominal value of s/R0: effect of Fx on Mz"),
    ("SSZ2", 0.0, "-", "Variation of distance s/R0 with Fy/Fznom"),
    ("SSZ3", 0.0, "-", "Variation of distance s/R0 with camber"),
    ("SSZ4", 0.0, "-", "Variation of distance s/R0 with load and camber"),
    ("QTZ1", 0.0, "-", "Gyration torque constant (MF 5.2)", False),
    ("MBELT", 0.0, "kg", "Belt mass of the wheel (MF 5.2)", False),
])
_TABLE += _rows("TURNSLIP_COEFFICIENTS", [
    ("PDXP1", 0.4, "-", "Peak Fx reduction due to spin parameter"),
    ("PDXP2", 0.0, "-", "Peak Fx reduction due to spin with varying load parameter"),
    ("PDXP3", 0.0, "-", "Peak Fx reduction due to spin with kappa parameter"),
    ("PKYP1", 1.0, "-", "Cornering stiffness reduction due to spin"),
    ("PDYP1", 0.4, "-", "Peak Fy reduction due to spin parameter"),
    ("PDYP2", 0.0, "-", "Peak Fy reduction due to spin with varying load parameter"),
    ("PDYP3", 0.0, "-", "Peak Fy reduction due to spin with alpha parameter"),
    ("PDYP4", 0.0, "-", "Peak Fy reduction due to square root of spin parameter"),
    ("PHYP1", 1.0, "-", "Fy-alpha curve lateral shift limitation"),
    ("PHYP2", 0.15, "-", "Fy-alpha curve maximum lateral shift parameter"),
    ("PHYP3", 0.0, "-", "Fy-alpha curve maximum lateral shift varying with load parameter"),
    ("PHYP4", -4.0, "-", "Fy-alpha curve maximum lateral shift parameter"),
    ("PECP1", 0.5, "-", "Camber w.r.t. spin reduction factor parameter in camber stiffness"),
    ("PECP2", 0.0, "-", "Camber w.r.t. spin reduction factor varying with load parameter"),
    ("QDTP1", 10.0, "-", "Pneumatic trail reduction factor due to turn slip parameter"),
    ("QCRP1", 0.2, "-", "Turning moment at constant turning and zero forward speed parameter"),
    ("QCRP2", 0.1, "-", "Turn slip moment (at alpha=90deg) parameter for increase with spin"),
    ("QBRP1", 0.1, "-", "Residual (spin) torque reduction factor parameter due to side slip"),
    ("QDRP1", 1.0, "-", "Turn slip moment peak magnitude parameter"),
    ("QDRP2", 0.0, "-", "Turn slip moment curvature parameter", False),
])

#: The table: one :class:`Parameter` per standard key, in standard file order.
PARAMETERS: tuple[Parameter, ...] = tuple(_TABLE)
del _TABLE

#: Lookup by upper-case key.
BY_KEY: dict[str, Parameter] = {p.key: p for p in PARAMETERS}

#: Units of keys that are not standard parameters (no default, not filled in) but that a reader must
#: convert from non-SI ``[UNITS]``: the operating pressures of PAC2002's ``[TIRE_CONDITIONS]`` /
#: ``[TYRE_CONDITIONS]``, which :mod:`mftire.mf.pac2002` maps to INFLPRES / NOMPRES.
OTHER_UNITS: dict[str, str] = {"IP": "Pa", "IP_NOM": "Pa"}

#: Standard section names (without brackets) in the order a ``.tir`` file lists them.
STANDARD_SECTIONS: tuple[str, ...] = (
    "MDI_HEADER",
    "UNITS",
    "MODEL",
    "DIMENSION",
    "OPERATING_CONDITIONS",
    "INERTIA",
    "VERTICAL",
    "STRUCTURAL",
    "CONTACT_PATCH",
    "INFLATION_PRESSURE_RANGE",
    "VERTICAL_FORCE_RANGE",
    "LONG_SLIP_RANGE",
    "SLIP_ANGLE_RANGE",
    "INCLINATION_ANGLE_RANGE",
    "SCALING_COEFFICIENTS",
    "LONGITUDINAL_COEFFICIENTS",
    "OVERTURNING_COEFFICIENTS",
    "LATERAL_COEFFICIENTS",
    "ROLLING_COEFFICIENTS",
    "ALIGNING_COEFFICIENTS",
    "TURNSLIP_COEFFICIENTS",
)

assert len(BY_KEY) == len(PARAMETERS), "duplicate key in the parameter table"
assert all(p.unit in UNIT_DIMENSIONS or p.unit == _S for p in PARAMETERS)
assert all(p.section in STANDARD_SECTIONS for p in PARAMETERS)


def defaults() -> dict[str, float]:
    """Return ``{KEY: default}`` for every numeric standard key (MFeval 4.0's defaults).

    Returns
    -------
    dict of str to float
    """
    return {p.key: float(p.default) for p in PARAMETERS if p.unit != _S}


def _is_number(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def _to_float(value: float) -> float:
    try:
        return float(value)
    except OverflowError:  # an int beyond the float range
        return float("inf") if value > 0 else float("-inf")


def with_defaults(params: Any) -> dict[str, float]:
    """Flat parameter dict with every standard numeric key filled in.

    Parameters
    ----------
    params : TirParameters or Mapping[str, Any]
        Parameters as read by :func:`mftire.iotools.tir.read_tir` (values in SI
        units), or a flat mapping ``{KEY: value}`` (keys case-insensitive).

    Returns
    -------
    dict of str to float
        Every numeric key of :data:`PARAMETERS` (SI units) with the file's value
        where present and numeric, else the default of the table; plus every other
        numeric key the input holds (unknown keys are passed through).  A file
        without ``FITTYP`` (PAC2002) gets MFeval's default 0 here;
        :class:`mftire.tyre.Tyre` then marks a PAC2002 file with the evaluator's
        model code (:data:`mftire.mf.family.PAC2002_CODE`).  ``INFLPRES``
        falls back to ``NOMPRES`` (file value or 220000 Pa) when absent.
    """
    if hasattr(params, "flat") and callable(params.flat):
        flat = params.flat()
    elif isinstance(params, Mapping):
        flat = {str(k).upper(): v for k, v in params.items()}
    else:
        raise TypeError(f"params must be a TirParameters or a mapping, not {type(params).__name__}")

    out: dict[str, float] = {}
    for p in PARAMETERS:
        if p.unit == _S:
            continue
        value = flat.get(p.key)
        out[p.key] = _to_float(value) if _is_number(value) else float(p.default)
    for key, value in flat.items():
        if key not in out and _is_number(value):
            out[key] = _to_float(value)
    if not _is_number(flat.get("INFLPRES")):
        out["INFLPRES"] = out["NOMPRES"]
    return out


# --------------------------------------------------------------------------- limits of the values
#
# The one table of the values that make a channel non-finite or absurd.  mftire.iotools.tir_checks
# checks every file and mapping against it (evaluate, info, fit's template, export-fmu, Tyre); the FMU's
# C check of its tunable parameters is generated from it.


@_dataclass(frozen=True)
class Limit:
    """A constant's bound: ``key op bound`` must hold (``op`` is ``">"`` or ``">="``)."""

    key: str
    op: str
    bound: float
    why: str

    def holds(self, value: float) -> bool:
        return value > self.bound if self.op == ">" else value >= self.bound


#: The one table of constants whose value makes a channel non-finite or absurd: an error in every
#: consumer (``evaluate``, ``info``, ``fit``'s template, ``export-fmu``, :class:`mftire.Tyre` from a
#: mapping, and the FMU's tunable parameters, whose C check is generated from this table).
PARAMETER_LIMITS: tuple[Limit, ...] = (
    Limit("FNOMIN", ">", 0.0, "every equation divides by the nominal load (eqs 4.E1, 4.E2a)"),
    Limit("FNOMIN", ">=", 1.0, "dfz = (Fz - Fz0')/Fz0' (eq 4.E2a) then overflows the load terms"),
    Limit("UNLOADED_RADIUS", ">", 0.0, "the moments, radii and relaxation lengths scale with it"),
    Limit("WIDTH", ">=", 0.0, "a width is not negative"),
    Limit("RIM_RADIUS", ">=", 0.0, "a radius is not negative"),
    Limit("NOMPRES", ">", 0.0, "dpi = (P - NOMPRES)/NOMPRES (eq 4.E2b): Fx, My and Cz come out NaN"),
    Limit("LFZO", ">=", 1e-3, "Fz0' = LFZO·FNOMIN divides dfz (eqs 4.E1, 4.E2a): every force comes out NaN "
          "or overflows"),
    Limit("LONGVL", ">", 0.0, "the default speed and Vs/LONGVL (eq 4.E7): Re and the speed terms come out NaN"),
    Limit("VXLOW", ">", 0.0, "the low-speed reduction divides by it: NaN at standstill"),
    Limit("LMUX", ">=", 0.0, "a negative friction scale turns Fx against the slip"),
    Limit("LMUY", ">=", 0.0, "a negative friction scale turns Fy against the slip"),
    # The transient model's constants (mftire.transient.CONSTANTS: not in a .tir; checked where they are set).
    Limit("TR_SAT", ">=", 0.0, "a negative saturation slip turns the carcass deflection against the slip "
          "(0: linear relaxation)"),
    Limit("TR_CS_STEP", ">", 0.0, "the Co-Simulation integrator takes ceil(H/TR_CS_STEP) sub-steps"),
)
#: Ranges whose lower end must be below the upper end (mode 1xx clips every input into them).
RANGE_PAIRS: tuple[tuple[str, str, str], ...] = (
    ("FZMIN", "FZMAX", "N"), ("KPUMIN", "KPUMAX", "-"), ("ALPMIN", "ALPMAX", "rad"), ("CAMMIN", "CAMMAX", "rad"),
    ("PRESMIN", "PRESMAX", "Pa"),
)  # fmt: skip
#: Peak friction coefficient beyond any rubber (racing slicks reach about 2): |(PDX1 + PDX2·dfz)·LMUX| and
#: |(PDY1 + PDY2·dfz)·LMUY| over dfz in :data:`FRICTION_DFZ` (eqs 4.E13, 4.E23).
MU_MAX = 10.0
FRICTION_DFZ = (-0.5, 0.0, 1.0)
#: A Magic Formula coefficient or scaling factor beyond this magnitude is absurd: it overflows a channel
#: (the largest in real files is about 2e3: RBY4, PEY5).
COEFFICIENT_MAX = 1e6
#: Coefficients that are exponents (Kxk = Fz·(PKX1 + PKX2·dfz)·exp(PKX3·dfz), eq 4.E15; My ∝ (Fz/FNOMIN)^QSY7
#: (P/NOMPRES)^QSY8, eq 4.E70): beyond this magnitude they overflow over the load range.
EXPONENT_KEYS, EXPONENT_MAX = ("PKX3", "QSY7", "QSY8"), 100.0


def parameter_bounds() -> tuple[tuple[str, str], ...]:
    """:data:`PARAMETER_LIMITS` as ``(key, "> 0")`` pairs (``op bound``), the form the FMU's generated C
    check of its tunable parameters reads (``mftire.mf.spec.PARAMETER_BOUNDS``)."""
    return tuple((lim.key, f"{lim.op} {lim.bound:g}") for lim in PARAMETER_LIMITS)
