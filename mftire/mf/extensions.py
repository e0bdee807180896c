"""Model extensions: MF scaling factors that depend on a condition.

The Magic Formula's own vocabulary for "this property of the tyre changes" is its
scaling factors (Pacejka 2012 §4.3.2, Table 4.4): LMUX/LMUY peak friction, LKX/LKY/
LKYC/LKZC stiffnesses, LCX/LCY shape, LEX/LEY curvature, LHX/LHY/LVX/LVY shifts,
LTR/LRES trail and residual torque, LMX/LMY/LVMX moments, LFZO nominal load.  An
extension makes one or more of them a function of a variable:

    λ_eff = λ_file · f(v; coefficients)

stored in a ``.tir`` section of our own, ``[MFTIRE_EXTENSIONS]`` (other MF tools ignore
it; without it the file is a plain MF file).  One numbered term per extension:

=====================  =========================================================================
key                    meaning
=====================  =========================================================================
``EXTn_TARGET``        scaling factor(s) it multiplies, e.g. ``'LMUX LMUY'``; or ``FX_OFFSET`` /
                       ``FY_OFFSET``: a force offset ``Fz·(f − 1)`` added to Fx / Fy [N]
``EXTn_FORM``          one of :data:`FORMS` (below)
``EXTn_VARIABLE``      the variable v: one of :data:`BUILTIN_VARIABLES` (derived by the
                       evaluator from its own inputs) or an external input (a data column in
                       Python, an FMU input), e.g. ``'temperature'``
``EXTn_REF``,          z = (u − REF)/SCALE with u = v clipped to [MIN, MAX] (the range the
``EXTn_SCALE``,        term was fitted on; defaults 0, 1, no clipping)
``EXTn_MIN/MAX``
``EXTn_C1`` ...        the coefficients of the form (neutral value 0: f = 1)
``EXTn_L1`` ...        the levels of a ``table`` form
``EXTn_VARIABLE2``     second variable of the ``interaction`` form (with REF2, SCALE2, MIN2, MAX2)
=====================  =========================================================================

The forms (each :class:`Form` holds its formula, neutral value, bounds and start values
for fitting, and its C expression, from which the FMU's C is generated; the size coefficients of a
term on a shift factor or the residual torque take wider bounds, :data:`WIDE_TARGETS`):

===============  ==============================================  ====================================
form             f                                               use
===============  ==============================================  ====================================
``linear``       1 + C1·z                                        a measured variable (temperature)
``quadratic``    1 + C1·z + C2·z²                                an optimum in the variable
``saturating``   1 + C1·(1 − exp(−C2·max(z, 0)))                 fade or warm-up with time or distance
``power``        (max(u, 1e-12)/REF)^C1                          a power law (REF > 0)
``decay``        1/(1 + C1·max(z, 0))                            friction decaying with slip speed:
                                                                 Pacejka 2012 eq 4.E7 (C1 = LMUV,
                                                                 v = Vs, SCALE = LONGVL)
``table``        1 + C(u), C linear between the levels L_k       a variable tested at a few levels (road
                 (C = C_k at L_k), the end values beyond them    surface, compound, temperature steps)
``interaction``  1 + C1·z + C2·z·z2                              a condition flag times a variable
                                                                 (grip loss on wet growing with speed)
``hinge``        1 + C1·max(z − C2, 0)                           a change above a threshold C2 (grip
                                                                 loss above a temperature)
``direction``    1 + C1·sgn(z)                                   hysteresis: changes sign with the
                                                                 sweep direction (v = sweep_dir)
===============  ==============================================  ====================================

Friction factors act where the book puts friction modifications (eq 4.E7: the file's
LMUX, LMUY enter lambda_mu*), so an extension on them moves the peak forces, the
vertical shifts, the trail and the residual torque, and leaves the slip stiffnesses alone;
an extension on LKX or LKY moves the stiffnesses only.

Every variable must be computable at evaluation time from the evaluator's inputs or be
an input a user supplies; quantities that need measured history (the friction energy
dissipated so far) are not allowed (:data:`BUILTIN_VARIABLES`).
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field

import numpy as np

from mftire.errors import MftireInputError
from mftire.mf import spec
from mftire.mf.basic import increments, slip_speed

#: The ``.tir`` section that holds the extension parameters.
SECTION = "MFTIRE_EXTENSIONS"

#: Scaling factors an extension may multiply (Pacejka 2012 Table 4.4, Besselink et al. 2010).
SCALING_TARGETS: tuple[str, ...] = (
    "LFZO", "LCX", "LMUX", "LEX", "LKX", "LHX", "LVX", "LCY", "LMUY", "LEY", "LKY", "LKYC", "LHY", "LVY",
    "LTR", "LRES", "LKZC", "LXAL", "LYKA", "LVYKA", "LS", "LMX", "LVMX", "LMY",
)  # fmt: skip
#: Force offsets an extension may add: ``Fz·(f − 1)`` [N].
OFFSET_TARGETS: tuple[str, ...] = ("FX_OFFSET", "FY_OFFSET")
#: Input laws: a measured MF input corrected by a law of a column, applied to the conditioned inputs
#: before the force and moment equations (a mis-measured input is one of the most common rig effects):
#: ``ALPHA_OFFSET`` alpha + (f − 1) [rad] (a slip-angle offset, e.g. a toe misalignment drifting with
#: time), ``GAMMA_OFFSET`` gamma + (f − 1) [rad] (a camber offset), ``KAPPA_OFFSET`` kappa + (f − 1) [-] (a
#: longitudinal-slip offset: a wheel-speed or effective-radius error; it moves Fx(kappa) sideways as the
#: horizontal shift SHx does, eq 4.E10, whatever the file's PHX1), ``P_FACTOR`` P·f (an effective
#: inflation pressure, e.g. P·(1 + C1·(T − T0)) when the logged pressure stays at the cold value; Gay-Lussac:
#: at constant volume P/T is constant).  The effective pressure enters every force and moment equation
#: through dpi (Pacejka 2012 eq 4.E2b); the loaded radius and contact patch keep the logged pressure.
INPUT_TARGETS: tuple[str, ...] = ("ALPHA_OFFSET", "GAMMA_OFFSET", "KAPPA_OFFSET", "P_FACTOR")
TARGETS: tuple[str, ...] = SCALING_TARGETS + OFFSET_TARGETS + INPUT_TARGETS
#: Targets whose law's size coefficients take wider fitting bounds (x this factor, and either sign): the factors
#: of the horizontal and vertical shifts (Pacejka 2012 eqs 4.E17-4.E18, 4.E27-4.E29) and of the residual torque
#: (eq 4.E47: Dr, an additive torque of either sign).  A file's shift is often near zero (PHX1, PVX1 ~ 1e-3) and its
#: residual torque a few N·m, so that a shift or a residual torque changing with a condition (a hysteresis torque
#: that changes sign with the sweep direction) needs a factor of many times 1.
WIDE_TARGETS: dict[str, float] = {"LHX": 8.0, "LHY": 8.0, "LVX": 8.0, "LVY": 8.0, "LRES": 8.0}

#: Codes of the targets that are not scaling factors in the C term table (``MF_TARGET_*`` of the generated
#: ``mf_ext_gen.h``; scaling factors are indices into ``MFParams``, >= 0).
TARGET_CODES: dict[str, int] = {"FX_OFFSET": -1, "FY_OFFSET": -2, "ALPHA_OFFSET": -3, "GAMMA_OFFSET": -4,
                                "P_FACTOR": -5, "KAPPA_OFFSET": -6}  # fmt: skip

#: Channels each target acts on (the fitter fits a term in the first stage of these).
TARGET_CHANNELS: dict[str, tuple[str, ...]] = {
    **{k: ("Fx",) for k in ("LCX", "LMUX", "LEX", "LKX", "LHX", "LVX", "LXAL", "FX_OFFSET")},
    **{k: ("Fy",) for k in ("LCY", "LMUY", "LEY", "LKY", "LKYC", "LHY", "LVY", "LYKA", "LVYKA", "FY_OFFSET")},
    **{k: ("Mz",) for k in ("LTR", "LRES", "LKZC", "LS")},
    "LMX": ("Mx",), "LVMX": ("Mx",), "LMY": ("My",), "LFZO": ("Fx", "Fy"),
    # an input law acts on the channels whose pure-slip equations read that input: the slip angle those of Fy
    # and Mz, the camber also the friction of Fx (Pacejka 2012 eq 4.E13, PDX3), the pressure all three, the
    # longitudinal slip that of Fx (the channels that read an input through the combined slip only:
    # COMBINED_READERS)
    "ALPHA_OFFSET": ("Fy", "Mz"), "GAMMA_OFFSET": ("Fy", "Mz", "Fx"), "P_FACTOR": ("Fx", "Fy", "Mz"),
    "KAPPA_OFFSET": ("Fx",),
}  # fmt: skip

#: Channels that read an input law's input through the combined-slip weighting only (not in
#: :data:`TARGET_CHANNELS`): the slip angle in Fx (Pacejka 2012 eqs 4.E54-4.E57), the longitudinal slip in Fy
#: (4.E58-4.E67).  On pure-slip sweeps a fit without the law absorbed the mis-measured input into those channels'
#: own coefficients (an unseen slip angle lowers the force of every braking sweep through G_xα): the diagnosis
#: refits them with the law (:func:`mftire.diagnosis.effects.refit_channels_of`).
COMBINED_READERS: dict[str, tuple[str, ...]] = {"ALPHA_OFFSET": ("Fx",), "KAPPA_OFFSET": ("Fy",)}

#: Variables the evaluator derives from its own (conditioned) inputs: name -> (meaning,
#: C expression over the conditioned inputs ``c`` and parameters ``p`` of the FMU's C).
#: :func:`builtin_variables` is the Python implementation.
BUILTIN_VARIABLES: dict[str, tuple[str, str]] = {v.name: (v.description, v.c_expr) for v in spec.BUILTIN_VARIABLES}

#: Input names of the evaluator that an external variable may not take.
RESERVED_VARIABLES = ("phit", "omega", "mode", "muRoad")

#: Words that make a column name an identifier (a run, sweep, segment, row, file or record
#: number): a label that only numbers things is never a law variable.  On new data the numbers
#: are different, and a law in them extrapolates without meaning (issue 21).
IDENTIFIER_WORDS = frozenset({
    "run", "runs", "sweep", "sweeps", "segment", "seg", "row", "rows", "file", "files", "id", "ids", "idx", "index",
    "number", "num", "nr", "no", "count", "counter", "record", "rec", "sequence", "seq", "trial", "uid", "key",
})  # fmt: skip


#: Physical variables whose names hold an identifier word: the sweep direction (+1 while the swept slip
#: increases, −1 while it decreases), the variable of the ``direction`` (hysteresis) form.
NOT_IDENTIFIERS = frozenset({"sweep_dir", "sweep_direction"})


def identifier_name(name: str) -> bool:
    """True when ``name`` names an identifier: one of its words (split at ``_``, ``-``, ``.``, spaces,
    digits and camel-case humps) is in :data:`IDENTIFIER_WORDS`, or is two of them run together (``run``,
    ``sweep_id``, ``RunNumber``, ``seg_no``, ``file3``, ``FILENR``, ``runno``); not the sweep direction
    (:data:`NOT_IDENTIFIERS`)."""
    if str(name).strip().lower() in NOT_IDENTIFIERS:
        return False
    words = re.findall(r"[A-Z]?[a-z]+|[A-Z]+(?![a-z])", re.sub(r"[^A-Za-z]+", " ", str(name)))
    return any(_identifier_word(w.lower()) for w in words)


def _identifier_word(w: str) -> bool:
    """``w`` is an identifier word, or two run together as one-case names write them (``FILENR``, ``runno``)."""
    return w in IDENTIFIER_WORDS or any(w.startswith(a) and w[len(a):] in IDENTIFIER_WORDS
                                        for a in IDENTIFIER_WORDS if len(a) >= 3)  # fmt: skip


#: The warning of a variable outside the range its term was fitted on (modes 1xx; the FMU's C says the same).
EXT_RANGE_WARNING = next(w.text for w in spec.WARNINGS if w.name == "EXT_RANGE")

#: Most levels of a ``table`` form.
MAX_LEVELS = 8
#: Most external (data) variables of one tyre (FMU inputs).
MAX_EXTERNAL = 4


def _linear(u, z, z2, ref, c):
    return 1.0 + c[0] * z


def _quadratic(u, z, z2, ref, c):
    return 1.0 + c[0] * z + c[1] * z * z


def _saturating(u, z, z2, ref, c):
    return 1.0 + c[0] * (1.0 - np.exp(-c[1] * np.maximum(z, 0.0)))


def _power(u, z, z2, ref, c):
    return (np.maximum(u, 1e-12) / ref) ** c[0]


def _decay(u, z, z2, ref, c):
    return 1.0 / (1.0 + c[0] * np.maximum(z, 0.0))  # Pacejka 2012 eq 4.E7


def _table(u, z, z2, ref, c):
    n = len(c) // 2
    levels, values = np.asarray(c[:n], float), c[n:]
    order = np.argsort(levels)
    u = np.asarray(u, float)
    # piecewise linear between the levels, the end values beyond them: 1 + sum_k C_k·w_k(u) with the hat weights
    # w_k of the sorted levels (np.interp of the k-th unit vector), so that the coefficients carry their derivatives
    # (mftire.mf.derivatives); w_k = 1 at L_k
    out = 1.0
    for i, v in enumerate(values):
        w = np.interp(u, levels[order], (order == i).astype(float))
        out = out + v * w
    return out


def _interaction(u, z, z2, ref, c):
    return 1.0 + c[0] * z + c[1] * z * z2


def _hinge(u, z, z2, ref, c):
    # a change that starts at a threshold z = C2 (a grip loss above a temperature): piecewise linear
    return 1.0 + c[0] * np.maximum(z - c[1], 0.0)


def _direction(u, z, z2, ref, c):
    # hysteresis: a factor (or offset) that changes sign with the sweep direction sgn(z)
    return 1.0 + c[0] * np.sign(z)


@dataclass(frozen=True)
class Form:
    """One functional form f(u; C) of an extension (neutral: every coefficient 0 -> f = 1).

    ``fn(u, z, z2, ref, c)`` is the numpy implementation, ``c_expr`` the same formula in C
    over ``u, z, z2, ref`` and the coefficient array ``c`` (for ``table``: the levels, then
    the values); :mod:`mftire.fmu.variables` generates the FMU's C from it.
    """

    name: str
    formula: str
    n_coeffs: int  #: coefficients C1..Cn (table: per level)
    bounds: tuple[tuple[float, float], ...]  #: fitting bounds of C1..Cn
    start: tuple[float, ...]  #: fitting start values of C1..Cn
    c_expr: str
    fn: Callable = field(repr=False)
    two_variables: bool = False
    equation: str = ""
    #: indices of the coefficients that set the size of the effect (not a threshold, rate or exponent): their
    #: bounds widen for the targets of :data:`WIDE_TARGETS`
    amplitudes: tuple[int, ...] = (0,)


FORMS: dict[str, Form] = {
    f.name: f
    for f in (
        Form("linear", "1 + C1·z", 1, ((-2.0, 2.0),), (0.0,), "1.0 + c[0] * z", _linear),
        Form("quadratic", "1 + C1·z + C2·z²", 2, ((-2.0, 2.0), (-2.0, 2.0)), (0.0, 0.0),
             "1.0 + c[0] * z + c[1] * z * z", _quadratic, amplitudes=(0, 1)),
        Form("saturating", "1 + C1·(1 − exp(−C2·max(z, 0)))", 2, ((-0.9, 2.0), (1e-3, 100.0)), (0.0, 1.0),
             "1.0 + c[0] * (1.0 - exp(-c[1] * fmax(z, 0.0)))", _saturating),
        Form("power", "(max(u, 1e-12)/REF)^C1", 1, ((-3.0, 3.0),), (0.0,),
             "pow(fmax(u, 1e-12) / ref, c[0])", _power, amplitudes=()),
        Form("decay", "1/(1 + C1·max(z, 0))", 1, ((0.0, 20.0),), (0.0,),
             "1.0 / (1.0 + c[0] * fmax(z, 0.0))", _decay, equation="Pacejka 2012 eq 4.E7", amplitudes=()),
        Form("table", "1 + C(u): C_k at level L_k, linear between levels, constant beyond", 0, ((-0.9, 2.0),), (0.0,),
             "1.0 + mf_ext_table(u, c, n)", _table),
        Form("interaction", "1 + C1·z + C2·z·z2", 2, ((-2.0, 2.0), (-2.0, 2.0)), (0.0, 0.0),
             "1.0 + c[0] * z + c[1] * z * z2", _interaction, two_variables=True, amplitudes=(0, 1)),
        Form("hinge", "1 + C1·max(z − C2, 0)", 2, ((-2.0, 2.0), (-3.0, 3.0)), (0.0, 0.0),
             "1.0 + c[0] * fmax(z - c[1], 0.0)", _hinge),
        Form("direction", "1 + C1·sgn(z)", 1, ((-0.5, 0.5),), (0.0,),
             "1.0 + c[0] * (double)((z > 0.0) - (z < 0.0))", _direction),
    )
}  # fmt: skip

_KEY = re.compile(r"^EXT(\d+)_([A-Z0-9_]+)$")
_STRING_FIELDS = ("TARGET", "FORM", "VARIABLE", "VARIABLE2")
_NUMBER_FIELDS = ("REF", "SCALE", "MIN", "MAX", "REF2", "SCALE2", "MIN2", "MAX2")
_NUMBER_DEFAULTS = {"REF": 0.0, "SCALE": 1.0, "MIN": -math.inf, "MAX": math.inf,
                    "REF2": 0.0, "SCALE2": 1.0, "MIN2": -math.inf, "MAX2": math.inf}  # fmt: skip


@dataclass(frozen=True)
class Extension:
    """One term of ``[MFTIRE_EXTENSIONS]``: ``targets`` multiplied by ``form`` of ``variable``.

    Attributes
    ----------
    index : int
        The ``n`` of its ``EXTn_*`` keys.
    targets : tuple of str
        Scaling factors (or force offsets) it acts on (:data:`TARGETS`).
    form : Form
    variable, variable2 : str
        The variable(s) it reads (variable2 only for two-variable forms).
    numbers : dict
        Every numeric key of the term (``EXTn_REF``, ..., ``EXTn_C1``, ``EXTn_L1``) -> value.
    """

    index: int
    targets: tuple[str, ...]
    form: Form
    variable: str
    variable2: str | None
    numbers: dict[str, float]

    def key(self, name: str) -> str:
        """The ``.tir`` key of field ``name`` (``"C1"`` -> ``"EXT1_C1"``)."""
        return f"EXT{self.index}_{name}"

    @property
    def n_levels(self) -> int:
        """Levels of a ``table`` form (0 otherwise)."""
        return sum(1 for k in self.numbers if re.fullmatch(rf"EXT{self.index}_L\d+", k))

    @property
    def coefficient_keys(self) -> tuple[str, ...]:
        """The fitted coefficients C1..Cn."""
        n = self.n_levels if self.form.name == "table" else self.form.n_coeffs
        return tuple(self.key(f"C{i}") for i in range(1, n + 1))

    @property
    def level_keys(self) -> tuple[str, ...]:
        return tuple(self.key(f"L{i}") for i in range(1, self.n_levels + 1))

    @property
    def channels(self) -> tuple[str, ...]:
        """Channels the term acts on (first stage channel first)."""
        out: list[str] = []
        for t in self.targets:
            out += [c for c in TARGET_CHANNELS[t] if c not in out]
        return tuple(out)

    def bounds(self, key: str) -> tuple[float, float]:
        """Fitting bounds of coefficient ``key``: the form's, widened for a size coefficient of a term on the
        targets of :data:`WIDE_TARGETS` only."""
        i = self.coefficient_keys.index(key)
        b = self.form.bounds
        lo, hi = b[min(i, len(b) - 1)]
        j = i if self.form.n_coeffs else 0  # a table's values share one bound
        wide = min((WIDE_TARGETS.get(t, 1.0) for t in self.targets), default=1.0)
        if wide > 1.0 and j in self.form.amplitudes:
            lo, hi = wide * min(lo, -abs(hi)), wide * hi
        return lo, hi

    def start(self, key: str) -> float:
        """Fitting start value of coefficient ``key``."""
        i = self.coefficient_keys.index(key)
        s = self.form.start
        return s[min(i, len(s) - 1)]

    def value(self, name: str, q: Mapping[str, float] | None = None) -> float:
        """Value of field ``name`` (``"REF"``, ``"C1"`` ...), from ``q`` when it holds the key."""
        k = self.key(name)
        if q is not None and k in q:
            return q[k]
        return self.numbers.get(k, _NUMBER_DEFAULTS.get(name, 0.0))

    def variables(self) -> tuple[str, ...]:
        return (self.variable,) if self.variable2 is None else (self.variable, self.variable2)

    def factor(self, v: np.ndarray, v2: np.ndarray | None, q: Mapping[str, float] | None = None,
               clip: bool = True) -> np.ndarray:
        """f(v) of this term (q: flat parameters overriding the stored coefficient values); ``clip``: the
        variables clamped to the range the term was fitted on (``MIN``..``MAX``, :meth:`outside`)."""
        u = np.minimum(np.maximum(v, self.value("MIN", q)), self.value("MAX", q)) if clip else v
        ref = self.value("REF", q)
        z = (u - ref) / self.value("SCALE", q)
        z2 = 0.0
        if self.variable2 is not None and v2 is not None:
            u2 = np.minimum(np.maximum(v2, self.value("MIN2", q)), self.value("MAX2", q)) if clip else v2
            z2 = (u2 - self.value("REF2", q)) / self.value("SCALE2", q)
        c = [q[k] if q is not None and k in q else self.numbers.get(k, 0.0) for k in self.coefficient_keys]
        if self.form.name == "table":
            c = [self.numbers[k] for k in self.level_keys] + c
        return self.form.fn(u, z, z2, ref, c)

    def outside(self, v: np.ndarray, v2: np.ndarray | None, q: Mapping[str, float] | None = None) -> bool:
        """True when a value of a variable lies outside the range the term was fitted on."""
        with np.errstate(invalid="ignore"):
            out = bool(np.any((v < self.value("MIN", q)) | (v > self.value("MAX", q))))
            if self.variable2 is not None and v2 is not None:
                out |= bool(np.any((v2 < self.value("MIN2", q)) | (v2 > self.value("MAX2", q))))
        return out

    def describe(self) -> str:
        """One line: ``LMUX·LMUY × decay(Vs)``."""
        var = self.variable if self.variable2 is None else f"{self.variable}, {self.variable2}"
        return f"{'·'.join(self.targets)} × {self.form.name}({var}): f = {self.form.formula}"

    def section(self) -> dict[str, object]:
        """The term's ``[MFTIRE_EXTENSIONS]`` entries."""
        out: dict[str, object] = {
            self.key("TARGET"): " ".join(self.targets), self.key("FORM"): self.form.name,
            self.key("VARIABLE"): self.variable,
        }  # fmt: skip
        if self.variable2 is not None:
            out[self.key("VARIABLE2")] = self.variable2
        out.update(self.numbers)
        return out


