"""Lognormal fragility curves fitted to an ensemble of analyses by maximum likelihood.

:func:`fit_lognormal_fragility` fits ``P(failure | IM) = Phi(ln(IM / theta) / beta)`` to failures among runs
at intensity levels (IM in the ensemble's units, m/s2 or g) by the binomial likelihood of Baker (2015,
Earthquake Spectra 31(1) 579-599, eq. 11), with profile-likelihood (default) or Wald intervals, and returns a
:class:`FragilityFit` (median ``theta``, dispersion ``beta``, intervals, or the reason the data identify no
curve; :class:`FragilityError` otherwise). :func:`failure_indicator` turns an ensemble dataset (dims
``record``, ``intensity``, optional ``p_<name>`` and ``sample``) into failures: collapse or a demand over a
limit; :func:`fragility_table` fits one curve per combination of the parameter dims.

Theory: docs/ensembles.md, section "The fragility fit" (under "Report").
"""
from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, field

import numpy as np
import xarray as xr
from scipy import optimize, special, stats

from ..errors import MasonrydamError

G = 9.80665  # standard gravity, m/s2 (as masonrydam.records.readers.G, not imported: that pulls in obspy)

STATUS_COMPLETED = 0
STATUS_COLLAPSE = 1  # failed: mechanism / collapse
STATUS_NUMERICAL = 2  # failed: numerical (non-convergence before the record)
STATUS_ERROR = 3  # not run through: a model error or an exception (excluded, like numerical failures)
STATUS_NOT_RUN = -1  # a member not run (yet): an interrupted ensemble

#: dims that a fragility curve aggregates over (each element along them is one run)
RUN_DIMS = ("record", "sample")
INTENSITY_DIM = "intensity"

_LOG_SQRT_2PI = 0.5 * math.log(2.0 * math.pi)


class FragilityError(MasonrydamError, ValueError):
    """Data a lognormal fragility cannot be fitted to (degenerate or invalid), or a bad option."""


# ------------------------------------------------------------------------------------------------------
# the binomial probit likelihood
# ------------------------------------------------------------------------------------------------------

def _mills(t):
    """phi(t) / Phi(t), computed in logs so that it stays accurate far in the tails."""
    return np.exp(-0.5 * t * t - _LOG_SQRT_2PI - special.log_ndtr(t))


