"""Lognormal fragility fits (Baker 2015, eq. 11), IDA and fragility figures of an ensemble dataset
(masonrydam.ensemble.fragility and masonrydam.ensemble.report)."""
from __future__ import annotations

import csv
import math

import numpy as np
import pytest
import xarray as xr
from scipy import optimize, special, stats

from masonrydam.errors import MasonrydamError
from masonrydam.ensemble.fragility import (G, FragilityError, failure_indicator, fit_lognormal_fragility,
                                           fragility_table)
from masonrydam.ensemble.report import ensemble_report, fragility_figure, ida_figure, write_table_csv

THETA, BETA = 0.4, 0.35  # g
LEVELS = np.linspace(0.1, 0.8, 8)  # g
RUNS = 20


def _synthetic(seed):
    p = special.ndtr(np.log(LEVELS / THETA) / BETA)
    return np.random.default_rng(seed).binomial(RUNS, p)


def _loglik(im, z, n, mu, beta):
    eta = (np.log(im) - mu) / beta
    return float(np.sum(z * special.log_ndtr(eta) + (n - z) * special.log_ndtr(-eta)))


# ------------------------------------------------------------------------------------------------------
# the fit
# ------------------------------------------------------------------------------------------------------

def test_fit_recovers_synthetic_parameters_within_its_interval():
    z = _synthetic(2024)
    fit = fit_lognormal_fragility(LEVELS, z, np.full(8, RUNS))
    assert fit.identifiable and fit.level == 0.9 and fit.ci_method == "profile likelihood"
    assert fit.n_runs == 8 * RUNS and fit.n_failures == z.sum() and fit.n_levels == 8
    assert fit.median_ci[0] <= THETA <= fit.median_ci[1]
    assert fit.dispersion_ci[0] <= BETA <= fit.dispersion_ci[1]
    assert fit.median_ci[0] < fit.median < fit.median_ci[1]
    assert fit.dispersion_ci[0] < fit.dispersion < fit.dispersion_ci[1]
    # the units follow the intensities: the same data in m/s2 give the median in m/s2, the same beta
    si = fit_lognormal_fragility(LEVELS * G, z, np.full(8, RUNS))
    assert si.median == pytest.approx(fit.median * G, rel=1e-8)
    assert si.dispersion == pytest.approx(fit.dispersion, rel=1e-8)
    assert si.median_ci[1] == pytest.approx(fit.median_ci[1] * G, rel=1e-6)


def test_fit_is_the_maximum_and_its_intervals_are_the_profile_likelihood_ones():
    z, n = _synthetic(7), np.full(8, RUNS)
    fit = fit_lognormal_fragility(LEVELS, z, n)
    mu, beta = math.log(fit.median), fit.dispersion
    ref = optimize.minimize(lambda t: -_loglik(LEVELS, z, n, t[0], math.exp(t[1])), [math.log(0.3), math.log(0.5)],
                            method="Nelder-Mead", options=dict(xatol=1e-10, fatol=1e-12, maxiter=5000))
    assert math.exp(ref.x[0]) == pytest.approx(fit.median, rel=1e-6)
    assert math.exp(ref.x[1]) == pytest.approx(beta, rel=1e-6)
    const = np.sum(special.gammaln(n + 1) - special.gammaln(z + 1) - special.gammaln(n - z + 1))
    assert fit.log_likelihood == pytest.approx(_loglik(LEVELS, z, n, mu, beta) + const, rel=1e-12)
    half = 0.5 * stats.chi2.ppf(0.9, 1)
    lmax = _loglik(LEVELS, z, n, mu, beta)
    for m in fit.median_ci:  # profile over beta at the interval's ends: lmax - chi2/2
        prof = -optimize.minimize_scalar(lambda lb: -_loglik(LEVELS, z, n, math.log(m), math.exp(lb)),
                                         bounds=(-6, 3), method="bounded", options=dict(xatol=1e-11)).fun
        assert lmax - prof == pytest.approx(half, abs=1e-6)
    for b in fit.dispersion_ci:  # profile over the median
        prof = -optimize.minimize_scalar(lambda t: -_loglik(LEVELS, z, n, t, b), bounds=(-6, 3), method="bounded",
                                         options=dict(xatol=1e-11)).fun
        assert lmax - prof == pytest.approx(half, abs=1e-6)
    # a wider level gives a wider interval; the Wald interval is close to the profile one here
    wide = fit_lognormal_fragility(LEVELS, z, n, level=0.99)
    assert wide.median_ci[0] < fit.median_ci[0] and wide.median_ci[1] > fit.median_ci[1]
    wald = fit_lognormal_fragility(LEVELS, z, n, ci="wald")
    assert wald.median == fit.median and wald.ci_method.startswith("wald")
    assert wald.median_ci == pytest.approx(fit.median_ci, rel=0.05)


