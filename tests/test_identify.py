"""``posture_id.identify``: the CNN, least squares and the hybrid behind one entry point,
checked by re-simulation."""

from __future__ import annotations

import json

import numpy as np
import pytest

from posture_id.cli import main
from posture_id.dec import sample_parameters
from posture_id.identify import Method, identify
from posture_id.recording import Recording
from posture_id.simulation import prts, simulate


def _noisy_trial(body, seed, noise_deg, stimulus=None):
    rng = np.random.default_rng(seed)
    while True:
        truth = sample_parameters(body, 1, rng).trial(0, body.joint_names)
        trial = simulate(body, truth, stimulus)
        if trial.stable:
            break
    noisy = trial.theta + np.radians(noise_deg) * rng.standard_normal(trial.theta.shape)
    return truth, Recording(trial.time, trial.tilt, noisy, trial.segments)


def test_cnn_result_is_checked_by_resimulation(tip, tmp_path):
    truth, recording = _noisy_trial(tip, 31, 0.0)
    result = identify(recording, tip, Method.CNN)
    assert result.classes == tuple(truth[j].controls for j in tip.joint_names)
    assert 0 < result.e_rel < 0.5 and result.e_id_deg > 0
    assert [s.segment for s in result.segments] == list(tip.segment_names)
    assert all(s.variance_explained > 0.5 for s in result.segments)
    data = json.loads(result.to_json())
    assert data["method"] == "cnn" and data["fit"] is None
    assert data["provenance"]["body"]["sha256"] == tip.sha256
    fig = result.plot(tmp_path / "cnn.png")
    assert len(fig.axes) == 4 and (tmp_path / "cnn.png").stat().st_size > 10_000
    assert "E_rel" in result.summary()
    # the bundled model is calibrated: intervals around every answer, said in words
    iv = result.intervals
    assert iv.method.startswith("conformal, universal network") and iv.level == 0.9
    assert np.all(iv.lower <= result.normalised[:, :4])
    assert np.all(result.normalised[:, :4] <= iv.upper)
    assert data["intervals"]["modules"]["ankle"]["kp"]["determination"] in (
        "well determined", "partly determined", "not determined")
    assert "90 % intervals" in result.summary()
    result.plot_intervals(tmp_path / "intervals.png")
    assert (tmp_path / "intervals.png").stat().st_size > 10_000


@pytest.mark.slow("the hybrid's least squares, 3 segments")
def test_hybrid_on_a_noisy_recording_recovers_classes_and_kp(tip, tmp_path):
    truth, recording = _noisy_trial(tip, 12, 0.01)
    csv = tmp_path / "noisy.csv"
    recording.to_csv(csv)
    out = tmp_path / "hybrid.json"
    # the hybrid's least-squares scales are calibrated from the TIP specialist's answers
    from posture_id.learning.bundled import bundled_model_dir

    specialist = str(bundled_model_dir(tip)[0])
    assert main(["identify", str(csv), "--method", "hybrid", "--network", specialist,
                 "--out", str(out), "--plot", str(tmp_path / "hybrid.png")]) == 0
    data = json.loads(out.read_text())
    for joint in tip.joint_names:
        assert data["parameters"][joint]["controls"] == truth[joint].controls
        assert abs(data["parameters"][joint]["kp"] / truth[joint].kp - 1) <= 0.05, joint
    assert data["fit"]["status"]["converged"]
    assert data["cnn"]["parameters"].keys() == data["parameters"].keys()  # kept beside
    # the fit's intervals, calibrated for the hybrid, hold every Kp; drawn beside the plot
    intervals = data["intervals"]
    assert intervals["method"] == "Gauss-Newton SE × calibrated scale"
    for joint in tip.joint_names:
        kp = intervals["modules"][joint]["kp"]
        assert kp["lower_si"] <= truth[joint].kp <= kp["upper_si"], joint
    assert (tmp_path / "hybrid.intervals.png").stat().st_size > 10_000
    cnn_only = identify(Recording.from_csv(csv, tip.segment_names), tip, Method.CNN)
    assert data["e_rel"] < cnn_only.e_rel  # refining reproduces the sway better