class _Likelihood:
    """Log-likelihood of ``z`` failures in ``n`` runs at log-intensities ``x`` for the linear predictor
    ``eta`` (p = Phi(eta)), with its first two derivatives in ``eta`` (per level)."""

    def __init__(self, x, z, n):
        self.x, self.z, self.n = x, z, n
        self.s = n - z
        self.const = float(np.sum(special.gammaln(n + 1) - special.gammaln(z + 1) - special.gammaln(n - z + 1)))

    def value(self, eta):
        z, s = self.z, self.s
        # 0 * log(0) is 0 here: a level with no failures does not pay for p -> 0
        lp = np.where(z > 0, z * special.log_ndtr(eta), 0.0)
        lq = np.where(s > 0, s * special.log_ndtr(-eta), 0.0)
        return float(np.sum(lp + lq)) + self.const

    def derivatives(self, eta):
        lam_p, lam_q = _mills(eta), _mills(-eta)
        g = self.z * lam_p - self.s * lam_q
        h = -self.z * lam_p * (eta + lam_p) - self.s * lam_q * (lam_q - eta)
        return g, h

    # -- the fit in (a, b): eta = a + b (x - xbar)
    def fit(self, xbar):
        xc = self.x - xbar
        spread = float(np.sqrt(np.average(xc * xc, weights=self.n)))
        theta = np.array([0.0, 1.0 / max(spread, 1e-12)])
        f = self.value(theta[0] + theta[1] * xc)
        for _ in range(200):
            g_eta, h_eta = self.derivatives(theta[0] + theta[1] * xc)
            grad = np.array([g_eta.sum(), (g_eta * xc).sum()])
            hess = np.array([[h_eta.sum(), (h_eta * xc).sum()], [(h_eta * xc).sum(), (h_eta * xc * xc).sum()]])
            try:
                step = -np.linalg.solve(hess, grad)
            except np.linalg.LinAlgError:
                step = grad  # steepest ascent
            if not np.all(np.isfinite(step)):
                step = grad
            t = 1.0
            while True:
                trial = theta + t * step
                f_trial = self.value(trial[0] + trial[1] * xc)
                if np.isfinite(f_trial) and f_trial >= f - 1e-12 * abs(f):
                    break
                t *= 0.5
                if t < 1e-12:
                    break
            converged = np.max(np.abs(t * step)) <= 1e-11 * (1.0 + np.max(np.abs(theta)))
            theta, f = trial, f_trial
            if converged:
                break
        else:
            raise FragilityError("the maximum-likelihood fit did not converge in 200 Newton iterations")
        g_eta, h_eta = self.derivatives(theta[0] + theta[1] * xc)
        hess = np.array([[h_eta.sum(), (h_eta * xc).sum()], [(h_eta * xc).sum(), (h_eta * xc * xc).sum()]])
        return theta, f, hess

    # -- profiles
    def _argmax_1d(self, dfun, start, lower=None):
        """Root of the decreasing derivative ``dfun`` of a concave function, bracketed from ``start``;
        with ``lower``: the maximum over [lower, inf) (``lower`` if the derivative is <= 0 there)."""
        if lower is not None and dfun(lower) <= 0.0:
            return lower
        lo = hi = start
        step = 1.0 + abs(start)
        if dfun(start) > 0.0:
            while dfun(hi) > 0.0:
                lo, hi = hi, hi + step
                step *= 2.0
                if step > 1e12:
                    raise FragilityError("profile likelihood: no maximum found")
        else:
            while dfun(lo) <= 0.0:
                hi, lo = lo, lo - step
                step *= 2.0
                if lower is not None and lo <= lower:
                    lo = lower
                    break
                if step > 1e12:
                    raise FragilityError("profile likelihood: no maximum found")
        return optimize.brentq(dfun, lo, hi, xtol=1e-13, rtol=1e-12, maxiter=200)

    def profile_mu(self, mu, b_start):
        """max over b >= 0 of the log-likelihood with eta = b (x - mu)."""
        d = self.x - mu

        def db(b):
            return float(np.sum(self.derivatives(b * d)[0] * d))

        b = self._argmax_1d(db, b_start, lower=0.0)
        return self.value(b * d), b

    def profile_b(self, b, a_start):
        """max over a of the log-likelihood with eta = a + b x."""
        bx = b * self.x

        def da(a):
            return float(np.sum(self.derivatives(a + bx)[0]))

        a = self._argmax_1d(da, a_start)
        return self.value(a + bx), a


# ------------------------------------------------------------------------------------------------------
# the fit
# ------------------------------------------------------------------------------------------------------

@dataclass
class FragilityFit:
    """A fitted lognormal fragility P(failure | IM) = Phi(ln(IM / median) / dispersion).

    median: theta (the units of the intensities given); dispersion: beta; log_likelihood: the log of
    Baker's eq. 11 at the maximum (binomial coefficients included); level: the confidence level of
    median_ci and dispersion_ci, each ``(low, high)``, from ``ci_method`` (``"profile likelihood"`` or
    ``"wald (observed information on (ln theta, beta))"``); an open side is ``0.0`` or ``inf``.
    se_ln_median, se_dispersion: standard errors from the observed Fisher information.
    n_runs, n_failures, n_levels: the data; im, failed, n: the levels fitted (levels with no runs dropped).

    identifiable: False for degenerate data (with ``on_degenerate="flag"``); then the estimates are None,
    ``reason`` says why, and ``median_bounds`` brackets theta for separated data (beta -> 0).
    """

    median: float | None
    dispersion: float | None
    log_likelihood: float | None
    level: float
    median_ci: tuple[float, float] | None
    dispersion_ci: tuple[float, float] | None
    n_runs: int
    n_failures: int
    n_levels: int
    ci_method: str = "profile likelihood"
    se_ln_median: float | None = None
    se_dispersion: float | None = None
    identifiable: bool = True
    reason: str = ""
    median_bounds: tuple[float, float] | None = None
    im: np.ndarray = field(default=None, repr=False)
    failed: np.ndarray = field(default=None, repr=False)
    n: np.ndarray = field(default=None, repr=False)

    @property
    def median_ci_bounded(self) -> bool:
        return self.median_ci is not None and 0.0 < self.median_ci[0] and math.isfinite(self.median_ci[1])

    @property
    def dispersion_ci_bounded(self) -> bool:
        return self.dispersion_ci is not None and math.isfinite(self.dispersion_ci[1])

    def _require(self):
        if not self.identifiable:
            raise FragilityError(f"the fragility is not identifiable: {self.reason}")

    def probability(self, im):
        """P(failure | im) of the fitted curve (``im`` in the units of the fit)."""
        self._require()
        im = np.asarray(im, dtype=float)
        with np.errstate(divide="ignore"):
            return special.ndtr(np.log(im / self.median) / self.dispersion)

    def quantile(self, p):
        """The intensity at which the fitted probability of failure is ``p``."""
        self._require()
        return self.median * np.exp(self.dispersion * special.ndtri(np.asarray(p, dtype=float)))

    def __str__(self) -> str:
        head = f"{self.n_failures}/{self.n_runs} runs failed at {self.n_levels} intensity levels"
        if not self.identifiable:
            return f"lognormal fragility not identifiable ({head}): {self.reason}"
        pc = f"{100 * self.level:g} %"
        return (f"lognormal fragility: median {self.median:.4g} [{self.median_ci[0]:.4g}, {self.median_ci[1]:.4g}], "
                f"dispersion {self.dispersion:.3g} [{self.dispersion_ci[0]:.3g}, {self.dispersion_ci[1]:.3g}] "
                f"({pc} {self.ci_method}); {head}")


