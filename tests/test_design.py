"""Experiment design: the information of harmonics against closed forms and Monte Carlo,
unbounded widths for what a protocol does not see, and the prediction on a real body."""

from __future__ import annotations

import json

import numpy as np
import pytest

from posture_id.design.information import covariance, harmonic_information


def _first_order(omega: np.ndarray, a: float, b: float, c: float, omega_c: float):
    """Harmonics Y(ω) = b/(a + iω)·U + c·[ω > ω_c]·U of a unit input, and their
    derivatives with respect to (a, b, c): a linear system whose parameter c acts only
    above ω_c."""
    s = a + 1j * omega
    high = (omega > omega_c).astype(float)
    y = b / s + c * high
    jac = np.stack([-b / s**2, 1 / s, high], axis=-1)  # (K, 3)
    return y, jac


def test_a_gain_alone_has_the_closed_form_variance():
    # y_k = b·u_k + e_k, e_k circular with E|e|² = σ²: var(b̂) = σ² / (2 Σ|u_k|²)
    rng = np.random.default_rng(0)
    u = rng.standard_normal(20) + 1j * rng.standard_normal(20)
    sigma2 = 0.3
    info = harmonic_information(u[:, None, None], np.full((20, 1, 1), sigma2))
    expected = sigma2 / (2 * np.sum(np.abs(u) ** 2))
    assert info.fit_covariance()[0, 0] == pytest.approx(expected, rel=1e-12)
    assert info.bound()[0, 0] == pytest.approx(expected, rel=1e-12)


def test_the_sandwich_is_the_weighted_fit_s_covariance_under_correlated_noise():
    """Monte Carlo: weight each channel by its own variance (as the locked fit does) when
    the noise is correlated between channels; the estimates' covariance is A⁻¹BA⁻¹,
    larger than the Cramér–Rao bound F⁻¹."""
    rng = np.random.default_rng(1)
    k, m, p = 30, 2, 3
    jac = rng.standard_normal((k, m, p)) + 1j * rng.standard_normal((k, m, p))
    root = np.array([[1.0, 0.0], [0.8, 0.6]])  # correlation 0.8 between the channels
    scales = np.exp(rng.uniform(-1, 1, (k, 1)))
    cov = np.einsum("ij,kj->ki", root, root)[None] * np.ones((k, 1, 1))
    cov = cov * scales[:, :, None] ** 2
    info = harmonic_information(jac, cov.astype(complex))
    # the weighted least-squares estimate of many noise draws
    jr = np.concatenate([jac.real, jac.imag], axis=1).reshape(-1, p)
    weights = np.concatenate([np.einsum("kii->ki", cov)] * 2, axis=1).reshape(-1) / 2
    draws = 20000
    e = (rng.standard_normal((draws, k, m)) + 1j * rng.standard_normal((draws, k, m))) / np.sqrt(2)
    e = np.einsum("ij,dkj->dki", root, e) * scales[None]
    z = np.concatenate([e.real, e.imag], axis=2).reshape(draws, -1)
    w = 1 / weights
    est = np.linalg.solve(jr.T @ (w[:, None] * jr), (jr.T * w) @ z.T).T
    empirical = np.cov(est.T)
    np.testing.assert_allclose(np.diag(empirical), np.diag(info.fit_covariance()), rtol=0.05)
    assert np.all(np.diag(info.fit_covariance()) > np.diag(info.bound()) * 1.05)


def test_a_parameter_the_protocol_does_not_excite_is_unbounded():
    omega_c = 2 * np.pi * 1.0
    low = 2 * np.pi * np.arange(1, 20) / 20.0  # a protocol up to 0.95 Hz
    wide = 2 * np.pi * np.arange(1, 60) / 20.0  # one up to 2.95 Hz
    for omega, blind in ((low, True), (wide, False)):
        _, jac = _first_order(omega, 2.0, 3.0, 0.5, omega_c)
        noise = np.full((len(omega), 1, 1), 0.01 + 0j)
        cov = harmonic_information(jac[:, None, :], noise).fit_covariance()
        sd = np.sqrt(np.diag(cov))
        assert np.all(np.isfinite(sd[:2]))
        assert np.isinf(sd[2]) == blind
    # two parameters acting alike are unbounded together, the others not
    jac = np.random.default_rng(2).standard_normal((10, 1, 3)) + 0j
    jac[:, :, 2] = 2 * jac[:, :, 1]
    sd = np.sqrt(np.diag(covariance(harmonic_information(jac, np.ones((10, 1, 1)) + 0j)
                                    .weighted)))
    assert np.isfinite(sd[0]) and np.isinf(sd[1]) and np.isinf(sd[2])


