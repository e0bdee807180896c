"""The contract between the Python evaluator, the C model, the array kernel and the FMU (data only).

One table per shared fact; :mod:`mftire.mf.cheaders` generates ``mftire/mf/c/mf_spec_gen.h``
from it (``tests/test_spec.py`` checks the committed header is current), and the numpy
solver (:mod:`mftire.mf.solver`), the kernel's Python side (:mod:`mftire.mf.kernel`), the
FMU variable table (:mod:`mftire.fmu.variables`) and the transient FMU
(:mod:`mftire.fmu.transient_export`) read it.  Adding an output or a warning is one row here
plus its equation.

* :data:`GROUPS`: the channel groups of the C model's ``mf_evaluate_want`` (``MF_WANT_<name>``):
  which numpy channel functions (:func:`mftire.mf.solver.channels`) an output of the group
  needs, and which whole forces the C computes for it.
* :data:`OUTPUTS`: the outputs in MFeval's order (name, SI unit, group, ``MFOutputs`` member,
  the ``Cond`` member of the conditioned inputs, FMU name, description).
* :data:`KERNEL_INPUTS`: the inputs of the array kernel, in its order.
* :data:`WARNINGS`: the warning kinds (``MF_W_<name>``) in the order the numpy path issues them,
  with their texts.
* :data:`PARAMETER_BOUNDS`: parameters with a physical bound.
* :data:`FAMILIES`: the model codes (``p["FITTYP"]``) the evaluator handles.
* :data:`BUILTIN_VARIABLES`: the variables a model-extension term may read that the evaluator
  derives itself, with their Python and C expressions.

Units are SI, spelt as FMI unit names (``N.m``, ``N/rad``, ``rad/s``); ``-`` is dimensionless.
"""

from __future__ import annotations

from dataclasses import dataclass

from mftire.parameters import parameter_bounds


@dataclass(frozen=True)
class Group:
    """A channel group of the C model (``MF_WANT_<name>``, bit ``bit``)."""

    name: str
    bit: int
    #: The numpy channel functions (:func:`mftire.mf.solver.channels`) an output of the group needs.
    channels: tuple[str, ...]
    #: The whole forces ("Fx", "Fy") the group's equations read.
    forces: tuple[str, ...]
    #: The channel function of its own (:func:`mftire.mf.solver.channels`), None for derived groups.
    channel: str | None
    description: str


#: The channel groups, in bit order.
GROUPS: tuple[Group, ...] = (
    Group("FX", 1, ("Fx",), ("Fx",), "Fx", "Fx, mux, Kxk"),
    Group("FY", 2, ("Fy",), ("Fy",), "Fy", "Fy, muy, Kya"),
    Group("MZ", 4, ("Mz",), ("Fx", "Fy"), "Mz", "Mz, t, Mzr"),
    Group("MX", 8, ("Mx",), ("Fy",), "Mx", "Mx"),
    Group("MY", 16, ("My",), ("Fx",), "My", "My"),
    Group("RAD", 32, ("Fx", "Fy"), ("Fx", "Fy"), None, "rho, Rl, Cz"),
    Group("PATCH", 64, (), (), None, "2a, 2b"),
    # the C needs the slip stiffnesses and the friction coefficients only (it gives Kxk, Kya, mux, muy too, not the
    # forces: the transient kinematics); numpy computes them with the forces (and so do the kernel's calls, for the
    # same warnings)
    Group("RELAX", 128, ("Fx", "Fy"), (), None, "Cx, Cy, sigmax, sigmay; Kxk, Kya, mux, muy (slip stiffnesses and mu)"),
)


@dataclass(frozen=True)
class Output:
    """One output channel."""

    name: str  #: MFeval's name (key of ``Tyre.evaluate``'s result)
    unit: str  #: SI unit, FMI spelling; "-" dimensionless
    group: str | None  #: the group (:data:`GROUPS`) that computes it; None: set by every evaluation
    field: str | None  #: member of the C ``MFOutputs`` (None: not in it)
    cond: str | None  #: member of the conditioned inputs (``Cond`` / ``Conditions``) it reports, if any
    fmu: str | None  #: name of the output of the steady-state FMU (None: not published)
    description: str


