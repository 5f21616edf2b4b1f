"""The recording widening (posture_id.uncertainty.widening): a second calibration of the
network's intervals for people-like sway, by the share of its locked sway the recording's
own noise leaves."""

from __future__ import annotations

import json

import numpy as np
import pytest

from posture_id.errors import PostureIdError
from posture_id.uncertainty.intervals import ParameterIntervals
from posture_id.uncertainty.widening import (
    BINS,
    WIDENING_FILE,
    RecordingWidening,
    fit_widening,
    scores_of,
)


def test_scores_use_the_half_width_on_the_truths_side():
    estimate = np.array([[0.0, 0.0]])
    lower, upper = np.array([[-0.1, -1.0]]), np.array([[0.4, 0.2]])
    assert scores_of(estimate, np.array([[0.2, -0.5]]), lower, upper) == pytest.approx(
        np.array([[0.5, 0.5]]))
    assert scores_of(estimate, np.array([[-0.2, 0.4]]), lower, upper) == pytest.approx(
        np.array([[2.0, 2.0]]))


def test_each_noise_bin_gets_its_own_conformal_factor_never_below_one():
    """Scores that grow with the noise share: the noisier half of the recordings gets a
    factor, the quantile of its own scores at the level; the cleaner (scores within their
    intervals) none."""
    assert BINS == 2
    rng = np.random.default_rng(3)
    share = rng.uniform(0.2, 0.8, 900)
    scale = np.where(share > 0.5, 2.0, 0.5)
    scores = np.abs(rng.standard_normal((900, 4))) * scale[:, None] / 1.645
    widening = fit_widening(scores, share, 0.9, "abc")
    assert len(widening.factors) == BINS and sum(widening.counts) == 900
    assert widening.edges == pytest.approx((0.5,), abs=0.03)
    low, high = widening.factor(0.3), widening.factor(0.7)
    assert np.all(low == 1.0)  # covered already: never narrowed
    assert high == pytest.approx(np.full(4, 2.0), rel=0.15)
    # the conformal guarantee on fresh scores of the noisier bin
    fresh = np.abs(rng.standard_normal((20000, 4))) * 2.0 / 1.645
    assert np.mean(fresh <= high) == pytest.approx(0.9, abs=0.02)
    with pytest.raises(PostureIdError, match="too few"):
        fit_widening(scores[:5], share[:5], 0.9, "abc")


def test_intervals_are_widened_about_the_estimate_and_cut_at_minus_one():
    defaults = np.array([[100.0, 10.0, 50.0, 0.1]])
    estimate = np.array([[0.0, -0.5, 0.1, 0.0]])
    base = ParameterIntervals.around(estimate, np.array([[0.1, 0.4, 0.05, 0.2]]), defaults,
                                     0.9, "conformal", 0.02, ("ankle",))
    wide = base.widened(estimate, np.array([2.0, 2.0, 1.0, 1.5]), defaults, "widened")
    assert wide.upper == pytest.approx(np.array([[0.2, 0.3, 0.15, 0.3]]))
    assert wide.lower == pytest.approx(np.array([[-0.2, -1.0, 0.05, -0.3]]))  # Ki cut at p̃ = −1
    assert wide.upper_si == pytest.approx(defaults * (1 + wide.upper))
    assert wide.method == "conformal; widened" and wide.level == 0.9


def test_a_widening_file_that_is_not_one_is_refused_naming_it(tmp_path):
    (tmp_path / WIDENING_FILE).write_text(json.dumps({"format": "something else"}))
    with pytest.raises(PostureIdError, match=WIDENING_FILE):
        RecordingWidening.load(tmp_path)
    good = RecordingWidening(0.9, (0.4, 0.6), ((1.0,) * 4, (1.1,) * 4, (1.5,) * 4),
                             (10, 10, 10), "abc")
    good.save(tmp_path)
    assert RecordingWidening.load(tmp_path) == good
    bad = good.to_dict() | {"factors": [[0.5] * 4] * 3}
    (tmp_path / WIDENING_FILE).write_text(json.dumps(bad))
    with pytest.raises(PostureIdError, match="values ≥ 1"):
        RecordingWidening.load(tmp_path)
    assert RecordingWidening.load(tmp_path / "nowhere") is None


@pytest.fixture(scope="module")
def identifier():
    from posture_id.bodies.body import load_body
    from posture_id.identify import Identifier

    return Identifier(load_body())


@pytest.mark.slow("the default method on people-like sway, 3 segments")
def test_the_bundled_network_widens_a_people_like_recordings_intervals_only(identifier):
    """The bundled universal model carries its widening (made for its weights): a
    people-like recording's intervals are its conformal ones times its noise bin's factors,
    said in their method; a clean recording's are not touched."""
    from posture_id.dec.parameters import default_parameters
    from posture_id.simulation.stimulus import prts
    from posture_id.simulation.subjects import people_like

    network = identifier.cnn
    assert network.widening is not None, network.notices
    body = identifier.body
    stimulus = prts(states=80, cycles=6)
    subject = people_like(body, default_parameters(body), stimulus, 0.2, seed=5)
    noisy = identifier.identify(subject.recording, stimulus)
    assert noisy.verdict.locked_share < 0.5 and "widened ×" in noisy.intervals.method
    relative = noisy.verdict.noise.noise_relative
    factor = network.widening.factor(relative)
    raw = network.identify(identifier.prepare(subject.recording, stimulus),
                           identifier.level).intervals
    width, raw_width = (noisy.intervals.upper - noisy.intervals.lower,
                        raw.upper - raw.lower)
    uncut = noisy.intervals.lower > -1
    assert np.allclose((width / raw_width)[uncut], np.broadcast_to(factor, width.shape)[uncut])
    clean = identifier.identify(subject.locked.to_recording().with_sensor_noise(0.02, 1),
                                stimulus)
    assert "widened" not in clean.intervals.method