def _as_counts(im, failed, n):
    im = np.asarray(im, dtype=float).ravel()
    failed = np.asarray(failed).ravel()
    if failed.dtype == bool:
        failed = failed.astype(float)
    failed = failed.astype(float)
    n = np.ones_like(im) if n is None else np.asarray(n, dtype=float).ravel()
    if not (im.size == failed.size == n.size):
        raise FragilityError(f"im, failed and n must have the same length, got {im.size}, {failed.size}, {n.size}")
    if im.size == 0:
        raise FragilityError("no data to fit a fragility to")
    for name, v in (("im", im), ("failed", failed), ("n", n)):
        if not np.all(np.isfinite(v)):
            raise FragilityError(f"{name} holds NaN or infinite values")
    if np.any(im <= 0.0):
        raise FragilityError(f"intensities must be positive (a lognormal fragility), got min {im.min():g}")
    if np.any(n < 0) or np.any(failed < 0) or np.any(n != np.round(n)) or np.any(failed != np.round(failed)):
        raise FragilityError("failed and n must be non-negative counts (whole numbers)")
    if np.any(failed > n):
        j = int(np.flatnonzero(failed > n)[0])
        raise FragilityError(f"more failures than runs at intensity {im[j]:g}: {failed[j]:g} > {n[j]:g}")
    keep = n > 0
    im, failed, n = im[keep], failed[keep], n[keep]
    # pool entries at the same intensity (per-record data): the same likelihood up to a constant
    levels, inverse = np.unique(im, return_inverse=True)
    z = np.bincount(inverse, weights=failed, minlength=levels.size)
    m = np.bincount(inverse, weights=n, minlength=levels.size)
    return levels, z, m


def _degeneracy(levels, z, m, units: str):
    """The reason the MLE does not exist (with a bracket of theta for separated data), or None."""
    total, fails = int(m.sum()), int(z.sum())
    u = f" {units}" if units else ""
    if fails == 0:
        return f"no failures in {total} runs: the data only say that the median exceeds {levels.max():g}{u}", None
    if fails == total:
        return f"all {total} runs failed: the data only say that the median is below {levels.min():g}{u}", None
    if levels.size < 2:
        return (f"all runs at one intensity ({levels[0]:g}{u}): the fraction failing "
                f"({fails}/{total}) does not determine both median and dispersion"), None
    with_fail = levels[z > 0]
    with_survival = levels[z < m]
    if with_fail.min() >= with_survival.max():
        lo, hi = with_survival.max(), with_fail.min()
        where = f"at {lo:g}{u}" if lo == hi else f"between {lo:g} and {hi:g}{u}"
        return (f"perfectly separated data: every run fails at and above {hi:g}{u} and survives at and below "
                f"{lo:g}{u}, so the dispersion estimate is 0 and the median lies {where}; add runs at "
                f"intensities in between (or more records)"), (float(lo), float(hi))
    if with_fail.max() <= with_survival.min():
        return (f"failures only at intensities below the survivals ({with_fail.max():g}{u} <= "
                f"{with_survival.min():g}{u}): the failures do not increase with intensity"), None
    return None