_O = Output
#: The outputs, in the order and with the meaning of MFeval's output matrix.
OUTPUTS: tuple[Output, ...] = (
    _O("Fx", "N", "FX", "Fx", None, "Fx", "Longitudinal force"),
    _O("Fy", "N", "FY", "Fy", None, "Fy", "Lateral force"),
    _O("Fz", "N", None, "Fz", "uFz", "Fz_out", "Vertical load used (negative input set to 0)"),
    _O("Mx", "N.m", "MX", "Mx", None, "Mx", "Overturning moment"),
    _O("My", "N.m", "MY", "My", None, "My", "Rolling-resistance moment"),
    _O("Mz", "N.m", "MZ", "Mz", None, "Mz", "Self-aligning moment"),
    _O("kappa", "-", None, None, "ukappa_low", None, "Longitudinal slip (low-speed reduced)"),
    _O("alpha", "rad", None, None, "ualpha", None, "Slip angle"),
    _O("gamma", "rad", None, None, "ugamma", None, "Inclination angle"),
    _O("phit", "1/m", None, None, "phit", None, "Turn slip (conditioned)"),
    _O("Vx", "m/s", None, None, "Vx", None, "Forward speed"),
    _O("P", "Pa", None, None, "P", None, "Inflation pressure (clipped)"),
    _O("Re", "m", None, "Re", None, "Re", "Effective rolling radius"),
    _O("rho", "m", "RAD", "rho", None, "rho", "Tyre vertical deflection"),
    _O("2a", "m", "PATCH", "a2", None, "a2", "Contact patch length 2a"),
    _O("t", "m", "MZ", "t", None, "t", "Pneumatic trail"),
    _O("mux", "-", "FX", "mux", None, "mux", "Longitudinal friction coefficient"),
    _O("muy", "-", "FY", "muy", None, "muy", "Lateral friction coefficient"),
    _O("omega", "rad/s", None, "omega", "omega", None, "Wheel spin"),
    _O("Rl", "m", "RAD", "Rl", None, "Rl", "Loaded radius"),
    _O("2b", "m", "PATCH", "b2", None, "b2", "Contact patch width 2b"),
    _O("Mzr", "N.m", "MZ", "Mzr", None, "Mzr", "Residual aligning moment"),
    _O("Cx", "N/m", "RELAX", "Cx", None, None, "Longitudinal carcass stiffness"),
    _O("Cy", "N/m", "RELAX", "Cy", None, None, "Lateral carcass stiffness"),
    _O("Cz", "N/m", "RAD", "Cz", None, None, "Vertical stiffness"),
    _O("Kya", "N/rad", "FY", "Kya", None, "Kya", "Cornering stiffness dFy0/dalpha"),
    _O("sigmax", "m", "RELAX", "sigmax", None, "sigmax", "Longitudinal relaxation length"),
    _O("sigmay", "m", "RELAX", "sigmay", None, "sigmay", "Lateral relaxation length"),
    # the finite difference of Fy over the conditioned slip angle between neighbouring points
    _O("instKya", "N/rad", "FY", None, "alpha", None, "Instantaneous cornering stiffness dFy/dalpha"),
    _O("Kxk", "N", "FX", "Kxk", None, "Kxk", "Longitudinal slip stiffness dFx0/dkappa"),
)

#: Inputs of the array kernel (``mf_kernel.c``), in its order: the operating point, then the data
#: variables of the model extensions (``mftire.mf.extensions.MAX_EXTERNAL`` slots).
KERNEL_INPUTS: tuple[str, ...] = ("Fz", "kappa", "alpha", "gamma", "phit", "Vx", "P", "omega",
                                  "data0", "data1", "data2", "data3")  # fmt: skip


@dataclass(frozen=True)
class WarningKind:
    """One kind of warning (``MF_W_<name>``, bit of the C model's warning mask)."""

    name: str
    #: The text; ``{n}`` the number of values, ``{input}`` the input's name, ``{value}`` the limit's value.
    text: str
    limit: str | None = None  #: the parameter whose value the text names
    input: str | None = None  #: the input a NaN warning names (KERNEL_INPUTS)
    group: str | None = None  #: the group whose equations raise it (masked when the group is not computed)


_NAN = "{n} NaN value(s) in input '{input}' replaced by 0.0."
_SAT = " the limit {limit}={value}. Values have been saturated."
_CURV = " over limit (>1), eq {eq}; clipped to 1."
_W = WarningKind

#: The warning kinds, in the order the numpy path issues them.
WARNINGS: tuple[WarningKind, ...] = (
    *(_W(f"NAN_DATA{k}", _NAN, input=f"data{k}") for k in range(4)),
    *(_W(f"NAN_{n.upper()}", _NAN, input=n) for n in ("Fz", "kappa", "alpha", "gamma", "phit", "Vx", "omega")),
    _W("ALPHA_LOW", "Slip angle below" + _SAT, "ALPMIN"),
    _W("ALPHA_HIGH", "Slip angle above" + _SAT, "ALPMAX"),
    _W("GAMMA_LOW", "Inclination angle below" + _SAT, "CAMMIN"),
    _W("GAMMA_HIGH", "Inclination angle above" + _SAT, "CAMMAX"),
    _W("FZ_HIGH", "Vertical load above" + _SAT, "FZMAX"),
    _W("FZ_LOW", "Vertical load below" + _SAT, "FZMIN"),
    _W("P_LOW", "Pressure below" + _SAT, "PRESMIN"),
    _W("P_HIGH", "Pressure above" + _SAT, "PRESMAX"),
    _W("KAPPA_LOW", "Slip ratio below" + _SAT, "KPUMIN"),
    _W("KAPPA_HIGH", "Slip ratio above" + _SAT, "KPUMAX"),
    _W("LOW_SPEED", "Speed input Vx below the limit {limit}={value}. Low speed mode activated.", "VXLOW"),
    # a model-extension variable outside the range its term was fitted on, clamped (modes 1xx)
    _W("EXT_RANGE", "Model extension variable outside the range it was fitted on (EXTn_MIN..EXTn_MAX). Values "
       "have been saturated."),
    _W("EX", "Ex" + _CURV.replace("{eq}", "4.E14"), group="FX"),
    _W("EXA", "Exa" + _CURV.replace("{eq}", "4.E56"), group="FX"),
    _W("EY", "Ey" + _CURV.replace("{eq}", "4.E24"), group="FY"),
    _W("EYK", "Eyk" + _CURV.replace("{eq}", "4.E64"), group="FY"),
    _W("ET", "Et" + _CURV.replace("{eq}", "4.E44"), group="MZ"),
    # Ey clipped in the zero-camber Fy0 of the aligning moment (a second warning, as in Python)
    _W("EY0", "Ey" + _CURV.replace("{eq}", "4.E24"), group="MZ"),
)


