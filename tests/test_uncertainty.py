"""Honest error bars: conformal quantiles, coverage, class calibration, noise estimate,
identifiability, and intervals that are never narrower than the fit's noise allows."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.stats import norm

from posture_id.dec.parameters import default_parameters
from posture_id.errors import PostureIdError
from posture_id.fitting.result import FitResult, noise_allows
from posture_id.studies.calibration import least_squares_check
from posture_id.uncertainty import (
    ConformalCalibration,
    Determination,
    Normaliser,
    conformal_quantile,
    coverage,
    coverage_interval,
    determination,
    expected_calibration_error,
    fit_temperature,
    prior_interval,
    sensor_noise_deg,
)
from posture_id.uncertainty.intervals import ParameterIntervals


def test_gaussian_intervals_with_the_known_variance_cover_their_level():
    # y ~ N(mu, sigma^2) with sigma known: mu ± z·sigma must hold y at the nominal rate,
    # within the exact binomial interval of the sample size
    rng = np.random.default_rng(1)
    n = 20000
    mu = rng.normal(size=(n, 3, 4))
    sigma = rng.uniform(0.1, 2.0, size=(n, 3, 4))
    y = mu + sigma * rng.standard_normal((n, 3, 4))
    for level in (0.5, 0.8, 0.9, 0.95):
        z = norm.ppf((1 + level) / 2)
        share = coverage(y, mu - z * sigma, mu + z * sigma)
        assert share.shape == (3, 4)
        for c in share.ravel():
            low, high = coverage_interval(c, n, confidence=0.999)
            assert low <= level <= high, (level, c)
    # and far from it when the variance is taken too small
    too_narrow = coverage(y, mu - 0.5 * 1.645 * sigma, mu + 0.5 * 1.645 * sigma)
    assert np.all(np.abs(too_narrow - (2 * norm.cdf(0.8224) - 1)) < 0.02)


def test_the_conformal_quantile_is_the_right_order_statistic():
    scores = np.arange(1.0, 11.0)[:, None]  # n = 10
    assert conformal_quantile(scores, 0.5)[0] == 6.0  # ⌈11·0.5⌉ = 6th smallest
    assert conformal_quantile(scores, 0.9)[0] == 10.0  # ⌈9.9⌉ = 10
    assert math.isinf(conformal_quantile(scores, 0.95)[0])  # ⌈10.45⌉ = 11 > n
    with pytest.raises(ValueError):
        conformal_quantile(scores, 1.0)


def test_conformal_intervals_on_gaussian_scores_have_their_exact_coverage():
    # for exchangeable scores the coverage averaged over calibration sets is
    # ⌈(n+1)·level⌉/(n+1), whatever the distribution: check it on |N(0,1)|, where the
    # quantile must also approach z
    rng = np.random.default_rng(2)
    n, reps, level = 19, 20000, 0.9
    calibration = np.abs(rng.standard_normal((reps, n)))
    fresh = np.abs(rng.standard_normal(reps))
    q = np.array([conformal_quantile(c[:, None], level)[0] for c in calibration])
    exact = math.ceil((n + 1) * level) / (n + 1)
    assert abs(np.mean(fresh <= q) - exact) < 0.006
    big = np.abs(rng.standard_normal((200000, 1)))
    assert conformal_quantile(big, level)[0] == pytest.approx(norm.ppf(0.95), abs=0.01)


def test_clopper_pearson_interval_matches_its_closed_form():
    low, high = coverage_interval(0.0, 10)
    assert low == 0.0
    assert high == pytest.approx(1 - 0.025 ** (1 / 10), rel=1e-9)


def test_expected_calibration_error_known_answers():
    rng = np.random.default_rng(3)
    # every probability 0.8, the outcome half the time: ECE = |0.8 − 0.5| exactly
    outcome = np.arange(1000) % 2 == 0
    assert expected_calibration_error(np.full(1000, 0.8), outcome) == pytest.approx(0.3)
    # outcomes drawn with the stated probabilities: ECE only sampling scatter
    p = rng.uniform(size=200000)
    y = rng.uniform(size=p.size) < p
    assert expected_calibration_error(p, y) < 0.005
    # overconfident probabilities: clearly miscalibrated
    sharp = 1 / (1 + np.exp(-4 * np.log(p / (1 - p))))
    assert expected_calibration_error(sharp, y) > 0.05


def test_temperature_scaling_undoes_a_known_overconfidence():
    rng = np.random.default_rng(4)
    logits = rng.normal(0, 3, size=100000)
    outcome = rng.uniform(size=logits.size) < 1 / (1 + np.exp(-logits))
    assert fit_temperature(2.5 * logits, outcome) == pytest.approx(2.5, rel=0.03)
    assert fit_temperature(logits, outcome) == pytest.approx(1.0, rel=0.03)


def test_sensor_noise_is_estimated_from_the_sway_itself():
    rng = np.random.default_rng(5)
    t = np.arange(6051) / 50.0
    sway = np.radians(np.column_stack([
        0.8 * np.sin(2 * np.pi * 0.11 * t) + 0.3 * np.sin(2 * np.pi * 1.3 * t + k)
        + 0.002 * np.cumsum(np.cumsum(rng.standard_normal(t.size))) / 50 for k in range(3)]))
    assert sensor_noise_deg(sway) < 0.002
    for sd in (0.01, 0.05, 0.2):
        noisy = sway + np.radians(sd) * rng.standard_normal(sway.shape)
        assert sensor_noise_deg(noisy) == pytest.approx(sd, rel=0.05)
    batch = sensor_noise_deg(np.stack([sway, sway + np.radians(0.05) * rng.standard_normal(
        sway.shape)]))
    assert batch.shape == (2,) and batch[0] < batch[1]


def test_the_prior_interval_is_that_of_the_sampled_parameters():
    rng = np.random.default_rng(6)
    draws = np.abs(1 + 0.5 * rng.standard_normal(400000)) - 1
    low, high = prior_interval(0.9)
    assert low == pytest.approx(np.quantile(draws, 0.05), abs=0.005)
    assert high == pytest.approx(np.quantile(draws, 0.95), abs=0.01)
    width = high - low
    ratio, words = determination(np.array([0.1, 0.5, 0.9]) * width, 0.9)
    assert ratio == pytest.approx([0.1, 0.5, 0.9])
    assert list(words) == [Determination.WELL, Determination.PARTLY, Determination.NOT]


def _calibration(scales_by_noise, noise=(0.0, 0.05), modules=3) -> ConformalCalibration:
    scores = np.stack([s * np.ones((40, modules, 4)) for s in scales_by_noise])
    return ConformalCalibration.from_scores(Normaliser.ABSOLUTE, scores, np.array(noise),
                                            np.array(noise))


def test_calibration_interpolates_between_noise_levels_and_round_trips():
    cal = _calibration([0.1, 0.3])
    assert cal.scale(0.9, 0.0) == pytest.approx(0.1)
    # geometric between levels: a scale 1000× smaller at 0° stays small just above 0°
    assert cal.scale(0.9, 0.025) == pytest.approx(np.sqrt(0.1 * 0.3))
    steep = _calibration([1e-3, 1.0])
    assert steep.scale(0.9, 0.0005) == pytest.approx(1e-3 * 1000 ** 0.01)
    assert cal.scale(0.9, 0.5) == pytest.approx(0.3)  # held beyond the noisiest level
    assert cal.beyond(0.5) and not cal.beyond(0.05)
    back = ConformalCalibration.from_dict(cal.to_dict(), "test")
    assert np.array_equal(back.scales, cal.scales) and back.normaliser is cal.normaliser
    with pytest.raises(PostureIdError, match="outside the calibrated"):
        cal.scale(0.995, 0.0)
    with pytest.raises(PostureIdError, match="not a conformal calibration"):
        ConformalCalibration.from_dict({"scales": []}, "calibration.json")


def _fit_result(body, se: np.ndarray, noise_deg: float, residual_sd: float) -> FitResult:
    rng = np.random.default_rng(7)
    n = body.n_segments
    recorded = np.radians(noise_deg) * rng.standard_normal((6051, n))
    normalised = np.zeros((n, 5))
    normalised[:, 4] = 1
    return FitResult(
        parameters=default_parameters(body), normalised=normalised,
        standard_errors=se, standard_errors_normalised=se,
        poorly_determined=np.zeros((n, 4), bool), converged=True, iterations=1,
        evaluations=1, wall_time_s=0.0, cost=0.0, rms_deg=noise_deg, stages=(),
        backend="", notices=(), time=np.arange(6051) / 50, recorded=recorded,
        fitted=recorded, segments=body.segment_names, joints=body.joint_names,
        residual_sd=residual_sd, noise_floor_deg=0.001, defaults=default_parameters(body))


def test_an_interval_is_never_narrower_than_the_fits_noise_allows(tip):
    se = np.full((3, 4), 0.02)
    z = norm.ppf(0.95)
    noisy = _fit_result(tip, se, 0.05, residual_sd=0.05)
    gauss = noisy.intervals_at(0.9)
    np.testing.assert_array_equal(noisy.intervals.upper, gauss.upper)  # 90 % by default
    assert gauss.upper - gauss.lower == pytest.approx(np.full((3, 4), 2 * z * 0.02))
    # a calibration whose scales are below z (the fits looked better than their noise)
    # cannot narrow the interval below the Gauss-Newton one of the residual noise ...
    floored = noisy.intervals_at(0.9, _calibration([0.5, 0.5]))
    assert floored.upper - floored.lower == pytest.approx(gauss.upper - gauss.lower)
    # ... while one that says the errors are larger widens it
    widened = noisy.intervals_at(0.9, _calibration([3.0, 3.0]))
    assert widened.upper - widened.lower == pytest.approx(np.full((3, 4), 2 * 3.0 * 0.02))
    # a noise-free fit: its standard errors assumed the 0.001° floor, 100× its residual
    # noise; calibration may narrow them to what the fits showed, but never below z times
    # the residual noise's own standard errors
    exact = _fit_result(tip, se, 0.0, residual_sd=1e-5)
    assert np.allclose(exact.intervals_at(0.9, _calibration([0.5, 0.5])).upper, 0.5 * 0.02)
    least = exact.intervals_at(0.9, _calibration([1e-4, 1e-4]))
    assert np.allclose(least.upper, z * 1e-5 / 1e-3 * 0.02)
    assert noise_allows(0.9, 0.05, 0.001) == pytest.approx(z)
    assert noise_allows(0.9, 1e-5, 0.001) == pytest.approx(z * 0.01)


def test_intervals_are_cut_at_zero_and_say_what_is_not_determined(tip):
    estimate = np.zeros((3, 4))
    half = np.full((3, 4), 0.05)
    half[1, 1] = 5.0  # the knee's Ki: far wider than the prior
    half[2, 3] = 0.5
    defaults = np.column_stack([default_parameters(tip).array(f)
                                for f in ("kp", "ki", "kd", "delay_s")])
    iv = ParameterIntervals.around(estimate, half, defaults, 0.9, "test", 0.05,
                                   tip.joint_names)
    assert iv.lower[1, 1] == -1.0 and iv.lower_si[1, 1] == 0.0
    sentences = iv.sentences()
    assert "the knee's Ki is not determined by this recording" in sentences
    assert "the hip's delay is partly determined by this recording" in sentences
    assert not any("ankle" in s for s in sentences)
    assert iv.to_dict()["modules"]["knee"]["ki"]["determination"] == "not determined"


def _rows(n, noise, se_scale, rng):
    """Synthetic least-squares rows: errors N(0, SE²·se_scale²), SEs as reported."""
    rows = []
    for i in range(n):
        truth = np.abs(1 + 0.5 * rng.normal(size=(3, 5))) - 1
        truth[:, 4] = 1
        se = rng.uniform(0.01, 0.1, size=(3, 4))
        estimate = truth.copy()
        estimate[:, :4] += se_scale * se * rng.standard_normal((3, 4))
        rows.append({"split": "test", "position": i, "noise_deg": noise,
                     "truth": truth.tolist(), "estimate": estimate.tolist(),
                     "standard_errors": se.tolist(), "noise_estimate_deg": noise,
                     "rms_deg": noise})
    return rows


@pytest.mark.slow("coverage of 6000 synthetic fits")
def test_least_squares_coverage_known_answers():
    rng = np.random.default_rng(8)
    # standard errors right: both readings cover about 90 %
    rows = _rows(3000, 0.05, 1.0, rng)
    right, _ = least_squares_check(rows, (0.05,))
    for key in ("gauss_newton", "calibrated"):
        cov = getattr(right[0.05], key)[0.9].coverage
        assert np.all(np.abs(cov - 0.9) < 0.025), (key, cov)
    # standard errors half the truth: Gauss-Newton covers P(|N(0,1)| ≤ 0.82) ≈ 59 %, the
    # calibrated intervals still 90 %
    rows = _rows(3000, 0.05, 2.0, rng)
    wrong, cal = least_squares_check(rows, (0.05,))
    gauss = wrong[0.05].gauss_newton[0.9].coverage
    calibrated = wrong[0.05].calibrated[0.9].coverage
    assert np.all(np.abs(gauss - (2 * norm.cdf(norm.ppf(0.95) / 2) - 1)) < 0.03)
    assert np.all(np.abs(calibrated - 0.9) < 0.025)
    assert cal.scale(0.9, 0.05) == pytest.approx(np.full((3, 4), 2 * norm.ppf(0.95)),
                                                 rel=0.08)
    # too few fits for cross-validated coverage: said, not faked
    assert least_squares_check(_rows(5, 0.05, 1.0, rng), (0.05,)) == ({}, None)


def test_the_folded_normal_quantiles_are_scipys():
    """The prior's interval is computed without scipy.stats (start-up); it is
    scipy.stats.foldnorm's to rounding."""
    from scipy.stats import foldnorm

    from posture_id.uncertainty.identifiability import folded_normal_quantile

    for sigma in (0.2, 0.5, 1.0):
        for q in (0.001, 0.05, 0.25, 0.5, 0.9, 0.999):
            expected = foldnorm(1.0 / sigma, scale=sigma).ppf(q)
            assert folded_normal_quantile(q, 1.0, sigma) == pytest.approx(expected, rel=1e-12)


