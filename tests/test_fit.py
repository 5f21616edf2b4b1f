"""Least-squares identification (CasADi): recovery from noise-free and noisy recordings,
result object, command line, bad input."""

from __future__ import annotations

import json
from concurrent.futures import ThreadPoolExecutor
from dataclasses import replace

import numpy as np
import pytest

from posture_id.cli import main
from posture_id.dec.prior import sample_parameters
from posture_id.errors import RecordingError
from posture_id.fitting import FitOptions, fit_recording
from posture_id.recording import Recording
from posture_id.simulation import SimulationOptions, prts, simulate
from posture_id.trials import prepare_trial


def _stable_trial(body, seed, stimulus=None):
    rng = np.random.default_rng(seed)
    while True:
        truth = sample_parameters(body, 1, rng).trial(0, body.joint_names)
        result = simulate(body, truth, stimulus)
        if result.stable:
            return truth, result, rng


def _check_recovery(fitted, truth, tolerance, max_flagged):
    """Classes right; at most ``max_flagged`` of the 4N parameters flagged; every other
    one within ``tolerance`` (relative) of the truth and within 3 standard errors."""
    assert fitted.classes == tuple(truth[j].controls for j in truth.joints)
    assert fitted.poorly_determined.sum() <= max_flagged, fitted.summary()
    for k, field in enumerate(("kp", "ki", "kd", "delay_s")):
        fit, true = fitted.parameters.array(field), truth.array(field)
        determined = ~fitted.poorly_determined[:, k]
        error = np.abs(fit / true - 1)
        assert np.all(error[determined] <= tolerance), (field, error, fitted.summary())
        within = np.abs(fit - true) <= 3 * fitted.standard_errors[:, k]
        assert np.all(within[determined]), (field, fit - true, fitted.standard_errors[:, k])


@pytest.fixture(scope="module")
def noise_free(tip, tmp_path_factory):
    """A noise-free 60 s recording (three 80-state cycles) from random parameters, fitted
    by the command line."""
    truth, result, _ = _stable_trial(tip, 11, prts(states=80, cycles=3))
    folder = tmp_path_factory.mktemp("fit")
    result.to_csv(folder / "rec.csv")
    code = main(["fit", str(folder / "rec.csv"), "--out", str(folder / "fit.json"),
                 "--plot", str(folder / "fit.png")])
    return truth, folder, code


@pytest.mark.slow("least squares through the command line, 3 segments")
def test_noise_free_fit_recovers_the_truth(noise_free, tip):
    truth, folder, code = noise_free
    assert code == 0
    data = json.loads((folder / "fit.json").read_text())
    assert data["status"]["converged"]
    assert data["status"]["rms_deg"] < 1e-6
    assert sum(len(v) for v in data["poorly_determined"].values()) <= 4
    for joint in tip.joint_names:
        assert data["parameters"][joint]["controls"] == truth[joint].controls
        for field in ("kp", "ki", "kd", "delay_s"):
            fitted = data["parameters"][joint][field]
            if field in data["poorly_determined"][joint]:
                continue
            error = abs(fitted - getattr(truth[joint], field))
            assert error <= 0.02 * getattr(truth[joint], field)
            assert error <= 3 * data["standard_errors"][joint][field]
    assert data["provenance"]["body"]["sha256"] == tip.sha256
    assert data["provenance"]["options"]["classes"]["type"] == "RelaxedClasses"
    assert (folder / "fit.png").stat().st_size > 10_000


def test_noisy_fit_within_ten_percent_or_flagged(tip):
    truth, result, rng = _stable_trial(tip, 12, prts(states=80, cycles=3))  # 60 s
    noisy = result.theta + np.radians(0.01) * rng.standard_normal(result.theta.shape)
    noisy_rec = Recording(result.time, result.tilt, noisy, result.segments)
    fitted = fit_recording(prepare_trial(noisy_rec), tip)
    assert fitted.converged
    assert 0.008 < fitted.rms_deg < 0.012  # the fit reaches the noise, not below
    _check_recovery(fitted, truth, 0.10, max_flagged=6)
    data = fitted.to_dict()
    assert set(data["standard_errors"]) == set(tip.joint_names)
    assert json.loads(fitted.to_json()) == json.loads(json.dumps(data))


def test_short_recording_is_refused(tip):
    result = simulate(tip, stimulus=None, options=SimulationOptions())
    short = Recording(result.time[:1500], result.tilt[:1500], result.theta[:1500],
                      result.segments)
    with pytest.raises(RecordingError, match="shorter than one whole cycle of its stimulus"):
        fit_recording(prepare_trial(short), tip)


