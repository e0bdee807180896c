"""The three-digit ``useMode`` switch of the reference evaluator MFeval.

=========  =================================================================
digit      meaning
=========  =================================================================
hundreds   1: apply limit checks (clip inputs to the ``*_RANGE`` sections,
           low-speed reduction below VXLOW); 2: no limit checks
tens       1: no alpha-star; 2: alpha* = tan(alpha)·sign(Vx), gamma* = sin(gamma)
           (Pacejka 2012 eqs 4.E3, 4.E4)
units      1: combined slip; 2: combined slip plus turn slip;
           0: uncombined, pure slip only (an mftire addition: Fx = Fx0,
           Fy = Fy0, Mz = Mz0 of eq 4.E31)
=========  =================================================================
"""

from __future__ import annotations

from dataclasses import dataclass

from mftire.errors import MftireInputError


@dataclass(frozen=True)
class Mode:
    """Decoded ``useMode``."""

    limits: bool
    alpha_star: bool
    turn_slip: bool
    combined: bool
    code: int
    #: Clip the curvature factors E to 1 (eqs 4.E14, 4.E24, 4.E44, 4.E56, 4.E64). None: as
    #: ``limits`` (MFeval). The fitter sets True with ``limits`` False, so that the model it
    #: fits is the one a fitted file evaluates to in mode 1xx, without clipping the inputs.
    curvature_limit: bool | None = None

    @property
    def clips_curvature(self) -> bool:
        """Whether curvature factors above 1 are clipped to 1."""
        return self.limits if self.curvature_limit is None else self.curvature_limit

    @classmethod
    def from_code(cls, code: int) -> Mode:
        """Decode a three-digit mode such as 111, 121, 211 or 112."""
        try:
            icode = int(code)
        except (TypeError, ValueError):
            raise MftireInputError(f"mode must be a three-digit integer such as 111, got {code!r}") from None
        if icode != code or not 100 <= icode <= 999:
            raise MftireInputError(f"mode must be a three-digit integer such as 111, got {code!r}")
        hundreds, tens, units = icode // 100, (icode // 10) % 10, icode % 10
        if hundreds not in (1, 2):
            raise MftireInputError(f"mode {icode}: hundreds digit must be 1 (limit checks) or 2 (none)")
        if tens not in (1, 2):
            raise MftireInputError(f"mode {icode}: tens digit must be 1 (no alpha-star) or 2 (alpha-star)")
        if units not in (0, 1, 2):
            raise MftireInputError(
                f"mode {icode}: units digit must be 0 (pure slip), 1 (combined) or 2 (combined + turn slip)"
            )
        return cls(
            limits=hundreds == 1,
            alpha_star=tens == 2,
            turn_slip=units == 2,
            combined=units != 0,
            code=icode,
        )
