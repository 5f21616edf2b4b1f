"""Every answer says when it should not be trusted, and its labels are true."""

from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pytest

from posture_id.dec.parameters import default_parameters
from posture_id.identify import Identifier, Method, identify
from posture_id.identify.verdict import LOCKED_FLAGS, PEOPLE_LIKE_SHARE
from posture_id.simulation import prts, simulate
from posture_id.simulation.subjects import people_like
from posture_id.uncertainty.intervals import ParameterIntervals


def test_people_like_sway_makes_a_specialist_doubtful_and_names_the_locked_fit(tip):
    """20 % of the sway locked to the stimulus: outside what a specialist saw; the
    verdict says so, with the locked share it estimated, and suggests the locked fit."""
    from posture_id.learning.bundled import bundled_model_dir

    subject = people_like(tip, default_parameters(tip), prts(), 0.2, seed=4)
    result = identify(subject.recording, tip, model=bundled_model_dir(tip)[0])
    verdict = result.verdict
    assert verdict.doubtful
    assert verdict.locked_share < PEOPLE_LIKE_SHARE
    assert abs(verdict.locked_share - subject.locked_share) < 0.1
    assert any("stimulus-locked" in r for r in verdict.reasons)
    assert verdict.suggestion == LOCKED_FLAGS
    assert result.summary().splitlines()[-1].startswith("trust: DOUBTFUL")
    data = json.loads(json.dumps(result.to_dict(), allow_nan=False))
    assert data["trust"]["doubtful"] and data["trust"]["suggestion"] == LOCKED_FLAGS


def test_people_like_sway_is_inside_the_universal_models_scope(tip):
    """The same subject with the default network, trained on people-like sway: its share
    is no reason for doubt, and a doubtful answer points to the locked hybrid, not to
    least squares from the defaults."""
    subject = people_like(tip, default_parameters(tip), prts(), 0.2, seed=4)
    result = identify(subject.recording, tip)
    verdict = result.verdict
    assert result.stimulus_offset_s == 0.0  # rightly timed: the timing search keeps it
    assert verdict.locked_share < PEOPLE_LIKE_SHARE
    assert not any("stimulus-locked; the network" in r for r in verdict.reasons)
    assert not any("least squares on the raw sway" in r for r in verdict.reasons)
    assert verdict.suggestion in ("", "--method hybrid --locked --prior-sd 0.5")


def test_a_clean_recording_of_the_networks_own_body_is_trusted(tip):
    truth = default_parameters(tip)
    recording = simulate(tip, truth).to_recording().with_sensor_noise(0.01, 2)
    result = identify(recording, tip)
    assert not result.verdict.doubtful, result.verdict.line()
    assert result.verdict.locked_share > 0.9
    assert result.intervals.method.startswith("conformal, universal network")


def test_another_bodys_network_is_named_and_its_intervals_labelled_for_what_they_are(winter):
    """A 3-segment Winter body identified with the TIP's network: the verdict says the
    network was trained on another body, and the intervals are not called calibrated."""
    from posture_id.learning.bundled import bundled_model_dir

    recording = simulate(winter, default_parameters(winter)).to_recording()
    specialist = bundled_model_dir(winter)[0]
    result = identify(recording.with_sensor_noise(0.01, 5), winter, Method.CNN,
                      model=specialist)
    assert any("trained on body 'tip_default'" in r for r in result.verdict.outside)
    assert result.verdict.doubtful and result.verdict.suggestion == "--method hybrid"
    assert "not on this one" in result.intervals.method
    assert "validation split" not in result.intervals.method


def test_an_identifier_knows_whether_its_network_was_trained_on_its_body(tip, winter):
    """What the hybrid's use of its calibrated scales turns on (core.Identifier)."""
    from posture_id.learning.bundled import bundled_model_dir

    specialist = bundled_model_dir(tip)[0]
    tip_identifier = Identifier(tip, Method.HYBRID, specialist)
    winter_identifier = Identifier(winter, Method.HYBRID, specialist)
    assert tip_identifier.cnn.trained_on_this_body
    assert not winter_identifier.cnn.trained_on_this_body
    # the universal model has no body of its own: the hybrid scales nothing by it
    assert not Identifier(tip, Method.HYBRID).cnn.trained_on_this_body


