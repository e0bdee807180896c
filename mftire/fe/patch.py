"""Contact patch: size, rib layout and normal-pressure distribution on the element grid.

Grid convention (per operating point): ``ny`` rows across the width at lateral
positions ``y_j`` (ISO W-axis: y to the left), each row discretised into ``nx``
equal elements from the leading edge (x = +a_j) to the trailing edge (x = -a_j).
Row j has its own half-length ``a_j`` (rounded footprint ends, long/short
shoulder under lateral load) and land fraction ``land_j`` (circumferential
grooves carry no pressure).  Units: m, N, Pa.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from mftire.fe.carcass import pressure_increment
from mftire.fe.config import TyreConfig


@dataclass(frozen=True)
class PatchGeometry:
    """Contact-patch geometry for a batch of n operating points."""

    a: np.ndarray  #: nominal contact half-length (n,) [m]
    b: np.ndarray  #: contact half-width (n,) [m]
    y: np.ndarray  #: row centre lines (n, ny) [m]
    dy: np.ndarray  #: row pitch (n,) [m]
    land: np.ndarray  #: land (rubber) fraction of each row (n, ny) [-]
    eta: np.ndarray  #: normalised row position y/b (n, ny) [-]
    xi: np.ndarray  #: normalised element centres along a row, +1 -> -1 (nx,) [-]


def contact_half_length(R_omega: ArrayLike, rho: ArrayLike, q_a: float) -> np.ndarray:
    """Contact half-length a = q_a sqrt(2 R rho - rho^2) [m]: a scaled chord of the deflected circle
    (the usual brush-model footprint length, Pacejka 2012 section 3.2 / Besselink's a(rho) law)."""
    R_omega, rho = np.asarray(R_omega, dtype=float), np.asarray(rho, dtype=float)
    return q_a * np.sqrt(np.clip(2.0 * R_omega * rho - rho**2, 0.0, None))


def contact_half_width(tyre: TyreConfig, rho: ArrayLike) -> np.ndarray:
    """Contact half-width b = (W_t/2)(1 - c_w exp(-rho/rho_w)) [m]; grows to the tread width with load."""
    pa = tyre.patch
    rho = np.asarray(rho, dtype=float)
    return 0.5 * tyre.size.tread_width * (1.0 - pa.width_drop * np.exp(-rho / pa.width_rho))


def land_fraction(edges: np.ndarray, groove_centres: ArrayLike, groove_width: float) -> np.ndarray:
    """Fraction of each row [edges[..., j], edges[..., j+1]] not covered by grooves [-]."""
    lo, hi = edges[..., :-1], edges[..., 1:]
    covered = np.zeros_like(lo)
    for gc in np.atleast_1d(np.asarray(groove_centres, dtype=float)):
        g_lo, g_hi = gc - 0.5 * groove_width, gc + 0.5 * groove_width
        covered += np.clip(np.minimum(hi, g_hi) - np.maximum(lo, g_lo), 0.0, None)
    return np.clip(1.0 - covered / (hi - lo), 0.0, 1.0)


def patch_geometry(tyre: TyreConfig, a: np.ndarray, b: np.ndarray) -> PatchGeometry:
    """Row layout (positions, pitch, land fraction) for half-length a and half-width b (n,)."""
    nx, ny = tyre.grid.nx, tyre.grid.ny
    u = np.linspace(-1.0, 1.0, ny + 1)
    edges = b[:, None] * u[None, :]
    y = 0.5 * (edges[:, :-1] + edges[:, 1:])
    land = land_fraction(edges, tyre.patch.groove_centres, tyre.patch.groove_width)
    xi = 1.0 - (np.arange(nx) + 0.5) * 2.0 / nx
    return PatchGeometry(a=a, b=b, y=y, dy=2.0 * b / ny, land=land, eta=y / b[:, None], xi=xi)


def shoulder_bias(tyre: TyreConfig, Fz: ArrayLike, P: ArrayLike) -> np.ndarray:
    """Shoulder/centre load bias c_sh [-]: > 0 loads the shoulders (under-inflation, overload),
    < 0 the centre (over-inflation) -- the classical footprint behaviour (cf. thesis Fig. 5.11)."""
    pa = tyre.patch
    fz_n = np.asarray(Fz, dtype=float) / tyre.load_index_load
    return pa.shoulder0 - pa.shoulder_pressure * pressure_increment(tyre, P) + pa.shoulder_load * (fz_n - 0.8)


def row_half_lengths(tyre: TyreConfig, geom: PatchGeometry, c_sh: np.ndarray, lam: np.ndarray) -> np.ndarray:
    """Per-row half-lengths a_j (n, ny) [m].

    Rounded ends (1 - c eta^4), longer shoulders when c_sh > 0 (butterfly footprint of an
    under-inflated tyre), and the long/short shoulder of a cornering tyre through the lateral
    load-transfer parameter lam (thesis 6.2: 'a right turn leads to a long left shoulder').
    """
    eta = geom.eta
    shape = (1.0 - tyre.patch.end_rounding * eta**4) * (1.0 + 0.5 * c_sh[:, None] * (eta**2 - 1.0 / 3.0))
    shape *= np.clip(1.0 + 0.5 * lam[:, None] * eta, 0.2, None)
    return geom.a[:, None] * np.clip(shape, 0.1, None)


def longitudinal_shape(xi: np.ndarray, exponent: float, skew: np.ndarray) -> np.ndarray:
    """Pressure shape along a row, (1 - |xi|^n)(1 + s xi) for each point (n, nx) [-].

    The forward skew s moves the pressure centre ahead of the contact centre: the
    hysteresis (rolling-resistance) moment of a rolling viscoelastic tyre (Pacejka 2012 section 4.3.4).
    """
    base = 1.0 - np.abs(xi) ** exponent
    return base[None, :] * (1.0 + skew[:, None] * xi[None, :])


def skew_for_offset(xi: np.ndarray, exponent: float, offset_ratio: np.ndarray) -> np.ndarray:
    """Skew s giving a pressure-centre offset e = offset_ratio * a (exact on the discrete grid)."""
    base = 1.0 - np.abs(xi) ** exponent
    c_n = np.sum(base * xi**2) / np.sum(base)
    return np.clip(offset_ratio / c_n, -0.9, 0.9)


def pressure_field(
    tyre: TyreConfig,
    Fz: np.ndarray,
    geom: PatchGeometry,
    a_row: np.ndarray,
    c_sh: np.ndarray,
    lam: np.ndarray,
    skew: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Normal pressure on the grid.

    Returns (p_row, g, area): the pressure of element (j, i) is ``p_row[:, j] * g[:, i]`` [Pa],
    with ``area[:, j]`` the rubber area of one element of row j [m^2].  The row loads follow the
    lateral weighting (1 + c_sh (eta^2 - 1/3)) (1 + lam eta) over the land area, and the field
    integrates exactly to Fz.
    """
    eta = geom.eta
    nx = geom.xi.size
    weight = np.clip(1.0 + c_sh[:, None] * (eta**2 - 1.0 / 3.0), 0.05, None)
    weight *= np.clip(1.0 + lam[:, None] * eta, 0.05, None)
    area = geom.land * geom.dy[:, None] * (2.0 * a_row / nx)  # element rubber area
    g = longitudinal_shape(geom.xi, tyre.patch.pressure_exponent, skew)
    row_load_w = weight * area * np.sum(g, axis=1)[:, None]  # load of row j for unit row pressure
    p_row = weight * Fz[:, None] / np.sum(row_load_w, axis=1)[:, None]
    return p_row, g, area