@pytest.mark.slow
def test_interval_coverage_over_seeded_synthetic_datasets():
    covered_median = covered_beta = 0
    for seed in range(200):
        fit = fit_lognormal_fragility(LEVELS, _synthetic(seed), np.full(8, RUNS))  # none is degenerate
        covered_median += fit.median_ci[0] <= THETA <= fit.median_ci[1]
        covered_beta += fit.dispersion_ci[0] <= BETA <= fit.dispersion_ci[1]
    assert 160 <= covered_median <= 194  # 80-97 % of 200 for a nominal 90 %
    assert 160 <= covered_beta <= 194


def test_symmetric_data_put_the_median_where_half_fail():
    x0, step = 0.3, 0.25
    im = x0 * np.exp(step * np.arange(-2, 3))  # symmetric in ln IM about x0 ...
    z = np.array([2, 5, 10, 15, 18])  # ... and the failures antisymmetric: z(-k) = n - z(k)
    fit = fit_lognormal_fragility(im, z, np.full(5, 20))
    assert fit.median == pytest.approx(x0, rel=1e-9)
    # its interval is symmetric in ln IM as well
    assert math.log(fit.median_ci[1] / x0) == pytest.approx(math.log(x0 / fit.median_ci[0]), rel=1e-6)


def test_two_levels_are_fitted_exactly():
    # two levels: the curve passes through both observed fractions (a saturated model)
    im, z, n = np.array([0.2, 0.5]), np.array([3, 15]), np.array([20, 20])
    q = special.ndtri(z / n)
    beta = math.log(im[1] / im[0]) / (q[1] - q[0])
    fit = fit_lognormal_fragility(im, z, n)
    assert fit.dispersion == pytest.approx(beta, rel=1e-8)
    assert fit.median == pytest.approx(im[0] * math.exp(-beta * q[0]), rel=1e-8)
    assert fit.probability(im) == pytest.approx(z / n, rel=1e-8)
    assert fit.quantile(0.5) == pytest.approx(fit.median)


def test_per_run_data_give_the_grouped_fit():
    z, n = _synthetic(11), np.full(8, RUNS)
    grouped = fit_lognormal_fragility(LEVELS, z, n)
    im = np.repeat(LEVELS, RUNS)
    flags = np.concatenate([np.arange(RUNS) < k for k in z])  # booleans, one run each
    per_run = fit_lognormal_fragility(im, flags)
    assert per_run.n_runs == 8 * RUNS and per_run.n_failures == z.sum()
    assert per_run.median == pytest.approx(grouped.median, rel=1e-9)
    assert per_run.dispersion == pytest.approx(grouped.dispersion, rel=1e-9)
    assert per_run.median_ci == pytest.approx(grouped.median_ci, rel=1e-7)


@pytest.mark.parametrize("im, z, n, words", [
    ([0.1, 0.2, 0.3], [0, 0, 0], [5, 5, 5], "no failures"),
    ([0.1, 0.2, 0.3], [5, 5, 5], [5, 5, 5], "all 15 runs failed"),
    ([0.1, 0.2, 0.3], [0, 0, 5], [5, 5, 5], "perfectly separated"),
    ([0.1, 0.2, 0.3], [0, 2, 5], [5, 5, 5], "perfectly separated"),  # quasi-separated: beta -> 0 at 0.2
    ([0.2, 0.2], [1, 2], [5, 5], "one intensity"),
    ([0.1, 0.2, 0.3], [5, 0, 0], [5, 5, 5], "do not increase"),
    ([0.1, 0.2, 0.3], [4, 1, 1], [5, 5, 5], "not positive"),  # overlapping, but falling with intensity
])
def test_degenerate_data_raise_or_are_flagged(im, z, n, words):
    with pytest.raises(FragilityError, match=words) as info:
        fit_lognormal_fragility(im, z, n)
    assert isinstance(info.value, MasonrydamError)
    flagged = fit_lognormal_fragility(im, z, n, on_degenerate="flag")
    assert not flagged.identifiable and words in flagged.reason
    assert flagged.median is None and flagged.dispersion is None and flagged.median_ci is None
    assert flagged.n_runs == sum(n) and flagged.n_failures == sum(z)
    assert "not identifiable" in str(flagged)
    with pytest.raises(FragilityError, match="not identifiable"):
        flagged.probability(0.2)