def make_extension(
    index: int,
    targets: str | tuple[str, ...] | list[str],
    form: str,
    variable: str,
    *,
    variable2: str | None = None,
    **numbers: float,
) -> Extension:
    """Build (and validate) one term; ``numbers`` by field name (``REF=0.0, C1=0.1``)."""
    sec: dict[str, object] = {
        f"EXT{index}_TARGET": targets if isinstance(targets, str) else " ".join(targets),
        f"EXT{index}_FORM": form,
        f"EXT{index}_VARIABLE": variable,
    }
    if variable2 is not None:
        sec[f"EXT{index}_VARIABLE2"] = variable2
    sec.update({f"EXT{index}_{k.upper()}": float(v) for k, v in numbers.items()})
    return parse_section(sec).terms[0]


def _check_variable(name: object, key: str) -> str:
    if not isinstance(name, str) or not name.strip():
        raise MftireInputError(f"[{SECTION}] {key} must name the variable, not {name!r}")
    name = name.strip()
    if name in RESERVED_VARIABLES:
        raise MftireInputError(
            f"[{SECTION}] {key} = {name!r}: that name is an input of the evaluator; name the variable differently"
        )
    if identifier_name(name):
        raise MftireInputError(
            f"[{SECTION}] {key} = {name!r}: an identifier (a run, sweep, segment, row or file number) cannot be a "
            "law variable: on new data the numbers differ and the law extrapolates without meaning; use the "
            "physical quantity it stands for (elapsed time, accumulated friction work, temperature, wear)"
        )
    if name.lower() in ("energy",):
        raise MftireInputError(
            f"[{SECTION}] {key} = {name!r}: a quantity that needs measured history cannot be a model variable; "
            "use a measured column (time, run index, temperature)"
        )
    return name