def test_the_sentences_say_what_the_precision_flags_say():
    """An interval narrow against the prior but wider than ±5 % of the value: the flag
    and the words agree (the words used to say nothing)."""
    estimate = np.zeros((1, 4))
    half = np.full((1, 4), 0.01)
    half[0, 1] = 0.2  # Ki: well determined against the prior (1.61 wide), ±20 % precision
    imprecise = np.array([[False, True, False, False]])
    intervals = ParameterIntervals.around(estimate, half, np.ones((1, 4)), 0.9, "test", 0.0,
                                          ("ankle",), imprecise)
    sentences = intervals.sentences()
    assert sentences == ["the ankle's Ki is determined to worse than ±5 % of the value "
                         "(poorly determined, 95 % Gauss-Newton interval)"]
    without = ParameterIntervals.around(estimate, half, np.ones((1, 4)), 0.9, "test", 0.0,
                                        ("ankle",))
    assert without.sentences() == []


@pytest.mark.slow("least squares from the defaults, 3 segments")
def test_a_parameter_on_a_search_bound_is_named(tip):
    """Kp 40 % above the defaults, searched within ±10 %: the fit stops on the bound, and
    the verdict names it and suggests a wider range."""
    from posture_id.fitting import FitOptions, FixedClasses

    truth = default_parameters(tip)
    truth = truth.replace("ankle", kp=1.4 * truth["ankle"].kp)
    recording = simulate(tip, truth).to_recording().with_sensor_noise(0.01, 6)
    options = FitOptions(gain_bounds=(-0.1, 0.1), classes=FixedClasses())  # the defaults'
    result = identify(recording, tip, Method.FIT, fit_options=options)
    assert any(b.startswith("ankle kp at its upper bound") for b in result.fit.on_bounds)
    assert result.verdict.doubtful
    assert any("on a search bound: ankle kp at its upper bound" in r
               for r in result.verdict.reasons)
    assert "--gain-range" in result.verdict.suggestion


@pytest.mark.parametrize(("share", "ratio", "noise_relative", "outside", "how", "level",
                          "suggested"), [
    # as good as the noise, the noise too large to check it: imprecise, refined on the
    # locked sway (the network's answer was measured to gain from it there)
    (0.8, 1.0, 0.3, (), "locked", "imprecise", "--method hybrid --locked"),
    (0.8, 3.0, 0.05, (), "raw", "doubtful", "--method hybrid"),  # a far answer, clean sway
    (0.8, 3.0, 0.3, (), "raw", "doubtful", "--method hybrid"),   # more than the noise leaves
    # people-like, beyond the noise: the locked fit with the network's spread as the prior
    (0.4, 3.0, 0.05, (), "locked_prior", "doubtful", "--method hybrid --locked --prior-sd 0.5"),
    (0.4, 1.0, 0.5, (), "keep", "imprecise", "--method hybrid --locked"),  # people-like
    (0.9, 1.0, 0.05, ("the body is outside",), "raw", "doubtful", "--method hybrid"),
    # one cycle (no locked share): as good as the noise, kept; a longer recording named
    (None, 1.0, 0.3, (), "keep", "imprecise", "a longer recording (more stimulus cycles to "
     "average): its noise alone leaves 30 % of the locked sway, so no answer can be checked "
     "to 10 %; for sway without motor noise (a robot's), --method hybrid"),
    (None, 3.0, 0.3, (), "raw", "doubtful", "--method hybrid"),  # more than the noise leaves
])
def test_auto_refines_an_answer_on_the_sway_that_suits_it(share, ratio, noise_relative,
                                                          outside, how, level, suggested):
    from posture_id.identify.core import auto_refinement
    from posture_id.identify.noise_check import NoiseCheck
    from posture_id.identify.verdict import TrustVerdict, suggestion

    noise = NoiseCheck(ratio, "locked", 0.001, relative=max(noise_relative, 0.2) * ratio,
                       noise_relative=noise_relative)
    verdict = TrustVerdict(noise, (), outside, share)
    assert verdict.level.value == level
    assert verdict.doubtful == (level == "doubtful")
    assert auto_refinement(verdict).value == how
    line = suggestion(Method.CNN, False, share, (), noise, network_reads_people_like=True)
    assert line.startswith(suggested)
    # a mistake in the recording: no fit can be right about it, so none is tried
    assert auto_refinement(replace(verdict, mistakes=("a step",))).value == "keep"
    assert auto_refinement(TrustVerdict(None, (), (), share)).value == "keep"