def test_separated_data_bracket_the_median():
    flagged = fit_lognormal_fragility([0.1, 0.2, 0.3, 0.4], [0, 0, 5, 5], [5, 5, 5, 5], on_degenerate="flag")
    assert flagged.median_bounds == (0.2, 0.3)


def test_weak_trend_leaves_the_intervals_open_not_nan():
    fit = fit_lognormal_fragility([0.1, 0.2, 0.3], [1, 1, 2], [5, 5, 5])
    assert fit.identifiable and np.isfinite(fit.median) and np.isfinite(fit.dispersion)
    assert fit.median_ci[1] == math.inf and not fit.median_ci_bounded
    assert fit.dispersion_ci[1] == math.inf and 0 < fit.dispersion_ci[0] < fit.dispersion


@pytest.mark.parametrize("args, words", [
    (([0.1, 0.2], [3, 1], [2, 2]), "more failures than runs"),
    (([0.0, 0.2], [0, 1], [2, 2]), "positive"),
    (([0.1, np.nan], [0, 1], [2, 2]), "NaN"),
    (([0.1, 0.2], [0.5, 1], [2, 2]), "whole numbers"),
    (([0.1, 0.2, 0.3], [0, 1], None), "same length"),
])
def test_invalid_input_is_an_error(args, words):
    with pytest.raises(FragilityError, match=words):
        fit_lognormal_fragility(*args)


# ------------------------------------------------------------------------------------------------------
# an ensemble dataset built by hand
# ------------------------------------------------------------------------------------------------------

RECORDS = ["rec_a", "rec_b", "rec_c"]
IM_G = np.array([0.1, 0.2, 0.3, 0.4])
FRICTION = np.array([0.6, 0.8])
# status[record, intensity, friction]
STATUS = np.zeros((3, 4, 2), dtype=np.int8)
STATUS[0, 3, 0] = 1  # rec_a collapses at 0.4 g with friction 0.6
STATUS[1, 2, 0] = 1  # rec_b collapses at 0.3 g with friction 0.6 ...
STATUS[1, 3, 0] = 0  # ... and stands at 0.4 g (structural resurrection: its IDA curve ends at 0.3 g)
STATUS[2, 1, 1] = 2  # rec_c fails numerically at 0.2 g with friction 0.8
STATUS[0, 3, 1] = 1  # rec_a collapses at 0.4 g with friction 0.8
LIMIT = 0.004


def _ensemble():
    im = IM_G * G
    scale = np.array([1.0, 2.2, 0.5])[:, None, None] / FRICTION[None, None, :]
    drift = 0.006 * scale * (IM_G[None, :, None] / 0.4) ** 1.5
    drift = np.where(STATUS == 1, 0.05, drift)  # what a collapsed run recorded: exceeds any limit anyway
    drift = np.where(STATUS == 2, np.nan, drift)
    reason = np.where(STATUS == 2, "no convergence after 8 step cuts", np.where(STATUS == 1, "mechanism", ""))
    dims = ("record", "intensity", "p_friction")
    ds = xr.Dataset(
        {"peak_drift": (dims, drift, {"units": "1", "long_name": "peak interstorey drift"}),
         "peak_displacement": (dims, drift * 3.0, {"units": "m", "long_name": "peak crest displacement"}),
         "status": (dims, STATUS, {"units": "1", "long_name": "0 completed, 1 collapse, 2 numerical"}),
         "status_reason": (dims, reason.astype(str), {"units": "1", "long_name": "reason of a failure"}),
         "wall_time": (dims, np.full(STATUS.shape, 2.5), {"units": "s", "long_name": "wall time"})},
        coords={"record": ("record", RECORDS),
                "intensity": ("intensity", im, {"measure": "pga", "units": "m/s2", "long_name": "PGA"}),
                "p_friction": ("p_friction", FRICTION, {"scene_key": "joints.bed.friction_coefficient"})})
    return ds