@dataclass(frozen=True)
class ExtensionSet:
    """The terms of one ``[MFTIRE_EXTENSIONS]`` section."""

    terms: tuple[Extension, ...]

    def __bool__(self) -> bool:
        return bool(self.terms)

    @property
    def external_variables(self) -> list[str]:
        """Variables a user must supply (data columns / FMU inputs), in term order."""
        out: list[str] = []
        for t in self.terms:
            out += [v for v in t.variables() if v not in BUILTIN_VARIABLES and v not in out]
        return out

    @property
    def coefficient_keys(self) -> list[str]:
        return [k for t in self.terms for k in t.coefficient_keys]

    def section(self) -> dict[str, object]:
        out: dict[str, object] = {}
        for t in self.terms:
            out.update(t.section())
        return out

    def scale(self, p: Mapping[str, float], variables: Mapping[str, np.ndarray], limits: bool = True,
              warn: bool = False) -> tuple[dict, dict]:
        """Effective parameters: ``(q, offsets)``.

        ``limits`` (modes 1xx): each variable is clamped to the range its term was fitted on
        (``EXTn_MIN``..``EXTn_MAX``), as the Magic Formula clamps its own inputs to the file's ranges;
        ``warn``: an :class:`~mftire.mf.inputs.MFLimitWarning` says so when a value was outside.  Without
        ``limits`` (modes 2xx) the law extrapolates.

        ``q`` is ``p`` with each targeted scaling factor replaced by λ·Π f (arrays);
        ``offsets`` maps ``FX_OFFSET``/``FY_OFFSET``, ``ALPHA_OFFSET``/``GAMMA_OFFSET``/``KAPPA_OFFSET`` to the sum
        Σ(f − 1) and ``P_FACTOR`` to the product Π f (:func:`apply_input_laws`).
        ``variables`` holds every variable the terms read (builtin and external).
        """
        q = dict(p)
        offsets: dict[str, np.ndarray] = {}
        for t in self.terms:
            v = _lookup(variables, t.variable, t)
            v2 = _lookup(variables, t.variable2, t) if t.variable2 is not None else None
            if limits and warn and t.outside(v, v2, p):
                import warnings

                from mftire.mf.inputs import MFLimitWarning

                warnings.warn(EXT_RANGE_WARNING, MFLimitWarning, stacklevel=4)
            f = t.factor(v, v2, p, clip=limits)
            for target in t.targets:
                if target == "P_FACTOR":
                    offsets[target] = offsets.get(target, 1.0) * f
                elif target in OFFSET_TARGETS or target in INPUT_TARGETS:
                    offsets[target] = offsets.get(target, 0.0) + (f - 1.0)
                else:
                    q[target] = q[target] * f
        return q, offsets


