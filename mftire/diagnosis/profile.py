"""Profile the MF scaling factors per sweep: which property of the tyre changes, and with what.

A tyre engineer reads a campaign by refitting a few scaling factors sweep by sweep with
everything else held at the global fit, and by looking at how they move:

* pure longitudinal sweeps: LMUX (peak friction), LKX (slip stiffness), LEX (curvature),
  LCX (shape) and an Fx offset;
* pure lateral sweeps: LMUY, LKY, LEY, LCY and an Fy offset

(Pacejka 2012 §4.3.2, Table 4.4; the offsets are ``FX_OFFSET``/``FY_OFFSET`` of
:mod:`mftire.mf.extensions`: a force Fz·c, the shifts' effect).  All sweeps are fitted in
one bounded least-squares problem whose Jacobian is block-diagonal (each sweep has its
own factors), with a weak prior pulling each factor to 1 (offset 0) so that a sweep that
cannot identify a factor (no peak reached) leaves it near neutral.

**Which factor changes.** The spread of a factor across sweeps is compared with the
spread expected from noise: the standard errors of each sweep's factors by a wild bootstrap
of the linearised fit (:data:`N_BOOT` replicates, residual signs flipped at random; never below
the noise-only standard error), giving χ² = Σ((λ_s − λ̄)/se_s)² on
n_sweeps − 1 degrees of freedom.  A factor is *affected* when that spread is significant
(p < 0.001) and large enough to matter (standard deviation of λ ≥ 1 %, offsets ≥ 0.5 %
of the load).

**With what.** The per-sweep values are correlated with the sweep means of the
candidate variables: cross-validated by sweep (leave one sweep out, a straight line and
a per-level mean for categorical variables), with a permutation test over sweeps.

**What is confounded.** A candidate whose sweep means correlate with an MF input
(load, speed, pressure, camber set points) or with the test order (|r| > 0.5) is
reported with the within-block correlation of the factor: blocks are the levels of the
confounder; a significant correlation inside blocks separates the two explanations.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np
import pandas as pd
from scipy import sparse, stats
from scipy.optimize import least_squares

from mftire.fitting.model import Inputs, Model
from mftire.mf.modes import Mode
from mftire.tyre import Tyre

#: Profiled factors per channel and the sweep kind they are fitted on.
FACTORS: dict[str, tuple[str, ...]] = {
    "Fx": ("LMUX", "LKX", "LEX", "LCX", "FX_OFFSET"),
    "Fy": ("LMUY", "LKY", "LEY", "LCY", "FY_OFFSET"),
}
KIND = {"Fx": "pure_longitudinal", "Fy": "pure_lateral"}
#: Family of each factor (names used in reports).
FAMILY = {"LMUX": "friction", "LMUY": "friction", "LKX": "stiffness", "LKY": "stiffness", "LEX": "curvature",
          "LEY": "curvature", "LCX": "shape", "LCY": "shape", "FX_OFFSET": "shift", "FY_OFFSET": "shift"}  # fmt: skip
#: Prior standard deviation of each factor (weak: the data decide where they can).
PRIOR = {"LMU": 0.3, "LK": 0.5, "LE": 1.0, "LC": 0.2, "OFF": 0.05}
#: Smallest spread that matters: standard deviation of λ across sweeps (offsets: × Fz).
MIN_SPREAD = {"LMU": 0.01, "LK": 0.02, "LE": 0.05, "LC": 0.01, "OFF": 0.005}
#: Significance of the spread test.
SPREAD_ALPHA = 1e-3
#: MF inputs offered as the second variable of an interaction, by their set-point column: the variable the
#: law reads (:data:`mftire.mf.extensions.BUILTIN_VARIABLES`).
SECOND_INPUTS = {"Fz_set": "dfz", "gamma_set": "gamma", "Vx_set": "Vx", "P_set": "P"}
#: Confounding threshold on |r| across sweeps.
CONFOUND_R = 0.5
#: Bootstrap replicates of each sweep's factors (their spread expected from noise).
N_BOOT = 200
MODE = Mode.from_code(111)


def _group(name: str) -> str:
    return "OFF" if name.endswith("OFFSET") else name[:3] if name.startswith("LMU") else name[:2]


@dataclass
class FactorProfile:
    """Per-sweep values of one scaling factor."""

    factor: str
    channel: str
    sweeps: np.ndarray  #: sweep ids
    values: np.ndarray  #: λ per sweep (offsets: the factor c of Fz·c)
    se: np.ndarray  #: standard error per sweep (from noise)
    chi2_p: float  #: p-value of the spread being noise
    spread: float  #: standard deviation of the values across sweeps
    affected: bool

    @property
    def family(self) -> str:
        return FAMILY[self.factor]


@dataclass
class VariableLink:
    """How well a candidate's sweep means predict a factor's per-sweep values."""

    variable: str
    factor: str
    score: float  #: 1 − CV MSE / variance [-]
    p_value: float
    r: float  #: Pearson correlation across sweeps
    confounded_with: dict[str, float] = field(default_factory=dict)  #: name -> r across sweeps
    within_block_p: dict[str, float] = field(default_factory=dict)  #: confounder -> p of the within-block test


@dataclass
class Profiles:
    """Result of :func:`profile_factors`."""

    factors: list[FactorProfile]
    links: list[VariableLink]
    sweep_table: pd.DataFrame  #: one row per profiled sweep: id, kind, factor values, candidate means

    @property
    def affected(self) -> list[FactorProfile]:
        return [f for f in self.factors if f.affected]

    def families_for(self, variable: str) -> list[str]:
        """Families of the affected factors that ``variable`` predicts (best first)."""
        out: list[str] = []
        for link in self.links:
            if link.variable == variable and link.p_value <= 0.05 and link.score > 0.2:
                fam = FAMILY[link.factor]
                if fam not in out:
                    out.append(fam)
        return out[:2]

    def second_variable(self, variable: str, candidates: Mapping[str, np.ndarray]) -> str | None:
        """The second variable of an interaction with ``variable``: of the other candidates and the MF
        inputs (:data:`SECOND_INPUTS`: load, camber, speed and pressure by their set points), the one that
        best explains, within the levels of a flag ``variable`` (or along a continuous one, as the product
        of the two centred variables), what ``variable`` alone leaves of the most affected factor it
        predicts (p < 0.01)."""
        links = [lk for lk in self.links if lk.variable == variable and lk.p_value <= 0.05]
        if not links or self.sweep_table.empty or variable not in self.sweep_table.columns:
            return None
        f = links[0]
        channel = next((p.channel for p in self.factors if p.factor == f.factor), None)
        if channel is None:
            return None
        t = self.sweep_table[self.sweep_table["channel"] == channel]
        lam, x = t[f.factor].to_numpy(float), t[variable].to_numpy(float)
        if not np.all(np.isfinite(x)) or np.std(x) == 0:
            return None
        flag = len(np.unique(x)) <= 3
        rest = lam.copy()
        if flag:
            for level in np.unique(x):
                rest[x == level] -= rest[x == level].mean()
        else:  # what a straight line in the variable leaves
            rest = lam - np.polyval(np.polyfit(x, lam, 1), x)
        others = {name: name for name in candidates if name != variable and name in t.columns}
        others.update({sp: name for sp, name in SECOND_INPUTS.items() if sp in t.columns and name != variable})
        best, best_p = None, 0.01
        for col, name in others.items():
            v = t[col].to_numpy(float)
            if not np.all(np.isfinite(v)) or np.std(v) == 0:
                continue
            if flag:
                for level in np.unique(x):
                    m = x == level
                    # np.ptp, not np.std: the std of equal floats can round to a tiny non-zero number, and
                    # scipy then warns of a constant input and returns NaN (no correlation either way)
                    if m.sum() >= 3 and np.ptp(v[m]) > 0 and np.ptp(rest[m]) > 0:
                        pv = float(stats.pearsonr(v[m], rest[m]).pvalue)
                        if pv < best_p:
                            best, best_p = name, pv
            else:
                prod = (x - x.mean()) * (v - v.mean())
                if len(x) >= 6 and np.ptp(prod) > 0 and np.ptp(rest) > 0:
                    pv = float(stats.pearsonr(prod, rest).pvalue)
                    if pv < best_p:
                        best, best_p = name, pv
        return best

    def confounding(self, variable: str) -> list[str]:
        """What ``variable`` is confounded with across sweeps, and what the data support, in words."""
        out = []
        for link in self.links:
            if link.variable != variable:
                continue
            for name, r in link.confounded_with.items():
                p = link.within_block_p.get(name, 1.0)
                if p <= 0.05:
                    verdict = (f"within blocks of constant {name}, {link.factor} still follows {variable} "
                               f"(p = {p:.2g}): the data separate the two, {variable} is supported")
                else:
                    verdict = (f"within blocks of constant {name} the data cannot separate them (p = {p:.2g}): "
                               f"both explanations remain; test {name} levels in an interleaved (randomised) "
                               f"order so that {variable} varies within each level")
                out.append(f"{variable} correlates with {name} across sweeps (r = {r:+.2f}) for {link.factor}; "
                           + verdict)  # fmt: skip
        return list(dict.fromkeys(out))

    def summary(self) -> list[str]:
        out = []
        for f in self.factors:
            flag = "AFFECTED" if f.affected else "steady"
            out.append(f"{f.factor} ({f.family}, {f.channel}): spread {f.spread:.3g} over {len(f.values)} sweeps, "
                       f"p(noise) {f.chi2_p:.2g}: {flag}")  # fmt: skip
        return out


def _fit_channel(tyre: Tyre, df: pd.DataFrame, channel: str, sigma: float, rng: np.random.Generator):
    """Fit the factors of ``channel`` per sweep; returns (sweep ids, values (s, k), se (s, k))."""
    names = FACTORS[channel]
    sweep = df["sweep_id"].to_numpy()
    ids, inv = np.unique(sweep, return_inverse=True)
    ns, k = len(ids), len(names)
    x = Inputs.from_frame(df, tyre.required_variables)
    # the profiled factors act on top of the tyre's own parameters (and extensions)
    base = Model(tyre.flat, x, MODE, tyre.extension_set)
    y = df[channel].to_numpy(float)
    Fz = df["Fz"].to_numpy(float)
    p = dict(tyre.flat)
    prior = np.array([PRIOR[_group(n)] for n in names])
    neutral = np.array([0.0 if n.endswith("OFFSET") else 1.0 for n in names])

    def predict(theta: np.ndarray) -> np.ndarray:
        lam = theta.reshape(ns, k)[inv]
        q = dict(p)
        for j, n in enumerate(names):
            if not n.endswith("OFFSET"):
                q[n] = p[n] * lam[:, j]
        out = getattr(base.channels(q, (channel,)), channel)
        return np.real(out) + Fz * lam[:, k - 1]

    def fun(theta):
        r = (predict(theta) - y) / sigma
        r = np.where(np.isfinite(r), r, 1e3)
        return np.concatenate([r, (theta - np.tile(neutral, ns)) / np.tile(prior, ns)])

    n = len(y)
    rows = np.concatenate([np.repeat(np.arange(n), k), n + np.arange(ns * k)])
    cols = np.concatenate([(inv[:, None] * k + np.arange(k)).ravel(), np.arange(ns * k)])
    sparsity = sparse.coo_matrix((np.ones(len(rows)), (rows, cols)), shape=(n + ns * k, ns * k)).tocsr()
    lo = np.tile([0.3 if not nm.endswith("OFFSET") else -0.3 for nm in names], ns)
    hi = np.tile([3.0 if not nm.endswith("OFFSET") else 0.3 for nm in names], ns)
    lo[np.tile(np.array([nm.startswith("LE") for nm in names]), ns)] = -3.0
    theta0 = np.tile(neutral, ns)
    with np.errstate(all="ignore"):
        res = least_squares(fun, theta0, bounds=(lo, hi), jac_sparsity=sparsity, loss="soft_l1", f_scale=3.0,
                            x_scale=np.tile(prior, ns), max_nfev=60, tr_solver="lsmr")  # fmt: skip
    theta = res.x.reshape(ns, k)
    J = res.jac.tocsr() if sparse.issparse(res.jac) else sparse.csr_matrix(res.jac)
    rdata = res.fun[:n]
    # standard errors by a wild bootstrap of the linearised per-sweep fit (Rademacher signs on the
    # residuals, which keeps their size and any heteroscedasticity; residuals clipped at the loss's
    # scale), never below the noise-only standard error
    se = np.full((ns, k), np.inf)
    P = np.diag(1.0 / prior**2)  # the prior's information
    for s in range(ns):
        m = np.flatnonzero(inv == s)
        Js = J[m][:, np.arange(s * k, (s + 1) * k)].toarray()
        try:
            N = np.linalg.inv(Js.T @ Js + P)
        except np.linalg.LinAlgError:
            continue
        r = np.clip(rdata[m], -3.0, 3.0)
        signs = rng.choice((-1.0, 1.0), size=(N_BOOT, len(m)))
        draws = (signs * r) @ Js @ N  # (N_BOOT, k): θ* − θ̂ of each replicate
        se[s] = np.maximum(draws.std(axis=0), np.sqrt(np.maximum(np.diag(N), 0.0)))
    return ids, theta, se


def _cv_scores(V: np.ndarray, lam: np.ndarray, categorical: bool) -> np.ndarray:
    """Leave-one-sweep-out R² of λ predicted from each row of ``V`` (a line, or per-level means) [-].

    ``V`` is (m, n): the candidate's per-sweep values and permutations of them (one multiset).  Closed form of
    refitting without sweep i: for the line, the deleted residual e_i / (1 − h_ii) of least squares with an
    intercept (h_ii = 1/n + (v_i − v̄)²/Sxx); for the levels, the mean of the other sweeps at v_i's level, or
    of all other sweeps when v_i's level has no other sweep.  0 where v or λ is constant or n < 4."""
    V = np.atleast_2d(np.asarray(V, float))
    lam = np.asarray(lam, float)
    m, n = V.shape
    out = np.zeros(m)
    var = float(np.var(lam))
    if n < 4 or var == 0.0:
        return out
    ok = np.std(V, axis=1) > 0
    total = lam.sum()
    others = (total - lam) / (n - 1)  # the mean of the other sweeps
    if categorical:
        pred = np.empty((m, n))
        for u in np.unique(V):
            at = V == u
            cnt = at.sum(axis=1, keepdims=True)
            s_u = np.where(at, lam, 0.0).sum(axis=1, keepdims=True)
            with np.errstate(invalid="ignore", divide="ignore"):
                mine = (s_u - lam) / (cnt - 1)
            pred = np.where(at, np.where(cnt > 1, mine, others), pred)
    else:
        dv = V - V.mean(axis=1, keepdims=True)
        sxx = np.sum(dv * dv, axis=1, keepdims=True)
        with np.errstate(invalid="ignore", divide="ignore"):
            slope = np.sum(dv * (lam - lam.mean()), axis=1, keepdims=True) / sxx
            e = lam - (lam.mean() + slope * dv)
            h = 1.0 / n + dv * dv / sxx
            pred = np.where(1.0 - h > 1e-12, lam - e / (1.0 - h), others)  # no spread left: the others' mean
    score = 1.0 - np.mean((lam - pred) ** 2, axis=1) / var
    out[ok] = score[ok]
    return out


