"""A stimulus off the sway's clock, as a lab's real PRTS recording has it: a COM-only
recording of people-like sway, an 80-state PRTS × 3 started part-way into its sequence,
its tilt column seconds from where the sway says the platform ran. The files are made
here from simulated sway; benchmarks/prts_timing.py measures the same over many."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from posture_id.bodies.anthropometry import straight_links, winter_segments
from posture_id.bodies.body import load_body
from posture_id.bodies.urdf_writer import write_chain_urdf
from posture_id.dec.parameters import default_parameters
from posture_id.errors import RecordingError
from posture_id.frf.locked import LockedOptions, LockedProjection
from posture_id.identify import identify
from posture_id.identify.noise_check import Basis, NoiseCheck
from posture_id.identify.verdict import TrustVerdict
from posture_id.learning.features.harmonics import harmonic_layout
from posture_id.recording import Recording
from posture_id.simulation.batch import simulate
from posture_id.simulation.stimulus import prts
from posture_id.simulation.subjects import people_like
from posture_id.trials import prepare_trial

LAB_PRTS = dict(amplitude_deg=1.0, cycles=3, states=80, onset_s=5.0, start_state=31.5)
TAIL_S = 5.0


@pytest.fixture(scope="module")
def subject(tmp_path_factory):
    """(body, its parameters, the stimulus as run): a lab's 1-segment subject."""
    folder = tmp_path_factory.mktemp("timing")
    urdf = write_chain_urdf(folder / "subject.urdf", "subject",
                            straight_links(winter_segments(1.72, 68.0, 1)))
    body = load_body(urdf)
    truth = default_parameters(body)
    joint = body.joint_names[0]
    truth = truth.replace(joint, kp=1.2 * truth[joint].kp)
    stimulus = prts(**LAB_PRTS)
    return body, truth, stimulus.spanning(stimulus.duration + TAIL_S)


def _recording(subject, shift_s: float, seed: int) -> Recording:
    """People-like sway (a third of it locked), its tilt column ``shift_s`` later than
    the platform moved (earlier when negative)."""
    body, truth, stimulus = subject
    rec = people_like(body, truth, stimulus, 0.33, seed, sensor_noise_deg=0.02).recording
    return replace(rec, tilt=stimulus.angle(rec.time - shift_s))


def test_a_shift_either_way_analyses_the_moved_stimulus_own_cycles(subject):
    """A stimulus of three cycles moved earlier than its lead-in: the first cycle now
    starts before the recording, so two are analysed, and their window holds no level
    platform (before, the window kept the three cycles' place and ended on the level
    rest, where the tilt does not repeat: the network read NaN)."""
    body, truth, stimulus = subject
    trial = prepare_trial(simulate(body, truth, stimulus).to_recording())
    for offset in (-6.0, -2.0, 2.0):
        shifted = trial.shifted_whole(offset)
        moved = shifted.stimulus
        begins = trial.stimulus.periodic_from_s + offset
        assert moved.periodic_from_s == pytest.approx(begins if begins >= 0
                                                      else begins + moved.period_s)
        assert moved.cycles == (2 if begins < 0 else 3)
        projection = LockedProjection.for_trial(shifted, LockedOptions(weighted=False))
        assert not projection.excited.all()  # the tilt repeats: harmonics left empty
        layout = harmonic_layout(shifted.recording.tilt, shifted.rate_hz, moved.period_s,
                                 moved.periodic_from_s, "moved", moved.cycles)
        assert not layout.excited.all()


def test_a_window_where_the_tilt_does_not_repeat_is_refused_naming_it():
    """A tilt that does not repeat over the cycles named leaves no harmonic empty to
    estimate the noise from: refused (before, the network's noise levels were the mean
    of nothing, and its answer NaN)."""
    wander = np.random.default_rng(1).standard_normal(3000) * 1e-3  # power everywhere
    with pytest.raises(RecordingError, match=r"late\.csv: the tilt over the 3 cycle\(s\).*"
                                             r"does not repeat"):
        harmonic_layout(wander, 50.0, 20.0, 0.0, "late.csv", 3)


