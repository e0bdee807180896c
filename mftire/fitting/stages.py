"""Stage definitions: which coefficients each fitting stage adjusts, on which data.

The staged procedure follows common tyre-engineering practice (Pacejka 2012, §4.3.2;
the equations are those of :mod:`mftire.mf`):

====  =============  ==========  ======================  ==============================
 #    name           channel(s)  data rows (sweep kind)  coefficients
====  =============  ==========  ======================  ==============================
 1    longitudinal   Fx          pure longitudinal       PCX1, PDX*, PEX*, PKX*, PHX*,
                                                         PVX*, PPX* (eqs 4.E9–4.E18)
 2    lateral        Fy          pure lateral            PCY1, PDY*, PEY*, PKY*, PHY*,
                                                         PVY*, PPY* (eqs 4.E19–4.E30)
 3    aligning       Mz          pure lateral            QBZ*, QCZ1, QDZ*, QEZ*, QHZ*,
                                                         PPZ* (eqs 4.E31–4.E47)
 4    combined       Fx, Fy      combined and pure       RBX*, RCX1, REX*, RHX1 (4.E50–
                                                         4.E57); RBY*, RCY1, REY*, RHY*,
                                                         RVY* (4.E58–4.E67)
 5    combined_mz    Mz          combined                SSZ1–SSZ4 (4.E71–4.E76, A56)
 6    overturning    Mx          all                     QSX*, PPMX1 (draft eq 49)
 7    rolling        My          all                     QSY1–QSY8 (A48)
====  =============  ==========  ======================  ==============================

Every coefficient carries the data it needs to be identified (see
:mod:`mftire.fitting.identify`) and loose bounds.  Operating constants (``FNOMIN``,
``NOMPRES``, ``UNLOADED_RADIUS``, ``LONGVL``, ranges ...) and the scaling factors
``L*`` are never fitted: they are not in any stage.
"""

from __future__ import annotations

from dataclasses import dataclass, field

__all__ = ["Coefficient", "Stage", "STAGES", "STAGE_BY_NAME", "resolve_stages", "FITTED_KEYS"]


@dataclass(frozen=True)
class Coefficient:
    """One fitted coefficient.

    Attributes
    ----------
    key : str
        ``.tir`` key.
    lower, upper : float
        Loose physical bounds (widened to contain the template value when needed).
    scale : float
        Typical magnitude, used as the least-squares parameter scale (``x_scale``)
        when the start value is smaller.
    needs : tuple of str
        Identifiability requirements, names of :data:`mftire.fitting.identify.RULES`,
        e.g. ``("loads2",)`` for a linear load term, ``("loads3",)`` for a dfz² term.
    keep_sign : bool
        The bounds are restricted to the sign of the start value (peak factors,
        stiffness factors that appear in a denominator).
    """

    key: str
    lower: float
    upper: float
    scale: float = 1.0
    needs: tuple[str, ...] = ()
    keep_sign: bool = False


def _c(key, lower, upper, scale=1.0, *needs, keep_sign=False) -> Coefficient:
    return Coefficient(key, float(lower), float(upper), float(scale), tuple(needs), keep_sign)


@dataclass(frozen=True)
class Stage:
    """One fitting stage.

    Attributes
    ----------
    number : int
        1..7, the order of the procedure.
    name : str
        Short name used on the command line (``--stages longitudinal,lateral`` or ``1,2``).
    channels : tuple of str
        Measured channels the residuals use.
    kinds : tuple of str
        Sweep kinds (see :func:`mftire.segmentation.grouping.sweep_kind`) whose rows are fitted;
        empty: every row.  The first kind is required (the stage is skipped without it);
        the others add rows.
    groups : tuple of tuple of Coefficient
        Independent sub-problems: one group per channel (stage 4 fits the Fx and the
        Fy coefficients separately since they do not interact).
    title : str
        Human-readable title.
    """

    number: int
    name: str
    channels: tuple[str, ...]
    kinds: tuple[str, ...]
    groups: tuple[tuple[Coefficient, ...], ...]
    title: str
    min_points: int = field(default=8)

    @property
    def coefficients(self) -> tuple[Coefficient, ...]:
        return tuple(c for g in self.groups for c in g)


def _shape_peak_curvature(axis: str) -> tuple[Coefficient, ...]:
    """The shape factor, the peak factor and the first curvature coefficients of the pure-slip force of
    ``axis`` ("X": PCX1, PDX1-3, PEX1-2, eqs 4.E11, 4.E13, 4.E14; "Y": PCY1, PDY1-3, PEY1-2, eqs 4.E21, 4.E23,
    4.E24), with the same bounds for both forces."""
    return (
        _c(f"PC{axis}1", 0.5, 3.0, 1.0, keep_sign=True),
        _c(f"PD{axis}1", -5.0, 5.0, 1.0, keep_sign=True),
        _c(f"PD{axis}2", -3.0, 3.0, 0.1, "loads2"),
        _c(f"PD{axis}3", -200.0, 200.0, 1.0, "gamma_even"),
        _c(f"PE{axis}1", -30.0, 1.0, 0.5),
        _c(f"PE{axis}2", -30.0, 30.0, 0.1, "loads2"),
    )