def _within_block_p(v: np.ndarray, lam: np.ndarray, blocks: np.ndarray) -> float:
    """p-value of the correlation of λ and v after removing block means (partial correlation)."""
    vv, ll = v.astype(float).copy(), lam.astype(float).copy()
    for b in np.unique(blocks):
        m = blocks == b
        vv[m] -= vv[m].mean()
        ll[m] -= ll[m].mean()
    if np.std(vv) == 0 or np.std(ll) == 0 or len(v) < 5:
        return 1.0
    return float(stats.pearsonr(vv, ll).pvalue)


def profile_factors(
    tyre: Tyre,
    df: pd.DataFrame,
    candidates: Mapping[str, np.ndarray],
    channels: Sequence[str],
    noise: Mapping[str, float],
    *,
    n_perm: int = 199,
    seed: int = 0,
) -> Profiles:
    """Profile the scaling factors of ``channels`` (Fx, Fy) per sweep and link them to candidates.

    ``df`` is the grouped sweep table (``sweep_id``, ``kind``, set points); ``candidates``
    maps a name to its values per row; ``noise`` the noise standard deviation per channel.
    """
    rng = np.random.default_rng(seed)
    df = df.reset_index(drop=True)
    factors: list[FactorProfile] = []
    tables = []
    order = {sid: i for i, sid in enumerate(pd.unique(df["sweep_id"]))}
    for ch in channels:
        if ch not in FACTORS:
            continue
        rows = (df["kind"] == KIND[ch]).to_numpy() & np.isfinite(df[ch].to_numpy(float))
        sub = df[rows]
        counts = sub.groupby("sweep_id").size()
        good = counts[counts >= 8].index
        sub = sub[sub["sweep_id"].isin(good)]
        if sub["sweep_id"].nunique() < 4:
            continue
        sigma = max(float(noise.get(ch, 0.0)), 1e-3 * float(np.nanmax(np.abs(sub[ch]))))
        ids, theta, se = _fit_channel(tyre, sub.reset_index(drop=True), ch, sigma, rng)
        fz_mean = sub.groupby("sweep_id")["Fz"].mean().reindex(ids).to_numpy()
        t = pd.DataFrame({"sweep_id": ids, "channel": ch, "order": [order[i] for i in ids]})
        for j, name in enumerate(FACTORS[ch]):
            vals, err = theta[:, j], se[:, j]
            ok = np.isfinite(err) & (err > 0)
            w = 1.0 / err[ok] ** 2
            mean = float(np.sum(w * vals[ok]) / np.sum(w)) if ok.any() else float(np.mean(vals))
            chi2 = float(np.sum(((vals[ok] - mean) / err[ok]) ** 2))
            dof = max(int(ok.sum()) - 1, 1)
            p = float(stats.chi2.sf(chi2, dof))
            spread = float(np.std(vals))
            affected = p < SPREAD_ALPHA and spread >= MIN_SPREAD[_group(name)]
            factors.append(FactorProfile(name, ch, ids, vals, err, p, spread, affected))
            t[name] = vals
        grp = sub.groupby("sweep_id")
        at = sub.index.to_numpy()  # positions in df (RangeIndex)
        for cname, cvals in candidates.items():
            s = pd.Series(np.asarray(cvals, float)[at], index=sub.index)
            t[cname] = s.groupby(sub["sweep_id"]).mean().reindex(ids).to_numpy()
        for sp in ("Fz_set", "Vx_set", "P_set", "gamma_set"):
            if sp in sub.columns:
                t[sp] = grp[sp].first().reindex(ids).to_numpy()
        t["Fz_mean"] = fz_mean
        tables.append(t)
    table = pd.concat(tables, ignore_index=True) if tables else pd.DataFrame()
    links = _link(factors, table, candidates, rng, n_perm)
    return Profiles(factors, links, table)