def test_segment_mismatch_is_refused(tip, winter2):
    result = simulate(tip)
    rec = Recording(result.time, result.tilt, result.theta, result.segments)
    with pytest.raises(RecordingError, match="do not match the body's segments leg,trunk"):
        fit_recording(prepare_trial(rec), winter2)


def test_other_rates_are_resampled_with_a_notice(tip):
    fine = simulate(tip, options=SimulationOptions(sample_rate_hz=100.0))
    rec = Recording(fine.time, fine.tilt, fine.theta, fine.segments)
    prepared = prepare_trial(replace(rec, name="rec100.csv"))
    resampled, notices = prepared.recording, prepared.notices
    assert all(n.startswith("rec100.csv: ") for n in notices)
    assert any("resampled from 100 Hz to 50 Hz" in n for n in notices)
    assert not any("time column says" in n for n in notices)  # a right time column: no hint
    at50 = simulate(tip)
    np.testing.assert_allclose(resampled.time, at50.time)
    np.testing.assert_allclose(resampled.theta, at50.theta, atol=1e-15)


def test_cli_errors_are_one_line(tmp_path, tip, capsys):
    result = simulate(tip)
    path = tmp_path / "nan.csv"
    result.to_csv(path)
    lines = path.read_text().splitlines()
    lines[100] = lines[100].rsplit(",", 1)[0] + ",nan"
    path.write_text("\n".join(lines) + "\n")
    assert main(["fit", str(path), "--out", str(tmp_path / "f.json")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "line 101, column 'trunk_deg'" in err


@pytest.mark.slow("six short least-squares fits, 2 and 3 segments")
def test_two_fits_at_once_equal_the_same_fits_one_after_the_other(tip, winter2):
    """Fits side by side (the identifier and the benchmark run them so) share compiled
    problems and their thread pools; a fit on another body must not disturb them."""
    jobs = []
    short = prts(cycles=1, states=80)  # 20 s: what is under test is sharing, not length
    for body, seed in ((tip, 21), (tip, 22), (winter2, 23)):
        truth, _, _ = _stable_trial(body, seed)
        jobs.append((body, simulate(body, truth, short).to_recording()))
    options = FitOptions(max_iterations=8, polish_iterations=3)

    def run(job):
        body, recording = job
        return fit_recording(prepare_trial(recording), body, options=options)

    one_by_one = [run(job) for job in jobs]
    with ThreadPoolExecutor(max_workers=3) as pool:
        side_by_side = list(pool.map(run, jobs))
    for a, b in zip(one_by_one, side_by_side, strict=True):
        np.testing.assert_array_equal(a.normalised, b.normalised)
        np.testing.assert_array_equal(a.standard_errors, b.standard_errors)
        assert a.cost == b.cost


@pytest.mark.slow("least squares from the defaults, 2 segments")
def test_any_robot_name_fits(tmp_path, winter2):
    """A URDF whose robot name has dots, dashes and spaces (as `posture-id body --height
    1.75` writes them) once crashed the fit inside CasADi's function naming."""
    from posture_id.bodies import load_body

    text = winter2.urdf_path.read_text()
    start = text.index('<robot name="') + len('<robot name="')
    end = text.index('"', start)
    path = tmp_path / "lab robot.urdf"
    path.write_text(text[:start] + "lab robot-v1.2 (left)" + text[end:])
    body = load_body(path)
    assert body.name == "lab robot-v1.2 (left)"
    truth, trial, _ = _stable_trial(body, 4)
    fitted = fit_recording(prepare_trial(trial.to_recording()), body)
    assert fitted.converged and fitted.rms_deg < 1e-6
    _check_recovery(fitted, truth, 0.02, 4)


@pytest.mark.slow("least squares from near the truth, 3 segments")
def test_known_classes_end_with_one_exact_jacobian(tip):
    """With the classes fixed and the warm start converged, the exact model gives the
    Jacobian at the warm optimum instead of iterating again: the parameters are the
    truth's (noise-free) and the standard errors come from the exact model."""
    from posture_id.fitting import FitOptions
    from posture_id.fitting.options import FixedClasses

    truth, trial, _ = _stable_trial(tip, 21)
    start = truth  # the truth's classes, gains 10 % off
    for joint in tip.joint_names:
        start = start.replace(joint, kp=1.1 * truth[joint].kp, kd=0.9 * truth[joint].kd)
    fitted = fit_recording(prepare_trial(trial.to_recording()), tip, start,
                           FitOptions(classes=FixedClasses()))
    assert [s.name for s in fitted.stages][-1] == "exact Jacobian at the optimum"
    assert fitted.stages[-1].evaluations == 1 and fitted.converged
    assert fitted.rms_deg < 1e-6
    _check_recovery(fitted, truth, 1e-4, 4)
    assert np.all(np.isfinite(fitted.standard_errors)) and np.all(fitted.standard_errors > 0)