def test_the_prior_width_is_the_prior_s_own():
    from posture_id.dec.prior import relative_factors
    from posture_id.design.predict import prior_width

    x = relative_factors(np.random.default_rng(3), 400000) - 1
    lo, hi = np.percentile(x, [5, 95])
    assert prior_width(0.9) == pytest.approx(hi - lo, rel=0.01)



def test_the_bounded_fit_s_error_is_the_censored_normal_s():
    """One parameter, SE 0.5, true value 0.3 within bounds (−1, 0.8): the bounded fit's
    estimate is the unbounded one clipped, whose RMS error has a closed form."""
    from scipy.stats import norm

    from posture_id.design.bounded import bounded_errors
    from posture_id.design.information import Information

    a = np.array([[4.0]])
    errors = bounded_errors(Information(a, a, a), np.array([0.3]), np.array([-1.0]),
                            np.array([0.8]), 100000, np.random.default_rng(5))
    lo, hi = (-1.0 - 0.3) / 0.5, (0.8 - 0.3) / 0.5
    inner = norm.cdf(hi) - norm.cdf(lo) - (hi * norm.pdf(hi) - lo * norm.pdf(lo))
    expected = 0.5 * np.sqrt(inner + lo**2 * norm.cdf(lo) + hi**2 * norm.sf(hi))
    assert np.sqrt(np.mean(errors**2)) == pytest.approx(expected, rel=0.01)
    assert errors.min() >= -1.3 - 1e-9 and errors.max() <= 0.5 + 1e-9


def test_far_bounds_leave_the_sandwich_and_near_ones_cap_a_correlated_partner():
    """With bounds far away the bounded errors have the weighted fit's covariance
    A⁻¹BA⁻¹; when one of two strongly correlated parameters is poorly determined, its
    bounds cap its error and, through the correlation, its partner's."""
    from posture_id.design.bounded import bounded_errors
    from posture_id.design.information import Information

    rng = np.random.default_rng(6)
    jac = rng.standard_normal((40, 1, 2)) + 1j * rng.standard_normal((40, 1, 2))
    noise = np.full((40, 1, 1), 0.02 + 0j)
    info = harmonic_information(jac, noise)
    far = bounded_errors(info, np.zeros(2), np.full(2, -1e6), np.full(2, 1e6), 40000, rng)
    np.testing.assert_allclose(np.cov(far.T), info.fit_covariance(), rtol=0.05, atol=1e-12)
    # a nearly collinear pair: both marginal SEs large, the box [−1, 1] caps both
    jac[:, :, 1] = jac[:, :, 0] + 0.01 * (rng.standard_normal((40, 1)) + 0j)
    info = harmonic_information(jac, noise)
    se = np.sqrt(np.diag(info.fit_covariance()))
    assert np.all(se > 1.0)
    capped = bounded_errors(info, np.zeros(2), -np.ones(2), np.ones(2), 4000, rng)
    rms = np.sqrt(np.mean(capped**2, axis=0))
    assert np.all(rms < 1.0) and np.all(rms < 0.6 * se)
    assert np.all(np.abs(capped) <= 1.0 + 1e-9)
    # a parameter with no information of its own: unbounded, as its width is
    blind = Information(np.diag([4.0, 0.0]), np.diag([4.0, 0.0]), np.diag([4.0, 0.0]))
    out = bounded_errors(blind, np.zeros(2), -np.ones(2), np.ones(2), 10, rng)
    assert np.all(np.isfinite(out[:, 0])) and np.all(np.isinf(out[:, 1]))

@pytest.mark.slow("design predictions on the exact model, 1 segment")
def test_predictions_on_a_real_body_scale_with_cycles_and_repetitions(winter1):
    """On the exact model of a 1-segment body with sensor noise only, the predicted SE
    falls as 1/√repetitions exactly, and with more cycles about as 1/√cycles (the cycle
    average's noise does; the transient from rest, a larger share of a short recording,
    informs too)."""
    from posture_id.design.noise import SwayNoise
    from posture_id.design.predict import DesignOptions, predict_protocols
    from posture_id.simulation.protocols import PrtsProtocol

    options = DesignOptions(draws=3, seed=4)
    base = PrtsProtocol(80, 0.25, 2.0, 2)
    more = [base, PrtsProtocol(80, 0.25, 2.0, 8), PrtsProtocol(80, 0.25, 2.0, 2, 4)]
    preds = predict_protocols(winter1, more, SwayNoise(0.05), options)
    se = [p.standard_errors for p in preds]
    assert np.all(np.isfinite(se[0]))
    assert np.all(se[1] < se[0]) and 0.4 < np.median(se[1] / se[0]) < 0.75
    np.testing.assert_allclose(se[2], se[0] / 2, rtol=1e-9)
    assert np.all(preds[0].widths < 1)
    # a 10× larger sensor noise: 10× the SE
    noisier = predict_protocols(winter1, [base], SwayNoise(0.5), options)[0]
    np.testing.assert_allclose(noisier.standard_errors, se[0] * 10, rtol=1e-9)