@pytest.mark.slow("least squares from the defaults, 3 segments")
def test_fit_method_needs_no_model(tip):
    truth, recording = _noisy_trial(tip, 11, 0.0, prts(states=80, cycles=3))  # 60 s
    result = identify(recording, tip, Method.FIT)
    assert result.class_probability is None and result.cnn is None
    assert result.classes == tuple(truth[j].controls for j in tip.joint_names)
    assert result.e_rel < 1e-4
    assert result.intervals.method == "Gauss-Newton ±z·SE (coverage not checked)"


@pytest.mark.slow("the hybrid's least squares, 3 segments")
def test_hybrid_overturns_a_confidently_wrong_cnn(tip, monkeypatch):
    """The CNN calls the knee's class wrong with P = 0 or 1: the short route (classes
    kept) leaves a locked residual far above the recording's noise, so the hybrid relaxes
    the classes and the fit recovers the truth; the verdict on the answer is good."""
    from dataclasses import replace

    from posture_id.learning.universal_identifier import UniversalIdentifier

    # two 80-state cycles (40 s): the route, not the recording's length, is under test
    truth, recording = _noisy_trial(tip, 12, 0.01, prts(states=80, cycles=2))
    honest = UniversalIdentifier.identify

    def confidently_wrong(self, trial, level=0.9):
        answer = honest(self, trial, level)
        wrong = "joint" if truth["knee"].controls == "com" else "com"
        probability = np.where(np.array(tip.joint_names) == "knee",
                               1.0 if wrong == "com" else 0.0,
                               (np.array([truth[j].controls for j in tip.joint_names])
                                == "com").astype(float))
        return replace(answer, parameters=answer.parameters.replace("knee", controls=wrong),
                       class_probability=probability)

    monkeypatch.setattr(UniversalIdentifier, "identify", confidently_wrong)
    result = identify(recording, tip, Method.HYBRID)
    assert result.cnn.parameters["knee"].controls != truth["knee"].controls
    assert any("fitted again with the classes relaxed" in n for n in result.notices)
    assert result.relaxed_refit
    assert any("overturned the CNN's class of knee" in n for n in result.notices)
    assert result.classes == tuple(truth[j].controls for j in tip.joint_names)
    for joint in tip.joint_names:
        assert abs(result.parameters[joint].kp / truth[joint].kp - 1) <= 0.05, joint
    assert not result.verdict.doubtful, result.verdict.line()


@pytest.mark.slow("the hybrid's least squares, 3 segments")
def test_auto_refines_a_doubtful_answer_and_keeps_a_good_one(tip, monkeypatch):
    """--method auto: a network's answer whose re-simulation is far from the recording is
    refined by least squares (and says so); a good answer is kept as it is."""
    from dataclasses import replace

    from posture_id.learning.universal_identifier import UniversalIdentifier

    truth, recording = _noisy_trial(tip, 12, 0.01)
    good = identify(recording, tip, Method.AUTO)
    if not good.verdict.doubtful:
        assert good.method is Method.CNN and good.fit is None
    honest = UniversalIdentifier.identify

    def feeble(self, trial, level=0.9):
        answer = honest(self, trial, level)
        weak = answer.parameters
        for joint in tip.joint_names:
            weak = weak.replace(joint, kd=0.3 * weak[joint].kd)
        return replace(answer, parameters=weak)

    monkeypatch.setattr(UniversalIdentifier, "identify", feeble)
    assert identify(recording, tip, Method.CNN).verdict.doubtful
    refined = identify(recording, tip, Method.AUTO)
    assert refined.method is Method.HYBRID and refined.fit is not None
    assert any("refined by least squares on the sway (--method auto)" in n
               for n in refined.notices)
    for joint in tip.joint_names:
        assert abs(refined.parameters[joint].kp / truth[joint].kp - 1) <= 0.05, joint