def fit_lognormal_fragility(im, failed, n=None, *, level: float = 0.9, ci: str = "profile",
                            on_degenerate: str = "raise", units: str = "") -> FragilityFit:
    """Maximum-likelihood lognormal fragility P(failure | IM) = Phi(ln(IM / theta) / beta).

    im: (k,) intensities (> 0, any units: the median comes back in the same ones); failed: (k,) the
    failures at each (counts, or 0/1 or bools for per-run data); n: (k,) the runs at each (default: one
    each). Entries at the same intensity are pooled; entries with n = 0 are dropped.
    level: the confidence level of the intervals (default 90 %); ci: ``"profile"`` (profile likelihood,
    chi-square with 1 degree of freedom; default) or ``"wald"`` (observed Fisher information on
    (ln theta, beta)). on_degenerate: ``"raise"`` (a :class:`FragilityError`) or ``"flag"`` (a result with
    ``identifiable=False`` and the reason) for data without a finite MLE. units: named in messages.
    """
    if not 0.0 < level < 1.0:
        raise FragilityError(f"level must lie in (0, 1), got {level!r}")
    if ci not in ("profile", "wald"):
        raise FragilityError(f"ci must be 'profile' or 'wald', got {ci!r}")
    if on_degenerate not in ("raise", "flag"):
        raise FragilityError(f"on_degenerate must be 'raise' or 'flag', got {on_degenerate!r}")
    levels, z, m = _as_counts(im, failed, n)
    common = dict(level=float(level), n_runs=int(m.sum()), n_failures=int(z.sum()), n_levels=int(levels.size),
                  im=levels, failed=z, n=m)
    degenerate = _degeneracy(levels, z, m, units)
    if degenerate is None:
        like = _Likelihood(np.log(levels), z, m)
        xbar = float(np.average(like.x, weights=m))
        (a, b), lmax, hess = like.fit(xbar)
        if not (b > 0.0 and np.isfinite(lmax)):
            degenerate = ("the fitted slope is not positive: the failures do not increase with intensity, "
                          "which a lognormal fragility cannot describe"), None
    if degenerate is not None:
        reason, bounds = degenerate
        if on_degenerate == "raise":
            raise FragilityError(f"cannot fit a lognormal fragility: {reason}")
        return FragilityFit(median=None, dispersion=None, log_likelihood=None, median_ci=None, dispersion_ci=None,
                            ci_method="", identifiable=False, reason=reason, median_bounds=bounds, **common)

    mu = xbar - a / b
    beta = 1.0 / b
    # observed information on (a, b) -> covariance on (mu = ln theta, beta) by the delta method
    try:
        cov_ab = np.linalg.inv(-hess)
        jac = np.array([[-1.0 / b, a / b**2], [0.0, -1.0 / b**2]])
        cov = jac @ cov_ab @ jac.T
        se_mu, se_beta = (float(np.sqrt(v)) if v > 0 else math.inf for v in np.diag(cov))
    except np.linalg.LinAlgError:
        se_mu = se_beta = math.inf

    if ci == "wald":
        zq = float(special.ndtri(0.5 + 0.5 * level))
        median_ci = (math.exp(mu - zq * se_mu), math.exp(mu + zq * se_mu))
        dispersion_ci = (max(beta - zq * se_beta, 0.0), beta + zq * se_beta)
        method = "wald (observed information on (ln theta, beta))"
    else:
        crit = 0.5 * float(stats.chi2.ppf(level, 1))
        target = lmax - crit
        mu_lo, mu_hi = _profile_interval(lambda t: like.profile_mu(t, b)[0], mu, target, max(se_mu, 1e-3))
        # beta through ln b; beta = exp(-ln b): the upper end of ln b is the lower end of beta
        lnb = math.log(b)
        lnb_lo, lnb_hi = _profile_interval(lambda t: like.profile_b(math.exp(t), -math.exp(t) * mu)[0], lnb, target,
                                           max(se_beta / beta, 1e-3))
        median_ci = (math.exp(mu_lo) if math.isfinite(mu_lo) else 0.0,
                     math.exp(mu_hi) if math.isfinite(mu_hi) else math.inf)
        dispersion_ci = (math.exp(-lnb_hi), math.exp(-lnb_lo) if math.isfinite(lnb_lo) else math.inf)
        method = "profile likelihood"
    return FragilityFit(median=math.exp(mu), dispersion=beta, log_likelihood=lmax, median_ci=median_ci,
                        dispersion_ci=dispersion_ci, ci_method=method, se_ln_median=se_mu, se_dispersion=se_beta,
                        **common)


