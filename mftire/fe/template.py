"""An MF 6.1 starting template for a tyre design of the FE surrogate.

A fit starts from a template that holds the constants of the tyre — nominal load,
radius, size, pressures, vertical stiffness — and start values of the shape
coefficients.  :func:`mf_template` takes the constants from the FE tyre description
and the shape coefficients from a shipped MF 6.1 file (the tyre of
``mftire/data/default.tir``), so a fit of FE sweeps starts from sensible values.
"""

from __future__ import annotations

from mftire.fe.config import TyreConfig
from mftire.iotools.tir import TirParameters, read_tir

#: The standard pressure coefficients (Besselink et al. 2010; Pacejka 2012 §4.3.2).
PRESSURE_KEYS = ("PPX1", "PPX2", "PPX3", "PPX4", "PPY1", "PPY2", "PPY3", "PPY4", "PPY5", "PPZ1", "PPZ2",
                 "PPMX1", "PFZ1", "PCFX3", "PCFY3", "PCMZ1", "QSY8")  # fmt: skip


def mf_template(tyre: TyreConfig, pressure_terms: bool = True, base: str | None = None) -> TirParameters:
    """MF 6.1 template for ``tyre``.

    Parameters
    ----------
    tyre : TyreConfig
        FE-surrogate tyre design.
    pressure_terms : bool
        With False, every pressure coefficient is set to zero (a ``.tir`` without
        inflation-pressure terms).
    base : path, optional
        MF 6.1 file giving the start values of the shape coefficients (default: the
        shipped ``default.tir``).
    """
    from mftire.data import default_tir

    params = read_tir(base or default_tir())
    s = tyre.size
    R0 = tyre.unloaded_radius
    F0 = tyre.load_index_load
    P0 = s.nominal_pressure
    constants = {
        "FNOMIN": F0,  # [N] the load-index load
        "UNLOADED_RADIUS": R0,  # [m]
        "WIDTH": s.section_width,  # [m]
        "ASPECT_RATIO": s.aspect_ratio,  # [-]
        "RIM_RADIUS": 0.5 * s.rim_diameter_in * 0.0254,  # [m]
        "NOMPRES": P0,  # [Pa]
        "INFLPRES": P0,  # [Pa]
        "VERTICAL_STIFFNESS": tyre.vertical.cz0,  # [N/m]
        "LONGVL": tyre.vertical.v0,  # [m/s]
        "FZMIN": 0.0,
        "FZMAX": s.max_load_fraction * F0,
        "PRESMIN": s.min_pressure_fraction * P0,
        "PRESMAX": s.max_pressure_fraction * P0,
    }
    for k, v in constants.items():
        params.set(k, float(v))
    if not pressure_terms:
        for k in PRESSURE_KEYS:
            params.set(k, 0.0)
    return params
