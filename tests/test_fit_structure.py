"""Standard errors that follow the residual's structure (posture_id/fitting/structure.py):
the cluster-robust covariance against the spread of many fits of a known linear model, the
locked residual's groups against its rows, and a locked fit whose noise is shared by its
channels."""

from __future__ import annotations

import numpy as np
import pytest

from posture_id.dec.parameters import default_parameters
from posture_id.fitting import FitOptions, fit_recording
from posture_id.fitting.evaluators import LockedResidual, SwayResidual
from posture_id.fitting.options import FixedClasses
from posture_id.fitting.structure import cluster_robust_covariance
from posture_id.frf.locked import LockedOptions, LockedProjection
from posture_id.recording import Recording
from posture_id.simulation import prts, simulate
from posture_id.trials import prepare_trial

GROUPS, SIZE, UNKNOWNS = 60, 6, 3


def _design(rng):
    """(G·SIZE, p) a design whose columns vary between groups more than within them (as a
    parameter moves every channel of a harmonic together), and each row's group."""
    per_group = rng.standard_normal((GROUPS, UNKNOWNS))
    x = np.repeat(per_group, SIZE, axis=0) + 0.3 * rng.standard_normal((GROUPS * SIZE,
                                                                          UNKNOWNS))
    return x, np.repeat(np.arange(GROUPS), SIZE)


def _spread(shared: float, prior_sd: float | None = None, trials: int = 3000):
    """The covariance of the errors of many least-squares fits of y = Xβ + e (unit-variance
    noise, a share ``shared`` of it common to each group; with ``prior_sd``, the MAP fits
    of a Gaussian prior about 0, each truth β drawn from it), and the mean of the
    cluster-robust and of the Gauss-Newton covariances they report."""
    rng = np.random.default_rng(3)
    x, clusters = _design(rng)
    prior = (np.zeros((0, UNKNOWNS)) if prior_sd is None
             else np.eye(UNKNOWNS) / prior_sd)
    jac = np.vstack([x, prior])
    inverse = np.linalg.inv(jac.T @ jac)
    errors, robust, white = [], [], []
    for _ in range(trials):
        truth = (np.zeros(UNKNOWNS) if prior_sd is None
                 else prior_sd * rng.standard_normal(UNKNOWNS))
        noise = (np.sqrt(shared) * np.repeat(rng.standard_normal(GROUPS), SIZE)
                 + np.sqrt(1 - shared) * rng.standard_normal(len(x)))
        y = x @ truth + noise
        beta = inverse @ (x.T @ y)  # the prior's rows: (β − 0)/sd
        residual = np.concatenate([x @ beta - y, prior @ beta])
        errors.append(beta - truth)
        robust.append(cluster_robust_covariance(jac, residual, clusters))
        sigma2 = residual @ residual / (len(residual) - UNKNOWNS)
        white.append(sigma2 * inverse)
    return np.cov(np.array(errors).T), np.mean(robust, axis=0), np.mean(white, axis=0)


def test_the_robust_covariance_is_the_spread_of_fits_whose_noise_groups_share():
    actual, robust, white = _spread(shared=0.8)
    ratio = np.diag(robust) / np.diag(actual)
    assert ratio == pytest.approx(np.ones(UNKNOWNS), abs=0.12)
    # the covariance of independent residuals misses most of it
    assert np.all(np.diag(white) < 0.4 * np.diag(actual))


def test_with_independent_noise_it_is_the_gauss_newton_covariance():
    actual, robust, white = _spread(shared=0.0)
    np.testing.assert_allclose(np.diag(robust) / np.diag(actual), 1, atol=0.1)
    np.testing.assert_allclose(np.diag(white) / np.diag(actual), 1, atol=0.1)


def test_a_prior_enters_as_the_fit_adds_it():
    """With the prior's rows (unit-noise data, each truth drawn from the prior) the robust
    covariance is the spread of the MAP estimates' errors, as Gauss-Newton's is."""
    actual, robust, _ = _spread(shared=0.0, prior_sd=0.05)
    np.testing.assert_allclose(np.diag(robust) / np.diag(actual), 1, atol=0.1)


def test_no_robust_covariance_from_one_group_or_too_few_rows():
    rng = np.random.default_rng(0)
    jac, r = rng.standard_normal((6, 3)), rng.standard_normal(6)
    assert cluster_robust_covariance(jac, r, np.zeros(6, int)) is None
    assert cluster_robust_covariance(jac[:3], r[:3], np.arange(3)) is None


def test_the_locked_residual_groups_each_harmonic_of_every_channel():
    stim = prts(states=80, cycles=3)
    rate = 50.0
    t = np.arange(int(round(stim.duration * rate)) + 1) / rate
    rng = np.random.default_rng(4)
    projection = LockedProjection.for_recording(stim.angle(t), rng.standard_normal(
        (len(t), 3)), rate, stim.period_s)
    target = LockedResidual(projection)
    j = 5
    wave = np.zeros((len(t), 3))
    wave[:, 1] = np.cos(2 * np.pi * projection.harmonics[j] * t / stim.period_s)
    rows = np.abs(target.values(wave)) > 1e-9
    clusters = target.clusters()
    assert len(clusters) == len(rows)
    assert set(clusters[rows]) == {j}
    # each group: the real and imaginary part of every channel
    assert np.bincount(clusters).tolist() == [6] * len(projection.harmonics)
    assert SwayResidual().clusters() is None


@pytest.mark.slow("least squares from near the truth, 3 segments")
def test_a_locked_fit_reports_the_larger_of_the_two_standard_errors(tip):
    """Sensor noise shared by the three segments (one camera's jitter): the fit reports,
    for each parameter, the larger of its Gauss-Newton standard error and the
    cluster-robust one of its final residual and Jacobian grouped by harmonic; its
    intervals are ±z times them. Here the shared noise widens the ankle's Kd and delay by
    half (their error is 1.6 and 2.0 Gauss-Newton standard errors)."""
    truth = default_parameters(tip)
    stim = prts(states=80, cycles=3)
    rec = simulate(tip, truth, stim).to_recording()
    rng = np.random.default_rng(5)
    rng.standard_normal(rec.theta.shape)  # the draws of the independent case, skipped
    shared = np.radians(0.05) * np.repeat(rng.standard_normal((len(rec.time), 1)), 3, axis=1)
    noisy = Recording(rec.time, rec.tilt, rec.theta + shared, rec.segments)
    trial = prepare_trial(noisy, stim)
    fit = fit_recording(trial, tip, truth, FitOptions(classes=FixedClasses(),
                                                     locked=LockedOptions()))
    last = fit.stages[-1]
    clusters = LockedResidual(LockedProjection.for_trial(trial, LockedOptions())).clusters()
    robust = np.sqrt(np.diag(cluster_robust_covariance(last.jacobian, last.residual,
                                                       clusters)))
    n = len(tip.joint_names)
    robust = robust[: 4 * n].reshape(4, n).T
    white = fit.white_standard_errors_normalised
    np.testing.assert_allclose(fit.standard_errors_normalised, np.maximum(white, robust),
                               rtol=1e-9)
    assert (fit.standard_errors_normalised / white).max() > 1.4
    half = fit.intervals.upper - fit.normalised[:, :4]
    np.testing.assert_allclose(half, 1.6448536 * fit.standard_errors_normalised, rtol=1e-6)