def test_an_answer_the_recording_does_not_pin_is_imprecise_and_says_what():
    from posture_id.identify.noise_check import NoiseCheck
    from posture_id.identify.verdict import TrustLevel, TrustVerdict

    close = NoiseCheck(1.1, "locked", 0.001, relative=0.03, noise_relative=0.02)
    assert TrustVerdict(close).level is TrustLevel.GOOD
    verdict = TrustVerdict(close, unpinned=("the hip's Kd", "the hip's class (P(com) 0.62)"))
    assert verdict.level is TrustLevel.IMPRECISE and not verdict.doubtful
    assert verdict.line() == (
        "trust: imprecise: the recording does not pin the hip's Kd and the hip's class "
        "(P(com) 0.62) (to ±10 %): nothing says the answer is wrong; its intervals give "
        "the precision")
    beyond = NoiseCheck(4.0, "locked", 0.001, relative=0.3, noise_relative=0.02)
    doubtful = replace(verdict, noise=beyond)
    assert doubtful.level is TrustLevel.DOUBTFUL and doubtful.imprecision == ()
    assert doubtful.to_dict()["level"] == "doubtful" and doubtful.to_dict()["doubtful"]


def test_classes_the_network_gives_less_than_four_in_five_together_make_the_answer_doubtful():
    """A class at P(com) 0.62 is named as unpinned; the product of the chosen classes'
    probabilities below CLASSES_RIGHT_AT_LEAST makes the answer doubtful and says why,
    above it the answer stays imprecise; the JSON carries the sentence."""
    from posture_id.identify.noise_check import NoiseCheck
    from posture_id.identify.verdict import (
        CLASSES_RIGHT_AT_LEAST,
        TrustLevel,
        TrustVerdict,
        class_doubts,
    )

    joints = ("ankle", "knee", "hip")
    sure = class_doubts(joints, [0.001, 0.999, 0.99])
    assert sure == ((), "")
    unsure, doubt = class_doubts(joints, [0.001, 0.9, 0.99])  # 0.999 · 0.9 · 0.99 ≈ 0.89
    assert unsure == ("the knee's class (P(com) 0.90)",) and doubt == ""
    unsure, doubt = class_doubts(joints, [0.001, 0.62, 0.99])  # ≈ 0.61 together
    assert unsure == ("the knee's class (P(com) 0.62)",)
    assert "the network cannot tell the knee's class (P(com) 0.62)" in doubt
    assert "all right only 61 %" in doubt
    _, two = class_doubts(joints, [0.15, 0.999, 0.12])  # each sure enough, together not
    assert 0.85 * 0.88 < CLASSES_RIGHT_AT_LEAST and two
    assert "the ankle's class (P(com) 0.15) and the hip's class (P(com) 0.12)" in two
    close = NoiseCheck(1.1, "locked", 0.001, relative=0.03, noise_relative=0.02)
    verdict = TrustVerdict(close, unpinned=unsure, classes_doubted=doubt)
    assert verdict.level is TrustLevel.DOUBTFUL and verdict.reasons == (doubt,)
    assert verdict.to_dict()["classes_doubted"] == doubt
    assert TrustVerdict(close, unpinned=unsure).level is TrustLevel.IMPRECISE