def _expected_counts(fail, usable):
    # per friction: failures and usable runs at each intensity, summed over the records
    return (fail & usable).sum(axis=0), usable.sum(axis=0)


def test_failure_indicator_collapse_and_limit_state():
    ds = _ensemble()
    failed, usable = failure_indicator(ds)
    assert failed.dims == ds["status"].dims
    np.testing.assert_array_equal(failed.values, STATUS == 1)
    np.testing.assert_array_equal(usable.values, STATUS != 2)
    failed, usable = failure_indicator(ds, "peak_drift", LIMIT)
    drift = ds["peak_drift"].values
    with np.errstate(invalid="ignore"):
        expected = ((drift > LIMIT) | (STATUS == 1)) & (STATUS != 2)
    np.testing.assert_array_equal(failed.values, expected)
    assert not failed.values[STATUS == 2].any()
    with pytest.raises(FragilityError, match="both"):
        failure_indicator(ds, "peak_drift")
    with pytest.raises(FragilityError, match="peak_drift"):  # the error lists the demands there are
        failure_indicator(ds, "peak_drif", 0.01)


def test_fragility_table_fits_one_curve_per_parameter_value():
    ds = _ensemble()
    rows = fragility_table(ds, "peak_drift", LIMIT)
    assert [r.params["p_friction"] for r in rows] == [0.6, 0.8]
    drift = ds["peak_drift"].values
    with np.errstate(invalid="ignore"):
        fail = (drift > LIMIT) | (STATUS == 1)
    usable = STATUS != 2
    for k, row in enumerate(rows):
        z, n = _expected_counts(fail[..., k], usable[..., k])
        np.testing.assert_array_equal(row.failed, z)
        np.testing.assert_array_equal(row.n, n)
        assert row.n_runs == n.sum() and row.n_failures == z.sum()
        assert row.n_excluded == (~usable[..., k]).sum()
        ref = fit_lognormal_fragility(IM_G * G, z, n, on_degenerate="flag")
        assert row.fit.identifiable == ref.identifiable
        if ref.identifiable:
            assert row.fit.median == pytest.approx(ref.median) and row.fit.median_ci == pytest.approx(ref.median_ci)
            d = row.as_dict()
            assert d["p_friction"] == FRICTION[k] and d["median [m/s2]"] == pytest.approx(ref.median)
            assert d["median [g]"] == pytest.approx(ref.median / G)
            assert d["dispersion_low"] == pytest.approx(ref.dispersion_ci[0])
            assert (d["runs"], d["failures"], d["excluded"]) == (n.sum(), z.sum(), (~usable[..., k]).sum())
    assert rows[1].n_excluded == 1 and rows[0].n_excluded == 0
    # collapse only: friction 0.6 has failures at 0.3 and 0.4 g and survivals there (a fit), friction 0.8
    # one collapse at the top level only (separated: flagged, not an error)
    rows = fragility_table(ds)
    assert rows[0].fit.identifiable and rows[0].n_failures == 2
    assert not rows[1].fit.identifiable and "separated" in rows[1].fit.reason
    assert rows[1].as_dict()["median [m/s2]"] is None and "not identifiable" in rows[1].as_dict()["note"]