@pytest.mark.slow("least squares from the defaults, 1 segment")
def test_auto_fits_a_tilt_the_network_cannot_read(winter1):
    """The default method on a tilt that is not periodic (a sum of sines, 30 s): the
    network reads only whole cycles of a periodic tilt, so ``auto`` fits the recording by
    least squares from the body's defaults and says so."""
    from posture_id.dec import default_parameters
    from posture_id.simulation.stimulus import tilt_from_array

    t = np.arange(0, 30.0001, 0.02)
    tilt = np.radians(0.8) * (np.sin(2 * np.pi * 0.13 * t) + 0.6 * np.sin(2 * np.pi * 0.41 * t)
                              + 0.4 * np.sin(2 * np.pi * 0.97 * t))
    stimulus = tilt_from_array(t, tilt, "sum of sines")
    (joint,) = winter1.joint_names
    defaults = default_parameters(winter1)
    truth = defaults.replace(joint, kp=1.2 * defaults[joint].kp)
    recording = simulate(winter1, truth, stimulus).to_recording().with_sensor_noise(0.01, 2)
    result = identify(recording, winter1, stimulus=stimulus)  # the default: auto
    assert result.method is Method.FIT and result.cnn is None
    assert any("identified by least squares from the body's defaults (--method auto)" in n
               for n in result.notices)
    assert result.parameters[joint].kp == pytest.approx(truth[joint].kp, rel=0.02)
    assert not result.verdict.suggestion.startswith("--method")


def test_a_doubtful_fit_of_a_tilt_the_network_cannot_read_is_not_sent_to_it():
    from types import SimpleNamespace

    from posture_id.identify.verdict import suggestion

    noisy = SimpleNamespace(acceptable=False, noise_relative=0.01)
    assert suggestion(Method.FIT, False, None, (), noisy) == "--method hybrid"
    instead = suggestion(Method.FIT, False, None, (), noisy, whole_cycles=False)
    assert "--method" not in instead and "whole cycle of a periodic tilt" in instead
    assert "--locked" not in suggestion(Method.FIT, False, None, ("ankle kp at its upper "
                                                                  "bound (3)",), noisy,
                                        whole_cycles=False)


@pytest.mark.slow("the hybrid's least squares, 3 segments")
def test_auto_refines_noisy_sway_on_its_stimulus_locked_part(tip):
    """Motor-noisy sway, three quarters of it stimulus-locked (not people-like): the
    network's answer explains the locked sway as well as its noise allows, and that noise
    leaves about a quarter of it, so no answer can be checked to 10 % (imprecise). Least
    squares on every sample would fit the subject's own sway too (benchmarks/auto_rule.py):
    ``auto`` refines on the stimulus-locked sway, and says so."""
    from posture_id.dec.parameters import default_parameters
    from posture_id.simulation.noise import MotorNoise

    truth = default_parameters(tip)
    trial = simulate(tip, truth, motor_noise=MotorNoise(0.1, seed=1))
    rng = np.random.default_rng(1)
    noisy = trial.theta + np.radians(0.05) * rng.standard_normal(trial.theta.shape)
    recording = Recording(trial.time, trial.tilt, noisy, trial.segments)
    network = identify(recording, tip, Method.CNN).verdict
    assert network.locked_share > 0.6 and network.noise.consistent
    # nothing says it is wrong, but it cannot be checked to 10 %: imprecise, no suggestion
    assert network.noise.noise_relative > 0.1 and network.level.value == "imprecise"
    assert not network.doubtful and network.suggestion == ""
    result = identify(recording, tip)
    assert result.method is Method.HYBRID and result.fit is not None
    assert any("refined by least squares on the stimulus-locked sway" in n
               for n in result.notices)
    for joint in tip.joint_names:
        assert abs(result.parameters[joint].kp / truth[joint].kp - 1) <= 0.15, joint


def test_auto_fits_a_body_the_network_does_not_identify(tmp_path):
    """A chain of 4 segments is beyond the universal network (1 to 3 modules): ``auto``
    takes least squares from the body's defaults for it, and says why; the network alone
    is refused in one sentence."""
    from posture_id.bodies.anthropometry import SegmentSpec, straight_links
    from posture_id.bodies.body import load_body
    from posture_id.bodies.urdf_writer import chain_urdf
    from posture_id.identify import Identifier
    from posture_id.learning.config import LearningError

    parts = [SegmentSpec(link, joint, 0.5, mass, 0.25, mass * 0.5**2 / 12) for link, joint, mass
             in (("shank", "ankle", 8.0), ("thigh", "knee", 12.0), ("trunk", "hip", 25.0),
                 ("head", "neck", 5.0))]
    urdf = tmp_path / "four.urdf"
    urdf.write_text(chain_urdf("four_segments", straight_links(parts)))
    body = load_body(urdf)
    auto = Identifier(body)
    assert auto.cnn is None and "1 to 3 segments" in auto.network_refusal
    with pytest.raises(LearningError, match="1 to 3 segments; 'four_segments' has 4"):
        Identifier(body, Method.CNN)