def test_the_ece_of_calibrated_probabilities_is_its_sampling_floor():
    """``calibrated_ece``: the ECE that perfectly calibrated probabilities read on so many
    samples. Outcomes drawn from the probabilities sit inside its spread; outcomes of a
    network sure of itself and wrong 10 % of the time at P 0.99 sit far above it."""
    from posture_id.uncertainty.coverage import calibrated_ece, expected_calibration_error

    rng = np.random.default_rng(7)
    p = np.clip(rng.beta(0.3, 0.3, 400), 0.001, 0.999)
    floor = calibrated_ece(p, draws=500, seed=1)
    assert 0 < floor.mean() < 0.06
    honest = expected_calibration_error(p, rng.random(len(p)) < p)
    assert np.mean(floor >= honest) > 0.01
    sure = np.full(400, 0.99)
    wrong = rng.random(400) < 0.9
    assert expected_calibration_error(sure, wrong) > calibrated_ece(sure, draws=500).max()


def test_a_calibrated_scale_multiplies_gauss_newton_s_errors_floored_by_the_structure(tip):
    """A locked fit whose reported standard errors are wider than Gauss-Newton's (the
    residual's structure, posture_id/fitting/structure.py): the calibrated scale, made of
    Gauss-Newton standard errors, multiplies those; the interval is never narrower than z
    times the reported ones; without a calibration it is ±z times the reported ones."""
    from dataclasses import replace

    white = np.full((3, 4), 0.02)
    reported = white.copy()
    reported[0, 0] = 0.05  # the ankle's Kp widened by the structure
    fit = replace(_fit_result(tip, reported, 0.05, residual_sd=0.05),
                  white_standard_errors_normalised=white)
    z = norm.ppf(0.95)
    plain = fit.intervals_at(0.9)
    np.testing.assert_allclose(plain.upper, z * reported)
    assert "widened by the residual's structure" in plain.method
    calibrated = fit.intervals_at(0.9, _calibration([2.0, 2.0]))
    expected = np.maximum(2.0 * white, z * reported)
    np.testing.assert_allclose(calibrated.upper, expected)
    assert calibrated.upper[0, 0] == pytest.approx(z * 0.05)
    assert calibrated.upper[1, 0] == pytest.approx(2.0 * 0.02)
    assert "no narrower than the residual's structure allows" in calibrated.method