def test_ida_figure_draws_one_curve_per_record_and_parameter():
    ds = _ensemble()
    fig = ida_figure(ds, "peak_drift")
    ax = fig.axes[0]
    curves = {line.get_gid(): line for line in ax.get_lines() if (line.get_gid() or "").startswith("ida:")}
    assert len(curves) == 3 * 2
    for i, rec in enumerate(RECORDS):
        for k, mu in enumerate(FRICTION):
            line = curves[f"ida:record={rec};p_friction={mu:g}"]
            s = STATUS[i, :, k]
            stop = int(np.flatnonzero(s == 1)[0]) if (s == 1).any() else 4
            keep = s[:stop] == 0
            np.testing.assert_allclose(line.get_xdata(), ds["peak_drift"].values[i, :stop, k][keep])
            np.testing.assert_allclose(line.get_ydata(), IM_G[:stop][keep])  # in g
    collapses = [line for line in ax.get_lines() if (line.get_gid() or "").startswith("collapse:")]
    assert len(collapses) == 3  # rec_a and rec_b at 0.6, rec_a at 0.8
    right = ax.get_xlim()[1]
    stood = max(np.max(line.get_xdata()) for line in curves.values())
    for line in collapses:  # a cross at the right edge, beyond every point that stood
        assert stood < line.get_xdata()[-1] <= right and line.get_marker() == "x"
    b = {line.get_gid(): line for line in collapses}["collapse:record=rec_b;p_friction=0.6"]
    assert b.get_ydata()[-1] == pytest.approx(0.3)  # at the intensity that brought it down
    numerical = [line for line in ax.get_lines() if (line.get_gid() or "").startswith("numerical:")]
    assert numerical == []  # its demand is NaN: nothing to mark
    medians = [line for line in ax.get_lines() if (line.get_gid() or "").startswith("median:")]
    assert len(medians) == 2
    m08 = {line.get_gid(): line for line in medians}["median:p_friction=0.8"]
    d = ds["peak_drift"].sel(p_friction=0.8).values
    np.testing.assert_allclose(m08.get_xdata()[:3], [np.median(d[:, 0]), np.median(d[[0, 1], 1]), np.median(d[:, 2])])
    assert "[g]" in ax.get_ylabel() and "9.80665" in ax.get_ylabel() and "[-]" in ax.get_xlabel()
    fig.canvas.draw()  # renders with Agg


def test_fragility_figure_markers_are_the_empirical_fractions():
    ds = _ensemble()
    fig = fragility_figure(ds, "peak_drift", LIMIT)
    ax = fig.axes[0]
    drift = ds["peak_drift"].values
    with np.errstate(invalid="ignore"):
        fail = (drift > LIMIT) | (STATUS == 1)
    usable = STATUS != 2
    lines = {line.get_gid(): line for line in ax.get_lines() if line.get_gid()}
    for k, mu in enumerate(FRICTION):
        z, n = _expected_counts(fail[..., k], usable[..., k])
        marks = lines[f"fraction:p_friction={mu:g}"]
        np.testing.assert_allclose(marks.get_xdata(), IM_G)
        np.testing.assert_allclose(marks.get_ydata(), z / n)
    texts = [t.get_text() for t in ax.texts]
    assert "1/2" in texts  # the level with the numerical failure: 2 usable runs
    assert "peak_drift > 0.004" in ax.get_title() and "excluded" in ax.get_title()
    fits = [g for g in lines if g.startswith("fit:")]
    row = fragility_table(ds, "peak_drift", LIMIT)
    assert len(fits) == sum(r.fit.identifiable for r in row)
    for r in row:
        if r.fit.identifiable:
            fit_line = lines[f"fit:p_friction={r.params['p_friction']:g}"]
            x = np.asarray(fit_line.get_xdata())
            np.testing.assert_allclose(fit_line.get_ydata(), r.fit.probability(x * G))
            median = lines[f"median:p_friction={r.params['p_friction']:g}"]
            assert median.get_xdata()[0] == pytest.approx(r.fit.median / G)
    collapse_fig = fragility_figure(ds)
    assert "collapse" in collapse_fig.axes[0].get_title()
    fig.canvas.draw()


