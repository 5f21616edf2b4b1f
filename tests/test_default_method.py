"""Every recording gets an answer from the default method, and the answer's trust is one of
three levels: a network answer that falls is refined on the locked sway with the network's
spread as the prior; when nothing balances the body the best answer is still written,
doubtful, and the command says so by its exit status (1, its answer written)."""

from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pytest

from posture_id.dec.parameters import default_parameters, normalise
from posture_id.fitting.evaluators import run_stage
from posture_id.fitting.options import FitError, FitOptions
from posture_id.frf.locked import LockedOptions
from posture_id.identify import Identifier, Method, identify
from posture_id.identify.core import network_prior
from posture_id.learning.universal_identifier import UniversalIdentifier
from posture_id.simulation import prts
from posture_id.simulation.subjects import people_like


@pytest.fixture(scope="module")
def subject(tip):
    return people_like(tip, default_parameters(tip), prts(states=80, cycles=3), 0.25, seed=12)


@pytest.fixture
def network_that_falls(monkeypatch, tip):
    """The bundled network with its ankle Kp cut to a twentieth: an answer that falls."""
    original = UniversalIdentifier.identify

    def falling(self, trial, level=0.9):
        answer = original(self, trial, level)
        weak = answer.parameters.replace("ankle", kp=answer.parameters["ankle"].kp / 20)
        normalised = np.array(answer.normalised, dtype=float)
        normalised[:, :4] = normalise(weak, default_parameters(self.body))[:, :4]
        return replace(answer, parameters=weak, normalised=normalised)

    monkeypatch.setattr(UniversalIdentifier, "identify", falling)


@pytest.mark.slow("least squares from the defaults, 3 segments")
def test_a_fallen_network_answer_on_people_like_sway_still_gets_an_answer(
        tip, subject, network_that_falls):
    """Refined on the locked sway with the network's spread as the prior; that starts
    from an answer so far off that it falls too, so least squares from the defaults with
    docs/model.md §5's prior answers."""
    alone = identify(subject.recording, tip, Method.CNN)
    assert alone.fell and alone.verdict.doubtful
    result = identify(subject.recording, tip)  # auto
    assert not result.fell
    assert any("with the network's spread as the prior" in n for n in result.notices)
    assert any("fitted again from the body's defaults" in n for n in result.notices)
    assert result.method is Method.FIT and result.verdict.level.value != "doubtful"


def test_when_nothing_balances_the_body_the_longest_standing_answer_is_given(
        tip, subject, network_that_falls, monkeypatch):
    from posture_id.identify.core import Step

    original = Identifier._identify

    def hybrid_falls_too(self, trial, step, progress=None, start=None, answer=None):
        # stand-ins for auto's refinement and fit from the defaults, that fall too
        if step.method in (Method.HYBRID, Method.FIT):
            network = original(self, trial, Step(Method.CNN, self.fit_options), progress,
                               start)
            later = 1.0 if step.method is Method.HYBRID else 0.5
            return replace(network, method=step.method, fell_at_s=network.fell_at_s + later)
        return original(self, trial, step, progress, start, answer)

    monkeypatch.setattr(Identifier, "_identify", hybrid_falls_too)
    result = identify(subject.recording, tip)
    assert result.fell and result.verdict.doubtful and result.method is Method.HYBRID
    assert any("the one that stays up longest is given, doubtful" in n
               for n in result.notices)
    # the line it ends with does not suggest what auto has tried already
    assert result.fell_line().startswith("the identified model falls in re-simulation at t")
    assert "no model tried balances" in result.fell_line()
    assert "try --method hybrid" not in result.summary()


def test_the_command_writes_a_fallen_answer_and_exits_1(tip, subject, network_that_falls,
                                                        tmp_path):
    from posture_id.cli import main
    from posture_id.cli.exit_status import DOUBTFUL

    path = tmp_path / "subject.csv"
    subject.recording.to_csv(path)
    out = tmp_path / "result.json"
    status = main(["identify", str(path), "--method", "cnn", "--out", str(out)])
    assert status == DOUBTFUL == 1
    data = json.loads(out.read_text())
    assert data["trust"]["level"] == "doubtful" and data["trust"]["doubtful"]
    assert data["parameters"]["ankle"]["kp"] > 0