def _profile_interval(profile, center, target, scale, reach=60.0):
    """The interval around ``center`` where ``profile(t) >= target`` (the profile is unimodal, with its
    maximum at center); a side that stays above the target within ``reach`` is open (-inf / inf)."""
    ends = []
    for sign in (-1.0, 1.0):
        step = scale
        inner = center
        bound = None
        while step <= 2.0 * reach:
            outer = center + sign * min(step, reach)
            if profile(outer) < target:
                bound = optimize.brentq(lambda t: profile(t) - target, *sorted((inner, outer)), xtol=1e-10,
                                        rtol=1e-10, maxiter=200)
                break
            if step >= reach:
                break
            inner = outer
            step *= 2.0
        ends.append(bound if bound is not None else sign * math.inf)
    return ends[0], ends[1]


# ------------------------------------------------------------------------------------------------------
# ensemble datasets
# ------------------------------------------------------------------------------------------------------

def as_dataset(ds):
    """An xarray Dataset, or the path of one (netCDF), opened."""
    if isinstance(ds, xr.Dataset):
        return ds
    try:
        return xr.load_dataset(ds)
    except (OSError, ValueError, TypeError) as exc:
        raise FragilityError(f"cannot read the ensemble dataset {ds!r}: {exc}") from exc


def parameter_dims(ds) -> list[str]:
    """The dims a fragility is fitted per combination of: every dim of ``status`` other than ``record``,
    ``intensity`` and ``sample`` (the ``p_<name>`` parameter dims)."""
    var = ds["status"] if "status" in ds else ds
    return [str(d) for d in var.dims if d not in RUN_DIMS and d != INTENSITY_DIM]


def run_dims(ds) -> list[str]:
    """The dims aggregated in one fragility: ``record`` and, if there, ``sample``."""
    var = ds["status"] if "status" in ds else ds
    return [d for d in RUN_DIMS if d in var.dims]


def check_ensemble_dataset(ds):
    """FragilityError unless ``ds`` is an ensemble dataset: a ``status`` on ``record`` and ``intensity``
    holding only the member status codes."""
    if "status" not in ds:
        raise FragilityError("the ensemble dataset has no 'status' variable (0 completed, 1 collapse, 2 numerical)")
    dims = ds["status"].dims
    for d in ("record", INTENSITY_DIM):
        if d not in dims:
            raise FragilityError(f"the ensemble dataset's 'status' has no '{d}' dim (dims: {list(dims)})")
    st = ds["status"].values
    bad = ~np.isin(st, (STATUS_COMPLETED, STATUS_COLLAPSE, STATUS_NUMERICAL, STATUS_ERROR, STATUS_NOT_RUN))
    if bad.any():
        raise FragilityError(f"status values must be 0, 1, 2, 3 or -1 (not run), found "
                             f"{sorted(set(np.unique(st[bad]).tolist()))}")


def demand_variables(ds) -> list[str]:
    """The data variables that can serve as demands: numeric, on the dims of ``status``, other than
    ``status`` and ``wall_time``."""
    out = []
    for name, var in ds.data_vars.items():
        if name in ("status", "status_reason", "wall_time") or var.dtype.kind not in "fiu":
            continue
        if "status" in ds and set(var.dims) - set(ds["status"].dims):
            continue
        out.append(str(name))
    return out