@pytest.mark.slow
def test_ensemble_report_from_a_netcdf_file(tmp_path):
    path = tmp_path / "ensemble.nc"
    _ensemble().to_netcdf(path)
    lines, figures = ensemble_report(path, "peak_drift", LIMIT)
    text = "\n".join(lines)
    assert set(figures) == {"fragility", "ida"}
    assert "3 records x 4 intensities x 2 values of joints.bed.friction_coefficient" in text
    assert "1 failed numerically" in text and "no convergence after 8 step cuts" in text
    assert "failure = peak_drift > 0.004 or collapse" in text
    header = next(i for i, line in enumerate(lines) if "dispersion_low" in line)
    assert len(lines) >= header + 3  # a header and a row per friction value
    rows = fragility_table(_ensemble(), "peak_drift", LIMIT)
    out = write_table_csv(rows, tmp_path / "table.csv")
    with open(out, newline="") as fh:
        read = list(csv.DictReader(fh))
    assert [float(r["p_friction"]) for r in read] == [0.6, 0.8]
    for r, row in zip(read, rows):
        assert int(r["runs"]) == row.n_runs and int(r["excluded"]) == row.n_excluded
        if row.fit.identifiable:
            assert float(r["median [m/s2]"]) == row.fit.median
        else:
            assert r["median [m/s2]"] == ""
    for fig in figures.values():
        fig.savefig(tmp_path / "f.png")


def test_samples_are_pooled_with_the_records():
    rng = np.random.default_rng(5)
    n_rec, n_im, n_smp = 4, 6, 3
    im = np.linspace(0.05, 0.6, n_im) * G
    capacity = np.exp(rng.normal(np.log(0.3 * G), 0.4, (n_rec, n_smp)))
    status = (im[None, :, None] > capacity[:, None, :]).astype(np.int8)
    status[0, 2, 1] = 2
    drift = 0.002 * im[None, :, None] / capacity[:, None, :]
    dims = ("record", "intensity", "sample")
    ds = xr.Dataset({"peak_drift": (dims, drift, {"units": "1", "long_name": "drift"}), "status": (dims, status)},
                    coords={"record": [f"r{i}" for i in range(n_rec)], "sample": np.arange(n_smp),
                            "intensity": ("intensity", im, {"measure": "sa", "period": 0.3, "damping": 0.05,
                                                            "units": "m/s2"})})
    rows = fragility_table(ds)
    assert len(rows) == 1 and rows[0].params == {}
    assert rows[0].n_runs == n_rec * n_im * n_smp - 1 and rows[0].n_excluded == 1
    usable = status != 2
    ref = fit_lognormal_fragility(im, ((status == 1) & usable).sum(axis=(0, 2)), usable.sum(axis=(0, 2)))
    assert rows[0].fit.median == pytest.approx(ref.median)
    ax = ida_figure(ds).axes[0]  # peak_drift by default
    gids = [line.get_gid() for line in ax.get_lines() if (line.get_gid() or "").startswith("ida:")]
    assert sorted(gids) == sorted(f"ida:record=r{r};sample={s}" for r in range(n_rec) for s in range(n_smp))
    assert ax.get_ylabel().startswith("Sa(T = 0.3 s, 5 % damping) [g]")
    numerical = [line for line in ax.get_lines() if (line.get_gid() or "").startswith("numerical:")]
    assert len(numerical) == 1 and numerical[0].get_xdata()[0] == drift[0, 2, 1]


def test_members_not_run_are_excluded_and_counted():
    ds = _ensemble()
    status = ds["status"].values.copy()
    status[2, 0, 0] = -1  # an interrupted ensemble: rec_c at 0.1 g with friction 0.6 not run
    ds["status"] = (ds["status"].dims, status)
    failed, usable = failure_indicator(ds)
    assert not usable.values[2, 0, 0] and not failed.values[2, 0, 0]
    rows = fragility_table(ds, "peak_drift", LIMIT)
    assert (rows[0].n_excluded, rows[0].n_not_run, rows[0].n_numerical) == (1, 1, 0)
    assert (rows[1].n_excluded, rows[1].n_not_run, rows[1].n_numerical) == (1, 0, 1)
    assert rows[0].n[0] == 2 and "1 not run" in rows[0].note
    lines, _ = ensemble_report(ds, "peak_drift", LIMIT)
    assert any("1 not run (status -1, excluded)" in line for line in lines)
    ds["status"] = (ds["status"].dims, np.where(status == 2, 3, status).astype(np.int8))  # an error: excluded too
    rows3 = fragility_table(ds, "peak_drift", LIMIT)
    assert (rows3[1].n_excluded, rows3[1].n_numerical) == (1, 1)
    ds["status"] = (ds["status"].dims, np.where(status == 2, 7, status).astype(np.int8))
    with pytest.raises(FragilityError, match="status values"):
        fragility_table(ds)