def test_people_like_right_answers_are_imprecise_not_doubtful(tip, subject):
    """Two cycles of people-like sway cannot check an answer to 10 %: that is precision,
    not evidence of a wrong answer."""
    result = identify(subject.recording, tip)
    verdict = result.verdict
    assert verdict.level.value == "imprecise", verdict.line()
    assert not verdict.doubtful and verdict.imprecision
    assert verdict.line().startswith("trust: imprecise: its noise alone leaves about")
    data = json.loads(json.dumps(result.to_dict(), allow_nan=False))
    assert data["trust"]["level"] == "imprecise" and data["trust"]["doubtful"] is False
    assert data["trust"]["imprecise"] == list(verdict.imprecision)


def test_the_network_prior_is_its_answer_and_calibrated_spread(tip, subject):
    answer = identify(subject.recording, tip, Method.CNN)
    prior = network_prior(answer, 0.9)
    n = tip.n_segments
    centre = np.array(prior["prior_centre"]).reshape(4, n).T  # field-major, as q
    np.testing.assert_allclose(centre, answer.normalised[:, :4])
    sd = np.array(prior["prior_sd"]).reshape(4, n).T
    half = (answer.intervals.upper - answer.intervals.lower) / 2
    np.testing.assert_allclose(np.maximum(half / 1.6448536269514722, 0.05), sd, rtol=1e-9)
    options = FitOptions(locked=LockedOptions(), **prior)
    assert options.prior_centre == prior["prior_centre"]
    with pytest.raises(FitError, match="prior_centre needs prior_sd"):
        FitOptions(locked=LockedOptions(), prior_centre=prior["prior_centre"])


def test_a_stage_with_a_centred_prior_finds_the_weighted_mean():
    """One unknown, data a with unit noise, prior N(c, s²): the MAP estimate is
    (a + c/s²)/(1 + 1/s²), exactly."""

    class Toy:
        def residual(self, q):
            return np.array([q[0] - 2.0])

        def jacobian(self, q, free, r):
            return np.ones((1, len(free)))

    c, s = 0.5, 0.5
    stage = run_stage("toy", Toy(), np.zeros(1), [0], np.array([-10.0]), np.array([10.0]),
                      1e-14, 50, prior_sd=np.array([s]), prior_centre=np.array([c]))
    assert stage.q[0] == pytest.approx((2.0 + c / s**2) / (1 + 1 / s**2), abs=1e-8)


@pytest.mark.slow("the hybrid's least squares, 3 segments")
def test_a_fit_from_the_network_s_prior_claims_no_more_than_the_network(tip, subject,
                                                                       monkeypatch):
    """The locked fit from the network's answer with its spread as the prior (what ``auto``
    refines people-like sway with) has intervals no narrower than the network's
    calibrated ones, each centred on the fit's answer. Without that floor its own
    Gauss-Newton intervals are narrower than the network's here (they assume a white
    residual, which the noise of people-like sway is not); a fit without the network's
    prior keeps its own."""
    import posture_id.identify.core as core

    answer = identify(subject.recording, tip, Method.CNN)
    network_half = (answer.intervals.upper - answer.intervals.lower) / 2
    locked = FitOptions(locked=LockedOptions())
    own = identify(subject.recording, tip, Method.HYBRID, fit_options=locked)
    assert "no narrower" not in own.intervals.method
    prior = replace(locked, **network_prior(answer, 0.9))
    refined = identify(subject.recording, tip, Method.HYBRID, fit_options=prior)
    assert "no narrower than the network's calibrated intervals" in refined.intervals.method
    half = (refined.intervals.upper - refined.intervals.lower) / 2
    assert np.all(half >= network_half - 1e-12)
    estimate = refined.normalised[:, :4]
    np.testing.assert_allclose(refined.intervals.upper[:, 0] - estimate[:, 0], half[:, 0],
                               rtol=1e-9, err_msg="Kp's centred on the fit's answer")
    monkeypatch.setattr(core, "_network_floor", lambda *args: {})
    unfloored = identify(subject.recording, tip, Method.HYBRID, fit_options=prior)
    unfloored_half = (unfloored.intervals.upper - unfloored.intervals.lower) / 2
    assert np.any(unfloored_half[:, 0] < 0.5 * network_half[:, 0])