@pytest.mark.slow("the default method on people-like sway, 3 segments")
def test_the_default_command_doubts_an_answer_whose_class_the_network_cannot_tell(
        tip, monkeypatch):
    """Through ``identify`` (``auto``, the bundled universal network) on people-like sway:
    the network's hip logit set to 0.4 (P(com) about 0.6) makes the answer doubtful for that
    reason, named; the same recording as the network gives it is not doubtful for it."""
    from posture_id.learning.universal_model import UniversalModel

    subject = people_like(tip, default_parameters(tip), prts(), 0.3, seed=7)
    plain = identify(subject.recording, tip)
    assert not plain.verdict.classes_doubted
    predict = UniversalModel.predict

    def unsure_hip(self, inputs, *noise, **options):
        out = predict(self, inputs, *noise, **options)
        logit = out.logit.copy()
        logit[2::3] = 0.4  # the hip of each 3-segment trial
        return replace(out, logit=logit)

    monkeypatch.setattr(UniversalModel, "predict", unsure_hip)
    result = identify(subject.recording, tip)
    assert 0.55 < result.class_probability[2] < 0.65  # (through the calibrated temperature)
    assert result.verdict.doubtful
    named = f"the hip's class (P(com) {result.class_probability[2]:.2f})"
    assert result.verdict.classes_doubted.startswith("the network cannot tell ")
    assert named in result.verdict.classes_doubted and named in result.verdict.unpinned
    assert result.verdict.classes_doubted in result.verdict.reasons


def test_least_squares_that_stops_far_above_the_noise_is_doubtful_however_close():
    """A least-squares answer leaving more than FITTED_NOISE_LIMIT times the noise is
    doubtful though close to the sway; the network's answer keeps the closeness
    allowance, and a fit within the limit is not doubted for it."""
    from posture_id.identify.noise_check import NoiseCheck
    from posture_id.identify.verdict import FITTED_NOISE_LIMIT, TrustLevel, TrustVerdict

    close_far = NoiseCheck(FITTED_NOISE_LIMIT + 0.5, "locked", 0.001, relative=0.04,
                           noise_relative=0.01)
    assert TrustVerdict(close_far).level is TrustLevel.GOOD  # the network's answer
    fitted = TrustVerdict(close_far, fitted=True)
    assert fitted.level is TrustLevel.DOUBTFUL
    assert fitted.reasons[0].startswith("least squares leaves a stimulus-locked residual")
    assert "a fit of the right model reaches it" in fitted.reasons[0]
    near = NoiseCheck(FITTED_NOISE_LIMIT - 0.5, "locked", 0.001, relative=0.04,
                      noise_relative=0.01)
    assert not TrustVerdict(near, fitted=True).doubtful


@pytest.mark.slow("the hybrid's least squares, 2 segments")
def test_the_hybrid_on_exchanged_columns_is_doubted_for_the_noise_it_leaves(monkeypatch):
    """A 2-segment Winter recording at 0.02° with its two columns exchanged, through the
    hybrid: least squares ends close to the sway (4 % of it) but many times its noise,
    and is doubtful for it even with the exchanged-columns reading switched off; with the
    limit put back to the closeness allowance alone it passes. The same recording in
    order is not doubted."""
    import posture_id.identify.core as core
    import posture_id.identify.verdict as verdict_module
    from posture_id.dec.prior import sample_parameters
    from posture_id.learning.data.bodies import build_body
    from posture_id.learning.data.scope import BodyDraw

    body = build_body(BodyDraw("winter", 2, 1.75, 70.0, ((1.0, 1.0),) * 2))
    truth = sample_parameters(body, 1, np.random.default_rng(5)).trial(0, body.joint_names)
    right = simulate(body, truth, prts(1.5, 6, 80)).to_recording().with_sensor_noise(0.02, 5)
    theta = right.theta.copy()
    theta[:, [0, 1]] = theta[:, [1, 0]]
    exchanged = replace(right, theta=theta)
    monkeypatch.setattr(core, "better_explanations", lambda *a, **k: [])
    hybrid = Identifier(body, method=Method.HYBRID)
    found = hybrid.identify(exchanged).verdict
    assert found.noise.acceptable and found.fit_beyond_noise
    assert found.doubtful and any(r.startswith("least squares leaves") for r in found.reasons)
    assert not hybrid.identify(right).verdict.doubtful
    monkeypatch.setattr(verdict_module, "FITTED_NOISE_LIMIT", np.inf)
    assert not hybrid.identify(exchanged).verdict.doubtful