@dataclass(frozen=True)
class Family:
    """A model family the evaluator handles: the model code in ``p["FITTYP"]``."""

    code: float
    name: str
    equations: str  #: the equations it takes (a model code of this table)


#: PAC2002 has no FITTYP: the evaluator's own code for it (never written to a file).
PAC2002_CODE = 2002.0

#: The model families, by the model name of :attr:`mftire.iotools.tir.TirParameters.model`.
FAMILIES: tuple[Family, ...] = (
    Family(6.0, "MF 5.2", "MF 5.2"),
    Family(61.0, "MF 6.1", "MF 6.1"),
    Family(62.0, "MF 6.2", "MF 6.2"),
    Family(PAC2002_CODE, "PAC2002", "MF 5.2 with the PAC2002 differences (docs/pac2002.md)"),
    Family(PAC2002_CODE, "MF-Tyre 5.0", "PAC2002 (docs/pac2002.md, 'MF_05')"),
)


#: Parameters with a physical bound, refused outside it (the FMU's tunable parameters at every set; the
#: ``.tir`` checks of :mod:`mftire.iotools.tir_checks` refuse the same in a file, the transient model its
#: constants ``TR_*``): (key, "> 0" or ">= 0").  One table with every other consumer:
#: :data:`mftire.parameters.PARAMETER_LIMITS` (evaluate, info, fit, export, the transient tyre).  In C a bound on
#: a key beyond the ``.tir`` parameters counts where ``MFParams`` has the member (``MF_HAS_<key>``).
PARAMETER_BOUNDS: tuple[tuple[str, str], ...] = parameter_bounds()


@dataclass(frozen=True)
class BuiltinVariable:
    """A variable a model-extension term may read that the evaluator derives from its own inputs.

    ``python``: an expression in ``p`` (the parameters), ``c`` (:class:`mftire.mf.inputs.Conditions`),
    ``np`` and ``increments`` / ``slip_speed`` (:mod:`mftire.mf.basic`); ``c_expr``: the same in C
    (``p`` an ``MFParams *``, ``c`` a ``Cond *`` of ``mf_eval.c``).
    """

    name: str
    description: str
    python: str
    c_expr: str


_B = BuiltinVariable
BUILTIN_VARIABLES: tuple[BuiltinVariable, ...] = (
    _B("Fz", "vertical load [N]", "c.Fz", "c->Fz"),
    _B("kappa", "longitudinal slip [-]", "c.kappa", "c->kappa"),
    _B("alpha", "slip angle [rad]", "c.alpha", "c->alpha"),
    _B("gamma", "inclination angle [rad]", "c.gamma", "c->gamma"),
    _B("Vx", "forward speed [m/s]", "c.Vx", "c->Vx"),
    _B("P", "inflation pressure [Pa]", "c.P", "c->P"),
    _B("Vs", "slip speed |Vx|·sqrt(kappa² + tan²alpha) [m/s] (Pacejka 2012 eqs 4.E5, 3.39)",
       "slip_speed(c.Vx, c.kappa, c.alpha)",
       "fabs(c->Vx) * sqrt(c->kappa * c->kappa + tan(c->alpha) * tan(c->alpha))"),
    _B("dfz", "normalised load increment (Fz − Fz0')/Fz0' [-] (eq 4.E2a)",
       "increments(p, c.Fz, c.P)[1]", "mf_dfz(p, c->Fz)"),
    _B("dpi", "normalised pressure increment (P − NOMPRES)/NOMPRES [-] (eq 4.E2b)",
       "increments(p, c.Fz, c.P)[2]", "mf_dpi(p, c->P)"),
    _B("sign_alpha", "sign of the slip angle [-]", "np.sign(c.alpha)",
       "(double)((c->alpha > 0.0) - (c->alpha < 0.0))"),
    _B("sign_kappa", "sign of the slip [-]", "np.sign(c.kappa)",
       "(double)((c->kappa > 0.0) - (c->kappa < 0.0))"),
)  # fmt: skip


__all__ = [
    "BUILTIN_VARIABLES", "FAMILIES", "GROUPS", "KERNEL_INPUTS", "OUTPUTS", "PAC2002_CODE", "PARAMETER_BOUNDS",
    "WARNINGS",
    "BuiltinVariable", "Family", "Group", "Output", "WarningKind",
]  # fmt: skip