_FX = (
    *_shape_peak_curvature("X"),  # eqs 4.E11, 4.E13, 4.E14
    _c("PEX3", -30.0, 30.0, 0.1, "loads3"),
    _c("PEX4", -1.0, 1.0, 0.1, "kappa_both_signs"),
    _c("PKX1", -500.0, 500.0, 10.0, keep_sign=True),  # eq 4.E15
    _c("PKX2", -500.0, 500.0, 1.0, "loads2"),
    _c("PKX3", -10.0, 10.0, 0.1, "loads3"),
    _c("PHX1", -0.1, 0.1, 1e-3),  # eq 4.E17
    _c("PHX2", -0.1, 0.1, 1e-3, "loads2"),
    _c("PVX1", -1.0, 1.0, 1e-2),  # eq 4.E18
    _c("PVX2", -1.0, 1.0, 1e-2, "loads2"),
    _c("PPX1", -10.0, 10.0, 0.1, "pressures2"),
    _c("PPX2", -10.0, 10.0, 0.1, "pressures3"),
    _c("PPX3", -10.0, 10.0, 0.1, "pressures2"),
    _c("PPX4", -10.0, 10.0, 0.1, "pressures3"),
)

_FY = (
    *_shape_peak_curvature("Y"),  # eqs 4.E21, 4.E23, 4.E24
    _c("PEY3", -30.0, 30.0, 0.1, "alpha_both_signs"),
    _c("PEY4", -500.0, 500.0, 1.0, "gamma", "alpha_both_signs"),
    _c("PEY5", -2000.0, 2000.0, 10.0, "gamma_even"),
    _c("PKY1", -500.0, 500.0, 10.0, keep_sign=True),  # eq 4.E25
    _c("PKY2", -100.0, 100.0, 1.0, "loads2", keep_sign=True),
    _c("PKY3", -20.0, 20.0, 0.1, "gamma_even"),
    _c("PKY4", -20.0, 20.0, 1.0, "loads3", keep_sign=True),
    _c("PKY5", -1000.0, 1000.0, 1.0, "gamma_even", "loads2"),
    _c("PKY6", -20.0, 20.0, 0.1, "gamma"),  # eq 4.E30
    _c("PKY7", -20.0, 20.0, 0.1, "gamma", "loads2"),
    _c("PHY1", -0.1, 0.1, 1e-3),  # eq 4.E27
    _c("PHY2", -0.1, 0.1, 1e-3, "loads2"),
    _c("PVY1", -1.0, 1.0, 1e-2),  # eq 4.E29
    _c("PVY2", -1.0, 1.0, 1e-2, "loads2"),
    _c("PVY3", -20.0, 20.0, 0.1, "gamma"),  # eq 4.E28
    _c("PVY4", -20.0, 20.0, 0.1, "gamma", "loads2"),
    _c("PPY1", -10.0, 10.0, 0.1, "pressures2"),
    _c("PPY2", -10.0, 10.0, 0.1, "pressures2"),
    _c("PPY3", -10.0, 10.0, 0.1, "pressures2"),
    _c("PPY4", -10.0, 10.0, 0.1, "pressures3"),
    _c("PPY5", -10.0, 10.0, 0.1, "pressures2", "gamma"),
)

