"""The residual against the recording's own noise: known answers.

A model that is the truth leaves exactly the noise that was added, so its ratio is about 1
whether the noise is white sensor noise (raw and locked) or the sway a subject makes of
their own (locked); a wrong class leaves more than the limit; a model that falls is
infinite and never consistent.
"""

from __future__ import annotations

import json
import math
from dataclasses import replace

import numpy as np
import pytest

from posture_id.dec.parameters import Controls, DecParameters, default_parameters
from posture_id.identify.noise_check import NOISE_RATIO_LIMIT, noise_check
from posture_id.simulation import prts, simulate
from posture_id.simulation.stimulus import tilt_from_array
from posture_id.simulation.subjects import people_like
from posture_id.trials import prepare_trial


def _flipped(params: DecParameters, joint: str) -> DecParameters:
    mods = dict(params.modules)
    other = Controls.JOINT if mods[joint].controls is Controls.COM else Controls.COM
    mods[joint] = replace(mods[joint], controls=other)
    return DecParameters(mods)


@pytest.mark.parametrize("noise_deg", [0.01, 0.05])
def test_the_truth_leaves_the_sensor_noise_locked(tip, noise_deg):
    truth = default_parameters(tip)
    clean = simulate(tip, truth)
    trial = prepare_trial(clean.to_recording().with_sensor_noise(noise_deg, 3))
    check = noise_check(trial, clean.theta)
    assert check.basis == "locked"
    assert 0.8 < check.ratio < 1.2 and check.consistent
    wrong = simulate(tip, _flipped(truth, tip.joint_names[2]))
    assert wrong.stable
    bad = noise_check(trial, wrong.theta)
    assert bad.ratio > 3 * NOISE_RATIO_LIMIT and not bad.consistent


def test_a_tilt_that_is_not_periodic_is_judged_by_its_white_noise(tip):
    t = np.arange(0, 60.0001, 0.02)
    tilt = np.radians(0.5) * (np.sin(2 * np.pi * 0.11 * t) + 0.6 * np.sin(2 * np.pi * 0.37 * t)
                              + 0.4 * np.sin(2 * np.pi * 0.93 * t))
    stimulus = tilt_from_array(t, tilt, "sum of sines")
    truth = default_parameters(tip)
    clean = simulate(tip, truth, stimulus)
    trial = prepare_trial(clean.to_recording().with_sensor_noise(0.03, 4), stimulus)
    check = noise_check(trial, clean.theta)
    assert check.basis == "raw"
    assert abs(check.noise_deg - 0.03) < 0.005
    assert 0.85 < check.ratio < 1.15 and check.consistent
    wrong = simulate(tip, _flipped(truth, tip.joint_names[1]), stimulus)
    assert not noise_check(trial, wrong.theta).consistent


def test_sway_of_the_subjects_own_counts_as_noise_when_locked(tip):
    """A people-like subject: 20 % of the body sway locked to the stimulus. The raw residual
    of the truth is mostly the subject's own sway, yet the locked ratio is about 1."""
    truth = default_parameters(tip)
    subject = people_like(tip, truth, prts(), 0.2, seed=5)
    trial = prepare_trial(subject.recording)
    check = noise_check(trial, subject.locked.theta)
    assert check.basis == "locked"
    assert 0.7 < check.ratio < 1.3 and check.consistent
    raw = np.degrees(subject.recording.theta - subject.locked.theta[: len(trial.recording.time)])
    assert raw.std() > 5 * 0.05  # far above the 0.05° sensor noise


def test_a_model_that_falls_is_never_consistent(tip):
    truth = default_parameters(tip)
    clean = simulate(tip, truth)
    trial = prepare_trial(clean.to_recording().with_sensor_noise(0.02, 1))
    fallen = clean.theta.copy()
    fallen[1000:] = np.nan
    check = noise_check(trial, fallen)
    assert math.isinf(check.ratio) and not check.consistent
    data = json.loads(json.dumps(check.to_dict(), allow_nan=False))
    assert data["ratio"] is None and data["consistent"] is False