def _lookup(variables: Mapping[str, np.ndarray], name: str, t: Extension) -> np.ndarray:
    if name not in variables:
        raise MftireInputError(
            f"[{SECTION}] EXT{t.index} needs the input variable '{name}': pass it as a keyword argument or an "
            "input column"
        )
    return variables[name]


def parse_section(section: Mapping[str, object] | None) -> ExtensionSet:
    """Validate a ``[MFTIRE_EXTENSIONS]`` section into an :class:`ExtensionSet`.

    Raises :class:`~mftire.errors.MftireInputError` naming the key of the first problem.
    """
    if not section:
        return ExtensionSet(())
    sec = {str(k).upper(): v for k, v in section.items()}
    by_index: dict[int, dict[str, object]] = {}
    for key, value in sec.items():
        m = _KEY.match(key)
        if not m:
            raise MftireInputError(
                f"[{SECTION}] {key}: not an extension key (expected EXTn_TARGET, EXTn_FORM, EXTn_VARIABLE, "
                "EXTn_C1 ...; see mftire.mf.extensions)"
            )
        by_index.setdefault(int(m.group(1)), {})[m.group(2)] = value
    terms = []
    for n in sorted(by_index):
        f = by_index[n]
        for req in ("TARGET", "FORM", "VARIABLE"):
            if req not in f:
                raise MftireInputError(f"[{SECTION}] EXT{n}_{req} is missing")
        targets = tuple(t for t in re.split(r"[\s,]+", str(f["TARGET"]).strip().upper()) if t)
        bad = [t for t in targets if t not in TARGETS]
        if not targets or bad:
            raise MftireInputError(
                f"[{SECTION}] EXT{n}_TARGET = {f['TARGET']!r}: each target must be one of {', '.join(TARGETS)}"
            )
        form = FORMS.get(str(f["FORM"]).strip().lower())
        if form is None:
            raise MftireInputError(f"[{SECTION}] EXT{n}_FORM = {f['FORM']!r}: must be one of {', '.join(FORMS)}")
        variable = _check_variable(f["VARIABLE"], f"EXT{n}_VARIABLE")
        variable2 = None
        if form.two_variables:
            if "VARIABLE2" not in f:
                raise MftireInputError(f"[{SECTION}] EXT{n}_VARIABLE2 is missing (form {form.name} reads two)")
            variable2 = _check_variable(f["VARIABLE2"], f"EXT{n}_VARIABLE2")
        numbers: dict[str, float] = {}
        for name, value in f.items():
            if name in _STRING_FIELDS:
                continue
            ok = name in _NUMBER_FIELDS or re.fullmatch(r"[CL]\d+", name)
            if not ok:
                raise MftireInputError(f"[{SECTION}] EXT{n}_{name}: unknown field")
            if isinstance(value, bool) or not isinstance(value, (int, float)) or math.isnan(float(value)):
                raise MftireInputError(f"[{SECTION}] EXT{n}_{name} = {value!r} must be a number")
            numbers[f"EXT{n}_{name}"] = float(value)
        t = Extension(n, targets, form, variable, variable2, numbers)
        if t.value("SCALE") == 0.0 or (variable2 and t.value("SCALE2") == 0.0):
            raise MftireInputError(f"[{SECTION}] EXT{n}_SCALE must not be 0")
        if form.name == "power" and not t.value("REF") > 0.0:
            raise MftireInputError(f"[{SECTION}] EXT{n}_REF must be > 0 for the power form")
        if form.name == "table":
            nl = t.n_levels
            if not 1 <= nl <= MAX_LEVELS or t.level_keys != tuple(f"EXT{n}_L{i}" for i in range(1, nl + 1)):
                raise MftireInputError(f"[{SECTION}] EXT{n}: a table needs levels EXT{n}_L1..L{{k}}, 1 <= k <= "
                                       f"{MAX_LEVELS}")  # fmt: skip
            lv = [numbers[k] for k in t.level_keys]
            if len(set(lv)) != len(lv):
                raise MftireInputError(f"[{SECTION}] EXT{n}: the levels of a table must differ ({lv})")
        extra = [k for k in numbers if re.fullmatch(rf"EXT{n}_C\d+", k) and k not in t.coefficient_keys]
        if extra:
            raise MftireInputError(f"[{SECTION}] {extra[0]}: the {form.name} form has no such coefficient")
        terms.append(t)
    out = ExtensionSet(tuple(terms))
    if len(out.external_variables) > MAX_EXTERNAL:
        raise MftireInputError(f"[{SECTION}] at most {MAX_EXTERNAL} external variables, not "
                               f"{len(out.external_variables)}")  # fmt: skip
    return out