_MZ = (
    # pneumatic trail (eqs 4.E33–4.E35, 4.E41, 4.E44; Besselink 2010 A58, A60)
    _c("QBZ1", -100.0, 100.0, 1.0, keep_sign=True),
    _c("QBZ2", -100.0, 100.0, 0.1, "loads2"),
    _c("QBZ3", -100.0, 100.0, 0.1, "loads3"),
    _c("QBZ4", -100.0, 100.0, 0.1, "gamma"),
    _c("QBZ5", -100.0, 100.0, 0.1, "gamma_abs_vs_linear"),
    _c("QCZ1", 0.3, 3.0, 1.0, keep_sign=True),
    _c("QDZ1", -1.0, 1.0, 0.01, keep_sign=True),
    _c("QDZ2", -1.0, 1.0, 1e-3, "loads2"),
    _c("QDZ3", -50.0, 50.0, 0.1, "gamma"),
    _c("QDZ4", -500.0, 500.0, 0.1, "gamma_square_vs_linear"),
    _c("QEZ1", -100.0, 1.0, 0.5),
    _c("QEZ2", -100.0, 100.0, 0.1, "loads2"),
    _c("QEZ3", -100.0, 100.0, 0.1, "loads3"),
    _c("QEZ4", -10.0, 10.0, 0.1, "alpha_both_signs"),
    _c("QEZ5", -100.0, 100.0, 0.1, "alpha_both_signs", "gamma"),
    _c("QHZ1", -0.1, 0.1, 1e-3),
    _c("QHZ2", -0.1, 0.1, 1e-3, "loads2"),
    _c("QHZ3", -10.0, 10.0, 0.01, "gamma"),
    _c("QHZ4", -10.0, 10.0, 0.01, "gamma", "loads2"),
    _c("PPZ1", -10.0, 10.0, 0.1, "pressures2"),
    # residual torque (eqs 4.E45–4.E47)
    _c("QBZ9", -200.0, 200.0, 1.0),
    _c("QBZ10", -20.0, 20.0, 0.1, "loads2"),
    _c("QDZ6", -1.0, 1.0, 1e-3),
    _c("QDZ7", -1.0, 1.0, 1e-3, "loads2"),
    _c("QDZ8", -50.0, 50.0, 0.1, "gamma"),
    _c("QDZ9", -50.0, 50.0, 0.1, "gamma", "loads2"),
    _c("QDZ10", -500.0, 500.0, 0.1, "gamma_odd2_vs_linear"),
    _c("QDZ11", -500.0, 500.0, 0.1, "gamma_odd2_vs_linear", "loads2"),
    _c("PPZ2", -10.0, 10.0, 0.1, "pressures2", "gamma"),
)

_FX_COMBINED = (  # eqs 4.E50–4.E57
    _c("RBX1", -500.0, 500.0, 1.0, "combined", keep_sign=True),
    _c("RBX2", -500.0, 500.0, 1.0, "combined", "kappa_levels2"),
    _c("RBX3", -5000.0, 5000.0, 1.0, "combined", "gamma_even"),
    _c("RCX1", 0.2, 3.0, 1.0, "combined", keep_sign=True),
    _c("REX1", -30.0, 1.0, 0.1, "combined"),
    _c("REX2", -30.0, 30.0, 0.1, "combined", "loads2"),
    _c("RHX1", -0.5, 0.5, 1e-3, "combined", "alpha_both_signs"),
)

_FY_COMBINED = (  # eqs 4.E58–4.E67
    _c("RBY1", -500.0, 500.0, 1.0, "combined", keep_sign=True),
    _c("RBY2", -500.0, 500.0, 1.0, "combined", "alpha_levels2"),
    _c("RBY3", -1.0, 1.0, 1e-2, "combined", "alpha_levels2"),
    _c("RBY4", -5000.0, 5000.0, 1.0, "combined", "gamma_even"),
    _c("RCY1", 0.2, 3.0, 1.0, "combined", keep_sign=True),
    _c("REY1", -30.0, 1.0, 0.1, "combined"),
    _c("REY2", -30.0, 30.0, 0.1, "combined", "loads2"),
    _c("RHY1", -0.5, 0.5, 1e-3, "combined", "kappa_both_signs"),
    _c("RHY2", -0.5, 0.5, 1e-3, "combined", "kappa_both_signs", "loads2"),
    _c("RVY1", -50.0, 50.0, 0.1, "combined"),
    _c("RVY2", -50.0, 50.0, 0.1, "combined", "loads2"),
    _c("RVY3", -1000.0, 1000.0, 1.0, "combined", "gamma"),
    _c("RVY4", -1000.0, 1000.0, 1.0, "combined", "alpha_levels2"),
    _c("RVY5", -10.0, 10.0, 0.1, "combined"),
    _c("RVY6", -1000.0, 1000.0, 1.0, "combined", "kappa_levels2"),
)

_MZ_COMBINED = (  # Besselink 2010 A56 (eq 4.E76)
    _c("SSZ1", -5.0, 5.0, 0.01, "combined"),
    _c("SSZ2", -5.0, 5.0, 0.01, "combined"),
    _c("SSZ3", -50.0, 50.0, 0.1, "combined", "gamma"),
    _c("SSZ4", -50.0, 50.0, 0.1, "combined", "gamma", "loads2"),
)