@pytest.mark.slow("a protocol design through the command line")
def test_design_command_ranks_and_writes_the_report(winter1, tmp_path, capsys):
    from posture_id.cli import main
    from posture_id.simulation.protocols import PrtsProtocol, read_protocol, write_protocol

    files = [write_protocol(PrtsProtocol(80, 0.25, a, 3), tmp_path / f"p{a:g}.json")
             for a in (0.5, 3.0)]
    out = tmp_path / "design"
    assert main(["design", "--body", str(winter1.urdf_path), "--protocol", *map(str, files),
                 "--draws", "3", "--goal", "kp", "kd", "--max-minutes", "5", "--out",
                 str(out), "--quiet"]) == 0
    report = json.loads((out / "design.json").read_text())
    assert [r["label"] for r in report["ranking"]][0].startswith("PRTS 80×0.25 s, 3°")
    assert read_protocol(out / "recommended.json") == PrtsProtocol(80, 0.25, 3.0, 3)
    assert (out / "design.png").stat().st_size > 0 and "Recommended" in (
        out / "design.md").read_text()
    # a limit the larger amplitude breaks leaves the smaller one
    assert main(["design", "--body", str(winter1.urdf_path), "--protocol", *map(str, files),
                 "--draws", "3", "--max-peak-to-peak-deg", "1", "--out", str(out),
                 "--quiet"]) == 0
    assert read_protocol(out / "recommended.json") == PrtsProtocol(80, 0.25, 0.5, 3)
    bad = tmp_path / "bad.json"
    bad.write_text('{"kind": "prts", "cycles": 0}')
    assert main(["design", "--protocol", str(bad), "--out", str(out)]) == 2
    assert "bad.json" in capsys.readouterr().err


def test_the_raw_fit_weighs_harmonics_alike_and_loses_to_the_locked_one_on_coloured_noise():
    rng = np.random.default_rng(5)
    jac = rng.standard_normal((40, 1, 2)) + 1j * rng.standard_normal((40, 1, 2))
    white = np.full((40, 1, 1), 0.2 + 0j)
    raw = harmonic_information(jac, white, weighted=False).fit_covariance()
    np.testing.assert_allclose(raw, harmonic_information(jac, white).fit_covariance(),
                               rtol=1e-12)
    coloured = (np.geomspace(0.01, 10, 40) + 0j)[:, None, None]
    raw = harmonic_information(jac, coloured, weighted=False).fit_covariance()
    locked = harmonic_information(jac, coloured).fit_covariance()
    assert np.all(np.diag(raw) > 1.5 * np.diag(locked))


def test_a_protocol_leaving_parameters_undetermined_gets_a_notice():
    """The report warns where its predictions are beyond the fit's linear range: a
    protocol whose median width of some parameter is at least half the prior's."""
    from posture_id.design.goal import DesignGoal
    from posture_id.design.noise import SwayNoise
    from posture_id.design.predict import DesignOptions, ProtocolPrediction
    from posture_id.design.report import UNDETERMINED, DesignResult
    from posture_id.simulation.protocols import PrtsProtocol

    def prediction(amplitude: float, widths: np.ndarray) -> ProtocolPrediction:
        protocol = PrtsProtocol(80, 0.25, amplitude, 2)
        return ProtocolPrediction(protocol, protocol.label(), 1.0, amplitude, 1.0,
                                  np.zeros((1, 1, 4)), np.zeros((1, 1)),
                                  np.zeros((1, 1, 4)), widths, widths, np.zeros(1), 1, 0.1)

    tight = prediction(3.0, np.array([[0.1, 0.3, 0.2, UNDETERMINED * 0.99]]))
    loose = prediction(1.0, np.array([[0.1, np.inf, 0.2, UNDETERMINED]]))
    result = DesignResult("b", ("ankle",), SwayNoise(0.05), DesignOptions(), DesignGoal(),
                          (tight, loose), 1.0)
    assert len(result.notices) == 1
    assert result.notices[0].startswith(loose.label) and "2 of 4" in result.notices[0]
    assert result.notices[0] in result.markdown()
    assert result.to_dict()["notices"] == list(result.notices)