def _link(factors: list[FactorProfile], table: pd.DataFrame, candidates, rng, n_perm: int) -> list[VariableLink]:
    links: list[VariableLink] = []
    for f in factors:
        if not f.affected:
            continue
        t = table[table["channel"] == f.channel]
        lam = t[f.factor].to_numpy(float)
        confounders = {sp: t[sp].to_numpy(float) for sp in ("Fz_set", "Vx_set", "P_set", "gamma_set")
                       if sp in t.columns and np.std(t[sp]) > 0}  # fmt: skip
        confounders["test order"] = t["order"].to_numpy(float)
        for cname in candidates:
            v = t[cname].to_numpy(float)
            if not np.all(np.isfinite(v)) or np.std(v) == 0:
                continue
            categorical = len(np.unique(v)) <= 3
            score = float(_cv_scores(v, lam, categorical)[0])
            if score <= 0:
                continue
            perms = np.array([rng.permutation(v) for _ in range(n_perm)]).reshape(n_perm, len(v))
            exceed = int(np.sum(_cv_scores(perms, lam, categorical) >= score))
            r = float(np.corrcoef(v, lam)[0, 1])
            link = VariableLink(cname, f.factor, score, (1 + exceed) / (1 + n_perm), r)
            for name, c in confounders.items():
                if name == cname or (name == "Vx_set" and cname == "Vx"):
                    continue
                rc = float(np.corrcoef(v, c)[0, 1])
                if abs(rc) > CONFOUND_R:
                    link.confounded_with[name] = rc
                    blocks = np.round(c, 6) if name != "test order" else np.arange(len(c)) // max(len(c) // 4, 2)
                    link.within_block_p[name] = _within_block_p(v, lam, blocks)
            links.append(link)
    links.sort(key=lambda v: v.score, reverse=True)
    return links