_MX = (  # Besselink et al. 2010 draft eq 49
    _c("QSX1", -1.0, 1.0, 1e-3),
    _c("QSX2", -50.0, 50.0, 0.1, "gamma"),
    _c("QSX3", -10.0, 10.0, 0.01, "lateral_force"),
    _c("QSX12", -500.0, 500.0, 0.1, "gamma_odd2_vs_linear"),
    _c("QSX13", -10.0, 10.0, 0.01, "lateral_force"),
    _c("QSX14", -100.0, 100.0, 0.01, "lateral_force", "gamma_even"),
    _c("PPMX1", -10.0, 10.0, 0.1, "pressures2", "gamma"),
    _c("QSX4", -10.0, 10.0, 0.1, "mx_nonlinear", "loads3"),
    _c("QSX5", -50.0, 50.0, 0.1, "mx_nonlinear", "loads3", "mx_load_factor"),
    _c("QSX6", -100.0, 100.0, 1.0, "mx_nonlinear", "loads3", "mx_load_factor"),
    _c("QSX7", -50.0, 50.0, 0.1, "mx_nonlinear", "gamma"),
    _c("QSX8", -50.0, 50.0, 0.1, "mx_nonlinear", "lateral_force"),
    _c("QSX9", -50.0, 50.0, 0.1, "mx_nonlinear", "lateral_force"),
    _c("QSX10", -50.0, 50.0, 0.1, "gamma", "loads2"),
    _c("QSX11", -50.0, 50.0, 0.1, "gamma", "loads3"),
)

_MY = (  # Besselink 2010 eq A48
    _c("QSY1", -1.0, 1.0, 1e-3),
    _c("QSY2", -1.0, 1.0, 1e-3, "longitudinal_force"),
    _c("QSY3", -1.0, 1.0, 1e-4, "speeds2"),
    _c("QSY4", -1.0, 1.0, 1e-5, "speeds3"),
    _c("QSY5", -100.0, 100.0, 0.01, "gamma_even"),
    _c("QSY6", -100.0, 100.0, 0.01, "gamma_even", "loads2"),
    _c("QSY7", -5.0, 5.0, 0.1, "loads2"),
    _c("QSY8", -5.0, 5.0, 0.1, "pressures2"),
)

STAGES: tuple[Stage, ...] = (
    Stage(1, "longitudinal", ("Fx",), ("pure_longitudinal", "free_rolling"), (_FX,),
          "pure longitudinal force Fx0"),
    Stage(2, "lateral", ("Fy",), ("pure_lateral", "free_rolling"), (_FY,), "pure lateral force Fy0"),
    Stage(3, "aligning", ("Mz",), ("pure_lateral", "free_rolling"), (_MZ,), "pure aligning moment Mz0"),
    # pure-slip rows too: the kappa-induced side force (RVY, eq 4.E66) shows most directly
    # in Fy of braking at alpha = 0; Gxa = 1 at alpha = 0 and Gyk = 1 at kappa = 0
    Stage(4, "combined", ("Fx", "Fy"), ("combined", "pure_longitudinal", "pure_lateral"),
          (_FX_COMBINED, _FY_COMBINED), "combined-slip forces Fx, Fy"),
    Stage(5, "combined_mz", ("Mz",), ("combined",), (_MZ_COMBINED,), "combined-slip aligning moment Mz"),
    Stage(6, "overturning", ("Mx",), (), (_MX,), "overturning moment Mx"),
    Stage(7, "rolling", ("My",), (), (_MY,), "rolling-resistance moment My"),
)  # fmt: skip

STAGE_BY_NAME: dict[str, Stage] = {s.name: s for s in STAGES}

#: Every key any stage may change.
FITTED_KEYS: frozenset[str] = frozenset(c.key for s in STAGES for c in s.coefficients)

_ALIASES = {"fx": "longitudinal", "fy": "lateral", "mz": "aligning", "fxfy": "combined",
            "mzc": "combined_mz", "mx": "overturning", "my": "rolling", "pure_fx": "longitudinal",
            "pure_fy": "lateral", "pure_mz": "aligning"}


def resolve_stages(spec: str | list | tuple | None) -> tuple[Stage, ...]:
    """Stages from ``"1,2,3"``, ``"longitudinal,lateral"``, ``"all"`` or a list of those.

    Raises
    ------
    ValueError
        Naming the unknown stage and listing the valid names.
    """
    if spec is None or spec == "all":
        return STAGES
    items = spec.split(",") if isinstance(spec, str) else [str(s) for s in spec]
    chosen: set[int] = set()
    for raw in items:
        item = raw.strip().lower()
        if not item:
            continue
        if item == "all":
            return STAGES
        if item.isdigit() and 1 <= int(item) <= len(STAGES):
            chosen.add(int(item))
            continue
        name = _ALIASES.get(item, item)
        if name not in STAGE_BY_NAME:
            valid = ", ".join(f"{s.number}={s.name}" for s in STAGES)
            raise ValueError(f"unknown stage {raw.strip()!r}; valid stages: {valid}, or all")
        chosen.add(STAGE_BY_NAME[name].number)
    return tuple(s for s in STAGES if s.number in chosen)