_BUILTIN_CODE = {v.name: compile(v.python, f"<builtin variable {v.name}>", "eval") for v in spec.BUILTIN_VARIABLES}


def builtin_variables(p: Mapping[str, float], c) -> dict[str, np.ndarray]:
    """The variables of :data:`BUILTIN_VARIABLES` from the file's parameters ``p`` and the
    conditioned inputs ``c`` (:class:`mftire.mf.inputs.Conditions`), by their Python expressions in
    :data:`mftire.mf.spec.BUILTIN_VARIABLES`."""
    names = {"p": p, "c": c, "np": np, "increments": increments, "slip_speed": slip_speed}
    return {name: eval(code, {"__builtins__": {}}, names) for name, code in _BUILTIN_CODE.items()}


def apply_input_laws(c, offsets: Mapping[str, np.ndarray]):
    """The conditioned inputs ``c`` (:class:`mftire.mf.inputs.Conditions`) with the input laws of
    ``offsets`` (:data:`INPUT_TARGETS`) applied: alpha + offset, gamma + offset, kappa + offset, P·factor (``c``
    itself when there is none)."""
    if not any(k in offsets for k in INPUT_TARGETS):
        return c
    import dataclasses

    return dataclasses.replace(
        c, alpha=c.alpha + offsets.get("ALPHA_OFFSET", 0.0), gamma=c.gamma + offsets.get("GAMMA_OFFSET", 0.0),
        kappa=c.kappa + offsets.get("KAPPA_OFFSET", 0.0), P=c.P * offsets.get("P_FACTOR", 1.0))  # fmt: skip


def required_variables(section: Mapping[str, object] | None) -> list[str]:
    """External variables (input columns) the section's terms need besides the MF inputs."""
    return parse_section(section).external_variables


__all__ = [
    "BUILTIN_VARIABLES", "EXT_RANGE_WARNING", "Extension", "ExtensionSet", "FORMS", "Form", "IDENTIFIER_WORDS",
    "INPUT_TARGETS", "OFFSET_TARGETS", "SCALING_TARGETS", "SECTION", "TARGETS", "TARGET_CODES", "apply_input_laws",
    "identifier_name", "make_extension", "parse_section", "required_variables",
]  # fmt: skip