def plot_profiles(result, outdir: str) -> list[str]:
    """``profile_<factor>.png``: each affected factor's per-sweep values against the cause,
    with the fitted law drawn over them (scaled to the factor's mean).  Returns the file names."""
    import os

    from mftire.iotools.atomic import atomic_path
    from mftire.plotting import subplots

    pr = result.profiles
    effect = result.effect
    var = effect.variable if effect is not None else (result.ranking[0].variable if result.ranking else None)
    if pr is None or var is None or pr.sweep_table.empty or var not in pr.sweep_table.columns:
        return []
    term = None
    if effect is not None and result.extended is not None and result.extended.extension_set:
        term = result.extended.extension_set.terms[-1]
    names = []
    for f in pr.affected:
        t = pr.sweep_table[pr.sweep_table["channel"] == f.channel]
        v, lam = t[var].to_numpy(float), t[f.factor].to_numpy(float)
        if not np.all(np.isfinite(v)):
            continue
        fig, ax = subplots(figsize=(6, 4), constrained_layout=True)
        err = np.where(np.isfinite(f.se), f.se, np.nan)
        ax.errorbar(v, lam, yerr=err, fmt="o", ms=4, label="per sweep (± noise s.e.)")
        if term is not None and f.factor in term.targets and term.variable == var:
            grid = np.linspace(np.min(v), np.max(v), 100)
            g2 = np.full_like(grid, np.nan)
            if term.variable2 is not None and term.variable2 in t.columns:
                g2 = np.full_like(grid, float(np.nanmax(t[term.variable2])))
            law = np.asarray(term.factor(grid, g2 if term.variable2 else None), float)
            base = np.asarray(term.factor(v, t[term.variable2].to_numpy(float) if term.variable2 else None), float)
            if f.factor.endswith("OFFSET"):
                shift = float(np.mean(lam) - np.mean(base - 1.0))
                ax.plot(grid, law - 1.0 + shift, "-", label=f"fitted law: {term.form.name}")
            else:
                ax.plot(grid, law * float(np.mean(lam) / np.mean(base)), "-", label=f"fitted law: {term.form.name}")
        from mftire.iotools.units import axis_label

        ax.set_xlabel(axis_label(var))
        ax.set_ylabel(f"{f.factor} per sweep [-]")
        ax.set_title(f"{f.factor} ({f.family}): spread {f.spread:.3g}, p(noise) {f.chi2_p:.1e}")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8)
        name = f"profile_{f.factor}.png"
        with atomic_path(os.path.join(outdir, name)) as tmp:
            fig.savefig(tmp, format="png", dpi=100)
        names.append(name)
    return names