def failure_indicator(ds, demand: str | None = None, limit: float | None = None):
    """``(failed, usable)``: two boolean DataArrays on the dims of ``status``.

    Without ``demand``: failed = collapse (``status == 1``: mechanism or collapse). With a ``demand``
    variable and a ``limit`` (in the demand's units): failed = ``demand > limit`` (a limit state is
    exceeded) or collapse (a collapsed run exceeds every limit, whatever demand it recorded).
    usable is False for numerical failures (``status == 2``), members not run (``status == -1``, an
    interrupted ensemble) and completed runs whose demand is NaN: those are left out of the fits (and
    counted by :func:`fragility_table`); failed is False there.
    """
    ds = as_dataset(ds)
    check_ensemble_dataset(ds)
    status = ds["status"]
    collapsed = status == STATUS_COLLAPSE
    usable = (status == STATUS_COMPLETED) | collapsed
    if (demand is None) != (limit is None):
        raise FragilityError("give both a demand variable and its limit (a limit state), or neither (collapse)")
    if demand is None:
        failed = collapsed
    else:
        if demand not in ds.data_vars:
            raise FragilityError(f"demand '{demand}' is not a variable of the ensemble dataset "
                                 f"(demands: {', '.join(demand_variables(ds)) or 'none'})")
        limit = float(limit)
        if not math.isfinite(limit):
            raise FragilityError(f"the limit of '{demand}' must be a finite number, got {limit!r}")
        d = ds[demand]
        extra = set(d.dims) - set(status.dims)
        if extra:
            raise FragilityError(f"demand '{demand}' has dims {sorted(extra)} that status has not: "
                                 f"select one value first (ds.sel(...))")
        d = d.broadcast_like(status)
        exceeds = d > limit
        usable = usable & (collapsed | d.notnull())
        failed = collapsed | exceeds
    failed = (failed & usable).transpose(*status.dims)
    usable = usable.transpose(*status.dims)
    failed.name, usable.name = "failed", "usable"
    return failed, usable


def failure_definition(ds=None, demand: str | None = None, limit: float | None = None) -> str:
    """The definition of failure in words (for titles and tables)."""
    if demand is None:
        return "failure = collapse (status 1: mechanism/collapse)"
    units = ""
    if ds is not None and demand in ds:
        units = str(ds[demand].attrs.get("units", ""))
    units = "" if units in ("", "1") else f" {units}"
    return f"failure = {demand} > {limit:g}{units} or collapse"


@dataclass
class FragilityRow:
    """One row of :func:`fragility_table`: the parameter values, the fit and the counts.

    params: ``{dim: value}`` of the parameter combination ({} without parameter dims); fit: the
    :class:`FragilityFit` (``identifiable`` False for degenerate data); n_excluded: runs left out, of
    which n_numerical numerical failures, n_not_run members not run, and the rest completed runs with a
    NaN demand; im, failed, n: the counts per intensity (usable runs only).
    """

    params: dict
    fit: FragilityFit
    n_runs: int
    n_failures: int
    n_excluded: int
    n_numerical: int = 0
    n_not_run: int = 0
    units: str = ""
    im: np.ndarray = field(default=None, repr=False)
    failed: np.ndarray = field(default=None, repr=False)
    n: np.ndarray = field(default=None, repr=False)

    @property
    def excluded_text(self) -> str:
        """What the excluded runs were, in words ("" if none)."""
        nan = self.n_excluded - self.n_numerical - self.n_not_run
        parts = [(self.n_numerical, "numerical failure"), (self.n_not_run, "not run"), (nan, "NaN demand")]
        return ", ".join(f"{k} {what}" for k, what in parts if k)

    @property
    def note(self) -> str:
        f = self.fit
        notes = [f"excluded: {self.excluded_text}"] if self.n_excluded else []
        if not f.identifiable:
            return "; ".join([f"not identifiable: {f.reason}"] + notes)
        if not f.median_ci_bounded:
            notes.append("median interval open: the data do not bound it")
        if not f.dispersion_ci_bounded:
            notes.append("dispersion interval open above")
        return "; ".join(notes)

    def as_dict(self) -> dict:
        """A flat dict (parameter dims first), for text and CSV tables; intensities in the dataset's units
        and in g. Fields of a fit that is not identifiable are None."""
        f = self.fit
        out = {k: _plain(v) for k, v in self.params.items()}
        ok = f.identifiable
        unit = self.units or "im"
        out[f"median [{unit}]"] = f.median if ok else None
        out[f"median_low [{unit}]"] = f.median_ci[0] if ok else None
        out[f"median_high [{unit}]"] = f.median_ci[1] if ok else None
        if self.units == "m/s2":
            out["median [g]"] = f.median / G if ok else None
            out["median_low [g]"] = f.median_ci[0] / G if ok else None
            out["median_high [g]"] = f.median_ci[1] / G if ok else None
        out["dispersion"] = f.dispersion if ok else None
        out["dispersion_low"] = f.dispersion_ci[0] if ok else None
        out["dispersion_high"] = f.dispersion_ci[1] if ok else None
        out["level"] = f.level
        out["runs"] = self.n_runs
        out["failures"] = self.n_failures
        out["excluded"] = self.n_excluded
        out["note"] = self.note
        return out


