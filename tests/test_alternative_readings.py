"""A recording explained far better read another way is doubted, and the other way named:
segment columns exchanged, another person's body. A body scaled in size keeps its
masses and scales its lengths, its m·g·h by b and its inertias by b²."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

import posture_id.identify.alternatives as alternatives
import posture_id.identify.core as core
from posture_id.bodies.anthropometry import straight_links, winter_segments
from posture_id.bodies.body import load_body
from posture_id.bodies.scaling import scaled_body
from posture_id.bodies.urdf_writer import write_chain_urdf
from posture_id.dec.parameters import default_parameters
from posture_id.identify import Method, identify
from posture_id.simulation import prts, simulate

#: The project's shipped URDFs (``make bodies``).
URDF_DIR = Path(__file__).resolve().parents[1] / "urdf"


def _winter(tmp_path, height, mass, segments):
    path = tmp_path / f"winter_{height}_{mass}_{segments}.urdf"
    write_chain_urdf(path, f"winter{segments}",
                     straight_links(winter_segments(height, mass, segments)))
    return load_body(path)


@pytest.mark.parametrize("name", ["tip_default", "talos_tip", "winter_1.75m_70kg_2seg"])
def test_a_scaled_body_keeps_its_build(name):

    body = load_body(URDF_DIR / f"{name}.urdf")
    same = scaled_body(body, 1.0)
    np.testing.assert_allclose(same.mgh, body.mgh, rtol=1e-12)
    np.testing.assert_allclose(same.inertias, body.inertias, rtol=1e-12)
    np.testing.assert_allclose(same.coupling, body.coupling, rtol=1e-12, atol=1e-12)
    assert same.segment_names == body.segment_names and same.joint_names == body.joint_names
    larger = scaled_body(body, 1.2)
    np.testing.assert_allclose(larger.mgh, 1.2 * body.mgh, rtol=1e-12)
    np.testing.assert_allclose(larger.inertias, 1.44 * body.inertias, rtol=1e-12)
    assert larger.total_mass == pytest.approx(body.total_mass)


def test_a_scaled_winter_body_is_the_winter_body_of_that_height(tmp_path):
    """Winter's proportions are shares of the height: 1.55 m × 1.226 is the 1.90 m body
    of the same mass."""
    short = _winter(tmp_path, 1.55, 70.0, 2)
    tall = _winter(tmp_path, 1.90, 70.0, 2)
    np.testing.assert_allclose(scaled_body(short, 1.90 / 1.55).inertias, tall.inertias,
                               rtol=1e-9)


@pytest.fixture(scope="module")
def clean_two_segment(tmp_path_factory):
    body = _winter(tmp_path_factory.mktemp("bodies"), 1.75, 70.0, 2)
    truth = default_parameters(body)
    truth = truth.replace(body.joint_names[0], kp=1.2 * truth[body.joint_names[0]].kp)
    recording = simulate(body, truth, prts()).to_recording().with_sensor_noise(0.02, 5)
    return body, recording


def test_exchanged_columns_are_named_and_the_right_ones_are_not(clean_two_segment,
                                                                monkeypatch):
    body, recording = clean_two_segment
    right = identify(recording, body, Method.CNN, stimulus=prts())
    assert not any("exchanged" in m for m in right.verdict.mistakes)
    theta = recording.theta[:, ::-1].copy()
    swapped = identify(replace(recording, theta=theta), body, Method.CNN, stimulus=prts())
    assert swapped.verdict.doubtful
    named = [m for m in swapped.verdict.mistakes if "are they exchanged?" in m]
    assert named and named[0].startswith(f"the {body.segment_names[0]} and "
                                         f"{body.segment_names[1]} columns read the other way")
    monkeypatch.setattr(alternatives, "SWAP_GAIN", np.inf)  # the check switched off
    again = identify(replace(recording, theta=theta), body, Method.CNN, stimulus=prts())
    assert not any("exchanged" in m for m in again.verdict.mistakes)


@pytest.mark.slow("identifications reading other body sizes")
def test_another_persons_body_is_named(tmp_path, monkeypatch):
    """A 1.90 m subject (the default controller, the 80-state PRTS at 3°, 0.02° of sensor
    noise) identified with the URDF of a 1.55 m one (the masses too differ, which the sway
    cannot show): a taller body explains the sway better, and least squares on the given
    body does not reach the noise, so it is named. The subject's own body is not; with
    the check switched off nothing is."""
    tall = _winter(tmp_path, 1.90, 95.0, 2)
    short = _winter(tmp_path, 1.55, 50.0, 2)
    stimulus = prts(3.0, 6, 80)
    recording = simulate(tall, default_parameters(tall), stimulus).to_recording()
    recording = replace(recording.with_sensor_noise(0.02, 6), segments=short.segment_names)
    result = identify(recording, short, Method.CNN, stimulus=stimulus)
    assert result.verdict.doubtful, result.verdict.line()
    named = [m for m in result.verdict.mistakes if "is the URDF this subject's?" in m]
    assert named and "taller" in named[0]
    own = identify(replace(recording, segments=tall.segment_names), tall, Method.CNN,
                   stimulus=stimulus)
    assert not any("URDF" in m for m in own.verdict.mistakes)
    monkeypatch.setattr(alternatives, "SIZE_GAIN", np.inf)  # the check switched off
    again = identify(recording, short, Method.CNN, stimulus=stimulus)
    assert not any("URDF" in m for m in again.verdict.mistakes)


def test_a_recording_cleaner_than_the_networks_own_error_reads_no_alternative(
        tmp_path, monkeypatch):
    """No sensor noise at all (a 1.75 m, 70 kg 2-segment Winter body, docs/model.md §5's draw of
    seed 109, the 80-state PRTS at 3°): the network's own error is hundreds of noise units,
    and a body 20 % shorter happens to read fewer (a chance of the network, not
    evidence): with the guard switched off it is named (least squares' confirmation
    switched off too: the readings alone), with it nothing is."""
    from posture_id.dec.prior import sample_parameters
    from posture_id.identify.alternatives import MIN_NOISE_SHARE
    from posture_id.identify.core import Identifier

    body = _winter(tmp_path, 1.75, 70.0, 2)
    truth = sample_parameters(body, 1, np.random.default_rng(109)).trial(0, body.joint_names)
    stimulus = prts(3.0, 6, 80)
    recording = simulate(body, truth, stimulus).to_recording()
    result = identify(recording, body, Method.CNN, stimulus=stimulus)
    noise = result.verdict.noise
    assert noise.ratio > 10 and noise.relative / noise.ratio < MIN_NOISE_SHARE
    assert not result.verdict.mistakes
    monkeypatch.setattr(alternatives, "MIN_NOISE_SHARE", 0.0)
    monkeypatch.setattr(Identifier, "_fits_within_noise", lambda self, *args: False)
    unguarded = identify(recording, body, Method.CNN, stimulus=stimulus)
    assert any("a body 20 % shorter" in m for m in unguarded.verdict.mistakes)


def test_exchanged_columns_are_named_on_a_recording_cleaner_than_the_networks_error(
        monkeypatch):
    """A 3-segment Winter body (1.75 m, 70 kg, docs/model.md §5's draw of seed 1) under the
    80-state PRTS at 2°, 0.02° of sensor noise (under 0.3 % of its locked sway), its shank
    and thigh columns exchanged: the answer leaves 7 % of the locked sway, close enough to
    pass on its own; the columns put back leave a third or less of it, so they are named
    and the answer is doubtful. With the size guard applied to columns too, as before,
    it was not; the recording as made has nothing named."""
    from posture_id.dec.prior import sample_parameters
    from posture_id.learning.data.bodies import build_body
    from posture_id.learning.data.scope import BodyDraw

    body = build_body(BodyDraw("winter", 3, 1.75, 70.0, ((1.0, 1.0),) * 3))
    stimulus = prts(2.0, 6, 80)
    truth = sample_parameters(body, 1, np.random.default_rng(1)).trial(0, body.joint_names)
    recording = simulate(body, truth, stimulus).to_recording().with_sensor_noise(0.02, 7)
    theta = recording.theta.copy()
    theta[:, [0, 1]] = theta[:, [1, 0]]
    exchanged = replace(recording, theta=theta)
    result = identify(exchanged, body, Method.CNN, stimulus=stimulus)
    noise = result.verdict.noise
    assert noise.relative / noise.ratio < alternatives.MIN_NOISE_SHARE
    assert noise.relative < 0.10  # close enough to pass without the check
    assert result.verdict.doubtful
    assert any(m.startswith("the shank and thigh columns read the other way round")
               for m in result.verdict.mistakes)
    assert not identify(recording, body, Method.CNN, stimulus=stimulus).verdict.mistakes
    original = alternatives.better_explanations

    def guarded_columns_too(trial, body, ratio, relative, ratio_of, sizes=True):
        if relative / ratio < alternatives.MIN_NOISE_SHARE:
            return ()
        return original(trial, body, ratio, relative, ratio_of, sizes)

    monkeypatch.setattr(core, "better_explanations", guarded_columns_too)
    before = identify(exchanged, body, Method.CNN, stimulus=stimulus)
    assert not any("exchanged" in m for m in before.verdict.mistakes)
    assert not before.verdict.doubtful


@pytest.mark.slow("identifications reading other body sizes")
def test_a_body_a_tenth_off_is_not_called_another_persons(tmp_path, monkeypatch):
    """A 1.75 m, 70 kg 2-segment Winter subject (docs/model.md §5's draw of seed 0, the default
    PRTS, 0.01° of sensor noise) on the right body: read with the body a tenth shorter,
    the network's answer leaves less of the noise by more than 1.3×, a chance of its own
    error on clean sway (the cohort tutorial's first subject did so with the network
    fine-tuned over the noise families alone). Only the far sizes (a fifth or more off)
    are read, so nothing is named; with the near sizes read too (and least squares'
    confirmation switched off: the readings alone), the right body is called another
    person's."""
    from posture_id.dec.prior import sample_parameters
    from posture_id.identify.core import Identifier

    body = _winter(tmp_path, 1.75, 70.0, 2)
    truth = sample_parameters(body, 1, np.random.default_rng(0)).trial(0, body.joint_names)
    recording = simulate(body, truth).to_recording().with_sensor_noise(0.01, 10)
    result = identify(recording, body)
    assert not any("URDF" in m for m in result.verdict.mistakes)
    monkeypatch.setattr(alternatives, "SIZES", (0.8, 0.9, 1.1, 1.25))
    monkeypatch.setattr(Identifier, "_fits_within_noise", lambda self, *args: False)
    near = identify(recording, body)
    assert any("a body 10 % shorter" in m for m in near.verdict.mistakes)


@pytest.mark.slow("identifications reading other body sizes")
def test_a_size_the_network_reads_by_chance_is_not_named_when_least_squares_fits(
        tmp_path, monkeypatch):
    """A 1.85 m, 85 kg 1-segment Winter subject (docs/model.md §5's draw of seed 20, the default
    PRTS, 0.01° of sensor noise) on the right body: the network's answer, read with the
    body a fifth shorter, leaves less of the noise by more than 1.3× (its own error on
    clean sway), but least squares from its answer on the given body explains the sway
    within the noise, so no other body is named; without that confirmation the right
    body is called another person's."""
    from posture_id.dec.prior import sample_parameters
    from posture_id.identify.core import Identifier

    body = _winter(tmp_path, 1.85, 85.0, 1)
    truth = sample_parameters(body, 1, np.random.default_rng(20)).trial(0, body.joint_names)
    recording = simulate(body, truth).to_recording().with_sensor_noise(0.01, 30)
    result = identify(recording, body)
    assert not any("URDF" in m for m in result.verdict.mistakes)
    monkeypatch.setattr(Identifier, "_fits_within_noise", lambda self, *args: False)
    unconfirmed = identify(recording, body)
    assert any("a body 20 % shorter" in m for m in unconfirmed.verdict.mistakes)
