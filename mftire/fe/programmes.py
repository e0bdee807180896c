"""Demonstration test programmes: measured-like campaigns with one effect MF 6.1 lacks.

Each programme is simulated with the FE surrogate and the artefacts of
:mod:`mftire.fe.measured` (noise, Fz wander, offsets, drift), and says how its MF
model is fitted.  They are *simulated* data, made to show and test the diagnosis:

==============  ===================================================================
name            content
==============  ===================================================================
``slip_speed``  friction that depends on the local sliding speed (Savkoor law with a
                fixed Vmax, thesis eq 2.2); braking at 20–100 km/h, cornering at 60
                km/h, three loads.  The MF 6.1 fit has no speed terms.
``fade``        thermal fade: the friction level falls with the friction energy
                dissipated along the sequence; three passes of braking and cornering
                at three loads, 60 km/h.
``pressure``    five inflation pressures (nominal, ±0.25 and ±0.5 bar); the MF model is
                fitted to all of them with its pressure terms held at zero (a
                ``.tir`` without pressure terms).
``null``        nothing MF 6.1 lacks: 60 km/h, nominal pressure, three loads.
==============  ===================================================================
"""

from __future__ import annotations

from dataclasses import dataclass

import pandas as pd

from mftire.fe.config import TyreConfig, load_tyre
from mftire.fe.measured import Artefacts, measured_campaign, thermal_fade
from mftire.fe.slip_sweeps import KMH, Condition
from mftire.fe.template import mf_template
from mftire.iotools.tir import TirParameters
from mftire.parallel import Executor

PROGRAMMES = ("slip_speed", "fade", "pressure", "null")

#: Pressure coefficients of the fitting stages, held at zero in the ``pressure`` programme.
PRESSURE_KEYS_FITTED = ("PPX1", "PPX2", "PPX3", "PPX4", "PPY1", "PPY2", "PPY3", "PPY4", "PPY5", "PPZ1", "PPZ2",
                        "PPMX1", "QSY8")  # fmt: skip

#: The effect each programme contains, as the diagnosis should name it.
EXPECTED_CAUSE = {"slip_speed": "Vs", "fade": ("energy", "time", "sequence"), "pressure": "P", "null": None}


@dataclass
class Programme:
    """A simulated campaign and how its MF model is fitted."""

    name: str
    data: pd.DataFrame
    template: TirParameters
    fit_rows: pd.Series  #: rows the MF model is fitted on (bool)
    description: str
    fixed: tuple[str, ...] = ()  #: coefficients held at the template's values in the fit


def slip_speed_tyre(base: TyreConfig | None = None) -> TyreConfig:
    """The default tyre with friction depending on the local sliding speed alone:
    constant Vmax = 1 m/s and h = 0.5 (thesis eq 2.2), mu_s and mu_m independent of Vx."""
    base = base or load_tyre(None)
    return base.updated({
        "friction.v_max": 1.0, "friction.h": 0.5, "friction.mu_lock": None,
        "friction.mu_m": [0.0, 1.05], "friction.mu_s": [0.0, 0.0, 0.62],
    })  # fmt: skip


def _loads(tyre: TyreConfig) -> list[float]:
    li = tyre.load_index_load
    return [0.4 * li, 0.8 * li, 1.2 * li]


def programme(name: str, seed: int = 0, scale: float = 1.0, executor: Executor | None = None) -> Programme:
    """Simulate one demonstration programme (``scale`` < 1 thins the slip grids for tests).

    ``executor`` runs the chunks of points of programmes without fade (default: in this process;
    see :mod:`mftire.parallel`); the data do not depend on it.
    """
    if name not in PROGRAMMES:
        raise ValueError(f"unknown programme {name!r}; choose from {', '.join(PROGRAMMES)}")
    base = load_tyre(None)
    pn = base.size.nominal_pressure
    nk, na = max(8, int(round(40 * scale))), max(9, int(round(41 * scale)))
    art = Artefacts(noise=0.005)  # a good rig: 0.5 % of peak
    v60 = 60.0 * KMH
    if name == "slip_speed":
        tyre = slip_speed_tyre(base)
        jobs = []
        for f in _loads(tyre):
            for v in (20.0, 40.0, 60.0, 80.0, 100.0):
                jobs.append(("braking", Condition(f, v * KMH, pn)))
            jobs.append(("cornering", Condition(f, v60, pn)))
        data = measured_campaign(tyre, jobs, art, n_kappa=nk, n_alpha=na, seed=seed, executor=executor)
        return Programme(name, data, mf_template(tyre), pd.Series(True, index=data.index),
                         "friction depends on sliding speed (fixed Vmax); braking 20-100 km/h")  # fmt: skip
    if name == "fade":
        tyre = base
        one_pass = [(kind, Condition(f, v60, pn)) for f in _loads(tyre) for kind in ("braking", "cornering")]
        jobs = one_pass * 3
        clean = measured_campaign(tyre, jobs, Artefacts(0.0, 0.0, {}, 0.0), n_kappa=nk, n_alpha=na, seed=seed,
                                  executor=executor)
        # friction energy of the whole programme, to set the fade's energy scale
        e_total = float(((clean.Fx * clean.kappa * clean.Vx).abs() + (clean.Fy * clean.Vx * clean.alpha.abs()).abs())
                        .sum() * art.point_time)  # fmt: skip
        data = measured_campaign(tyre, jobs, art, fade=thermal_fade(0.15, 0.4 * e_total), n_kappa=nk,
                                 n_alpha=na, seed=seed)  # fmt: skip
        return Programme(name, data, mf_template(tyre), pd.Series(True, index=data.index),
                         "thermal fade: friction falls with dissipated energy along the sequence")  # fmt: skip
    if name == "pressure":
        tyre = base
        pressures = (pn, pn - 0.5e5, pn + 0.5e5, pn - 0.25e5, pn + 0.25e5)
        jobs = [(kind, Condition(f, v60, p)) for p in pressures for f in _loads(tyre)
                for kind in ("braking", "cornering")]  # fmt: skip
        data = measured_campaign(tyre, jobs, art, n_kappa=nk, n_alpha=na, seed=seed, executor=executor)
        return Programme(name, data, mf_template(tyre, pressure_terms=False), pd.Series(True, index=data.index),
                         "three pressures; MF fitted without pressure terms", fixed=PRESSURE_KEYS_FITTED)  # fmt: skip
    tyre = base
    jobs = [(kind, Condition(f, v60, pn)) for f in _loads(tyre) for kind in ("braking", "cornering")]
    data = measured_campaign(tyre, jobs, art, n_kappa=nk, n_alpha=na, seed=seed, executor=executor)
    return Programme(name, data, mf_template(tyre), pd.Series(True, index=data.index),
                     "no effect MF 6.1 lacks: 60 km/h, nominal pressure")  # fmt: skip