def _plain(v):
    v = v.item() if hasattr(v, "item") else v
    return v


def parameter_combinations(ds) -> list[dict]:
    """``[{dim: value}, ...]``: every combination of the parameter dims' values (``[{}]`` without any)."""
    dims = parameter_dims(ds)
    values = [ds[d].values if d in ds.coords else np.arange(ds.sizes[d]) for d in dims]
    return [dict(zip(dims, combo)) for combo in itertools.product(*values)]


def at_parameters(da, params: dict):
    """``da`` at one parameter combination (by position, so that float values need no tolerance)."""
    where = {}
    for d, v in params.items():
        values = da[d].values if d in da.coords else np.arange(da.sizes[d])
        where[d] = int(np.flatnonzero(values == v)[0])
    return da.isel(where)


def counts_per_intensity(failed, usable, params: dict | None = None):
    """``(im, z, n, excluded)`` for one parameter combination: the intensities (in the dataset's order),
    the failures and the usable runs at each (summed over record and sample), and the runs left out."""
    params = params or {}
    f = at_parameters(failed, params)
    u = at_parameters(usable, params)
    agg = [d for d in f.dims if d != INTENSITY_DIM]
    z = f.sum(dim=agg).transpose(INTENSITY_DIM).values.astype(float)
    n = u.sum(dim=agg).transpose(INTENSITY_DIM).values.astype(float)
    total = int(np.prod([u.sizes[d] for d in u.dims]))
    im = np.asarray(f[INTENSITY_DIM].values, dtype=float)
    return im, z, n, int(total - n.sum())


def intensity_units(ds) -> str:
    return str(ds[INTENSITY_DIM].attrs.get("units", "")) if INTENSITY_DIM in ds.coords else ""


def fragility_table(ds, demand: str | None = None, limit: float | None = None, level: float = 0.9,
                    ci: str = "profile") -> list[FragilityRow]:
    """One lognormal fragility per combination of the parameter dims (one curve per friction value, say),
    each fitted to the failures of :func:`failure_indicator` pooled over the records (and samples) at
    every intensity; numerical failures, members not run and NaN demands are excluded and counted. A combination whose data have no
    finite MLE gets a row whose fit is flagged not identifiable (with the reason), not an error.
    Returns :class:`FragilityRow` objects (``row.as_dict()`` for a flat table)."""
    ds = as_dataset(ds)
    failed, usable = failure_indicator(ds, demand, limit)
    units = intensity_units(ds)
    rows = []
    for params in parameter_combinations(ds):
        im, z, n, excluded = counts_per_intensity(failed, usable, params)
        st = at_parameters(ds["status"], params).values
        n_numerical = int(((st == STATUS_NUMERICAL) | (st == STATUS_ERROR)).sum())
        n_not_run = int((st == STATUS_NOT_RUN).sum())
        keep = n > 0
        if not keep.any():
            fit = FragilityFit(median=None, dispersion=None, log_likelihood=None, level=float(level), median_ci=None,
                               dispersion_ci=None, n_runs=0, n_failures=0, n_levels=0, ci_method="",
                               identifiable=False, reason="no usable runs (numerical failures, not run, NaN demands)")
        else:
            try:
                fit = fit_lognormal_fragility(im[keep], z[keep], n[keep], level=level, ci=ci, on_degenerate="flag",
                                              units=units)
            except FragilityError as exc:  # a fit that does not converge: this row flagged, the report goes on
                fit = FragilityFit(median=None, dispersion=None, log_likelihood=None, level=float(level),
                                   median_ci=None, dispersion_ci=None, n_runs=int(n[keep].sum()),
                                   n_failures=int(z[keep].sum()), n_levels=int(keep.sum()), ci_method="",
                                   identifiable=False, reason=str(exc))
        rows.append(FragilityRow(params=params, fit=fit, n_runs=int(n.sum()), n_failures=int(z.sum()),
                                 n_excluded=excluded, n_numerical=n_numerical, n_not_run=n_not_run, units=units,
                                 im=im, failed=z, n=n))
    return rows