@pytest.mark.slow("the default method's timing search, 1 segment")
@pytest.mark.parametrize("shift_s, seed", [(2.2, 11), (-3.1, 12)])
def test_the_default_command_finds_a_tilt_column_seconds_off_the_sways_clock(
        subject, shift_s, seed):
    """Before, the default answered at the column's timing, doubtful or imprecise with a
    residual the noise hid, and never searched (the answer was not beyond the noise)."""
    body, _, _ = subject
    result = identify(_recording(subject, shift_s, seed), body)
    assert result.stimulus_offset_s == pytest.approx(-shift_s, abs=0.05)
    moved = [n for n in result.notices if "the sway says the stimulus ran" in n]
    assert moved and "check the tilt column's timing" in moved[0]
    assert result.verdict.noise.consistent or "--max-offset-s" in result.verdict.line()


@pytest.mark.slow("the default method's timing search, 1 segment")
def test_a_rightly_timed_people_like_recording_is_not_moved(subject):
    body, _, _ = subject
    result = identify(_recording(subject, 0.0, 13), body)
    assert result.stimulus_offset_s == 0.0
    assert not any("the sway says" in n for n in result.notices)


@pytest.mark.slow("the default method's timing search, 1 segment")
def test_a_wrong_prts_named_is_not_moved_by_half_a_cycle(subject):
    """The 80-state PRTS recorded without its tilt, named as the 242-state one: half a
    cycle on, a PRTS is its own negative, and no shift is taken for its timing; the
    verdict names the stimulus as what to check (before, moved 30 s and called
    "imprecise")."""
    body, truth, stimulus = subject
    rec = simulate(body, truth, stimulus).to_recording().with_sensor_noise(0.02, 4)
    named = prts(1.0, cycles=1, states=242).spanning(rec.duration_s)
    result = identify(replace(rec, tilt=named.angle(rec.time), tilt_recorded=False), body,
                      stimulus=named)
    assert abs(result.stimulus_offset_s) <= named.period_s / 4
    assert result.verdict.doubtful
    line = result.verdict.line()
    assert "--states" in result.verdict.suggestion or "the stimulus's sign" in line, line


def test_the_verdict_says_which_measure_decides_and_why_they_seem_to_disagree():
    """The lab's case: 31.9 % of the locked sway where the noise alone leaves 49 %, yet
    2.06× the noise: the residual lies at the quiet harmonics, and the clause says so."""
    quiet = NoiseCheck(2.06, Basis.LOCKED, 0.01, relative=0.319, noise_relative=0.49)
    sentence = quiet.sentence()
    assert sentence.startswith("stimulus-locked residual of 2.06× the recording's own noise "
                               "(beyond the 1.5× the noise allows)")
    assert "31.9 %" in sentence and "49 %" in sentence
    assert "harmonics where the noise is small" in sentence
    agreeing = NoiseCheck(2.06, Basis.LOCKED, 0.01, relative=0.9, noise_relative=0.4)
    assert agreeing.weighting_note() == ""
    loud = NoiseCheck(0.8, Basis.LOCKED, 0.01, relative=0.9, noise_relative=0.4)
    assert "where the noise is large" in loud.sentence()


def test_a_delay_on_its_lower_bound_is_said_to_be_the_search_edge():
    noise = NoiseCheck(0.9, Basis.LOCKED, 0.01, relative=0.4, noise_relative=0.5)
    verdict = TrustVerdict(noise, on_bounds=("ankle delay_s at its lower bound (0)",),
                           fitted=True)
    line = verdict.line()
    assert "ankle delay_s at its lower bound (0)" in line
    assert "the search's edge, not the subject's delay" in line
    assert not verdict.doubtful  # a delay on its bound is what the recording leaves open


def test_the_smoothest_frf_offset_finds_a_clean_shift(subject):
    """The model-free start of the timing search: within a few tenths of a second of a
    4 s shift on noise-free sway (the body's own group delay is what is left)."""
    body, truth, stimulus = subject
    rec = simulate(body, truth, stimulus).to_recording()
    rec = replace(rec, tilt=stimulus.angle(rec.time - 4.0))
    trial = prepare_trial(rec.with_sensor_noise(0.01, 3))
    projection = LockedProjection.for_trial(trial, LockedOptions())
    found = projection.smoothest_offset(np.degrees(trial.recording.theta),
                                        np.degrees(trial.recording.tilt), 5.0)
    assert found == pytest.approx(-4.0, abs=0.5)