def _added_noise_share(trial, noisy, clean):
    """(the trial's unweighted locked projection, the recorded sway (S, N) degrees, the
    share of the recorded locked sway that the added noise makes up: the answer the
    noise check estimates)."""
    from posture_id.frf.locked import LockedOptions, LockedProjection

    projection = LockedProjection.for_trial(trial, LockedOptions(weighted=False))
    recorded = np.degrees(noisy.theta)
    added = recorded - np.degrees(clean.theta[: len(noisy.time)])
    share = np.sqrt(np.sum(np.abs(projection.spectrum(added)) ** 2)
                    / np.sum(np.abs(projection.spectrum(recorded)) ** 2))
    return projection, recorded, share


def test_one_cycle_tells_how_much_of_the_locked_sway_its_noise_leaves(tip):
    """One cycle has no cycles to compare: the noise is read at the harmonics the PRTS
    leaves empty. Against the noise that was added (its own compared harmonics), the
    estimate is within a fifth; the truth is consistent and, at 0.1° of noise on a 0.5°
    tilt, too noisy to check an answer to 10 %."""
    truth = default_parameters(tip)
    clean = simulate(tip, truth, prts(0.5, 1))
    noisy = clean.to_recording().with_sensor_noise(0.1, 7)
    trial = prepare_trial(noisy)
    check = noise_check(trial, clean.theta)
    assert check.basis == "locked" and check.consistent
    projection, recorded, actual = _added_noise_share(trial, noisy, clean)
    assert projection.cycles == 1
    assert 0.8 < check.noise_relative / actual < 1.2
    assert check.noise_relative > 0.1 and check.unchecked


def test_one_cycle_s_noise_is_not_the_body_s_transient(tip):
    """One clean cycle at 0.01° of noise: the recording's empty harmonics also hold the
    body's transient from its start (more than 1.5× the noise's share here), the truth's
    residual only the noise; the smaller is used, so the truth is judged by the noise."""
    from posture_id.identify.noise_check import _empty_harmonics

    truth = default_parameters(tip)
    clean = simulate(tip, truth, prts(1.0, 1))
    noisy = clean.to_recording().with_sensor_noise(0.01, 3)
    trial = prepare_trial(noisy)
    check = noise_check(trial, clean.theta)
    projection, recorded, actual = _added_noise_share(trial, noisy, clean)
    locked = np.sum(np.abs(projection.spectrum(recorded)) ** 2)
    recording_alone = np.sqrt(np.sum(_empty_harmonics(projection, recorded)) / locked)
    assert recording_alone > 1.5 * actual
    assert 0.8 < check.noise_relative / actual < 1.2
    assert 0.8 < check.ratio < 1.2 and not check.unchecked


def test_an_identifier_judges_parameters_by_re_simulating_them(tip):
    """Identifier.judge: the parameters re-simulated on the trial's stimulus, their residual
    against the recording's noise and their relative residual on the body COM sway."""
    from posture_id.identify import Identifier, Method

    truth = default_parameters(tip)
    clean = simulate(tip, truth)
    trial = prepare_trial(clean.to_recording().with_sensor_noise(0.02, 5))
    judge = Identifier(tip, Method.FIT).judge
    right = judge(trial, tip, truth)
    by_hand = noise_check(trial, clean.theta, body_sway=(
        tip.com_angles(trial.recording.theta)[:, 0], clean.alpha[:, 0]))
    assert right.ratio == pytest.approx(by_hand.ratio) and right.consistent
    assert right.relative == pytest.approx(by_hand.relative)
    wrong = judge(trial, tip, _flipped(truth, tip.joint_names[2]))
    assert wrong.ratio > 3 * NOISE_RATIO_LIMIT and wrong.relative > right.relative
