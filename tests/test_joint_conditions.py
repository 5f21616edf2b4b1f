"""One subject, several trials: the joint fit with shared and per-condition parameters
(posture_id.fitting.joint_conditions), for the IC model, DEC and a third model, through the
command line, and fit_frequency_parts as its special case with the answers of the code
it replaced."""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from posture_id.bodies.body import load_body
from posture_id.cli import main
from posture_id.errors import PostureIdError
from posture_id.fitting.evaluators import Evaluator
from posture_id.fitting.frequency import FrequencyFitOptions
from posture_id.fitting.joint import ConditionEvaluator
from posture_id.fitting.joint_conditions import JointFit, fit_joint
from posture_id.fitting.models import fit_frequency_parts, fit_ic_parts
from posture_id.models.ic import IC, IcParameters, IcPlant
from posture_id.models.ic.simulation import simulate_ic
from posture_id.models.ic.subjects import draw_ic_parameters, ic_recording
from posture_id.models.protocol import TrustLevel
from posture_id.simulation.options import SimulationOptions
from posture_id.simulation.protocols import SumOfSinesProtocol
from posture_id.simulation.stimulus import prts
from posture_id.trials import prepare_trial

ROOT = Path(__file__).resolve().parents[1]
WINTER1 = ROOT / "urdf" / "winter_1.75m_70kg_1seg.urdf"
#: eyes open / closed: vision gone, the proprioceptive weight W rises
WEIGHTS = {"eyes open": 0.4, "eyes closed": 0.7}
FINE = SimulationOptions(dt=0.0005)


@pytest.fixture(scope="module")
def body():
    return load_body(WINTER1)


def _sine_trials(body, truth: IcParameters, seed: int, motor_deg: float = 0.0):
    """Three sinusoid trials per condition (0.1, 0.2, 0.4 Hz, 2° peak to peak, 40 s: 4, 8
    and 16 cycles), the stimulus given to prepare_trial; (trials, labels) or None where
    the sway makes the subject fall."""
    trials, labels = [], []
    for c, (condition, w) in enumerate(WEIGHTS.items()):
        for j, f in enumerate((0.1, 0.2, 0.4)):
            profile = SumOfSinesProtocol(frequencies_hz=(f,), amplitudes_deg=(1.0,),
                                         cycles=int(round(40 * f))).profile()
            noise_seed = 100 * seed + 10 * c + j
            # ic_recording's sway (motor noise through the loop, white sensor noise), at a
            # quarter of the 2 ms step: clean sway would otherwise see the Euler step's bias
            recording = simulate_ic(body, truth.replace(w=w), profile, FINE,
                                    motor_sd_deg=motor_deg, seed=noise_seed
                                    ).with_sensor_noise(0.05 if motor_deg else 0.02,
                                                        noise_seed)
            if not np.all(np.isfinite(recording.theta)):
                return None
            recording = replace(recording, name=f"{condition} {f:g} Hz")
            trials.append(prepare_trial(recording, stimulus=profile, rate_hz=50.0))
            labels.append(condition)
    return trials, labels


def _subjects(body, count: int, people_like: bool, seed: int):
    """``count`` IC subjects (shared Kp, Kd, Δ and torque feedback drawn by
    draw_ic_parameters) with their six trials; people-like: the motor noise that leaves
    15–40 % of the sway locked on a people-like PRTS trial (ic_recording's level), the
    same on every trial (as benchmarks/joint_fit.py)."""
    plant = IcPlant.of(body)
    rng = np.random.default_rng(seed)
    out = []
    while len(out) < count:
        truth = draw_ic_parameters(rng, plant)
        level = 0.0
        if people_like:
            _, level = ic_recording(body, truth.replace(w=0.4), prts(1.0, 3, 80),
                                    float(rng.uniform(0.15, 0.4)), len(out) + seed)
        made = _sine_trials(body, truth, len(out) + seed, level)
        if made is not None:
            out.append((truth, *made))
    return out


def test_ic_subjects_shared_parameters_and_w_per_condition_recovered(body):
    """Three subjects, two conditions (W 0.4 and 0.7), three sinusoid trials each, clean
    sway: the shared Kp, Kd, Δ within 10 % (median over the subjects) and each W within
    0.05, its interval narrower than ±0.05; the JSON is strict and complete."""
    errors = {n: [] for n in ("kp", "kd", "delay_s")}
    for truth, trials, labels in _subjects(body, 3, False, 11):
        fit = fit_joint(IC, trials, body, labels, ("w",))
        assert isinstance(fit, JointFit) and fit.conditions == tuple(WEIGHTS)
        assert set(fit.shared) == {"kp", "kd", "delay_s", "torque_feedback_gain",
                                   "torque_feedback_time_s"}
        for name in errors:
            errors[name].append(abs(fit.shared[name] / getattr(truth, name) - 1))
        for condition, w in WEIGHTS.items():
            assert fit.per_condition[condition]["w"] == pytest.approx(w, abs=0.05)
            low, high = fit.intervals["per_condition"][condition]["w"]
            assert 0 < high - low < 0.1  # a 90 % interval: it misses one time in ten
            assert fit.parameters[condition].w == fit.per_condition[condition]["w"]
            assert fit.parameters[condition].kp == fit.shared["kp"]
        assert fit.consistent and fit.trust_level is not TrustLevel.DOUBTFUL
        assert min(fit.explained) > 0.95
        data = json.loads(fit.to_json())
        assert data["model"] == "ic" and set(data["per_condition"]) == set(WEIGHTS)
        assert [t["condition"] for t in data["trials"]] == labels
        assert [t["name"] for t in data["trials"]] == [t.name for t in trials]
        assert set(data["intervals"]["shared"]) == set(fit.shared)
        assert data["trust"]["level"] == fit.trust_level.value
    for name, values in errors.items():
        assert np.median(values) < 0.10, (name, values)


def test_people_like_sway_is_honest_about_what_three_sines_pin(body):
    """People-like sway on the same design, six subjects: Kp within 10 % (median), W rises
    from eyes open to closed for every one; but three sinusoids cannot pin Kd and Δ to
    10 % (docs/fit.md), and the answer says so: never "good". The intervals are not
    collapsed: they hold most truths (their coverage, 85–95 %, is measured on 48 subjects
    by benchmarks/joint_fit.py; six subjects' misses come a subject at a time)."""
    inside, total, rises, kp = 0, 0, 0, []
    for truth, trials, labels in _subjects(body, 6, True, 23):
        fit = fit_joint(IC, trials, body, labels, ("w",))
        assert fit.trust_level is not TrustLevel.GOOD, fit.summary()
        kp.append(abs(fit.shared["kp"] / truth.kp - 1))
        for name, (low, high) in fit.intervals["shared"].items():
            inside += low <= getattr(truth, name) <= high
            total += 1
        for condition, w in WEIGHTS.items():
            low, high = fit.intervals["per_condition"][condition]["w"]
            inside += low <= w <= high
            total += 1
        rises += fit.per_condition["eyes closed"]["w"] > fit.per_condition["eyes open"]["w"]
    assert np.median(kp) < 0.10, kp
    assert rises == 6
    assert inside >= 0.7 * total, (inside, total)


def test_the_plot_shows_every_trial_and_each_conditions_model(body, tmp_path):
    truth, trials, labels = _subjects(body, 1, False, 5)[0]
    fit = fit_joint(IC, trials, body, labels, ("w",))
    fig = fit.plot(tmp_path / "joint.png")
    assert (tmp_path / "joint.png").stat().st_size > 0
    gain = fig.axes[0]
    # one curve per condition, one set of points per trial
    assert len(gain.lines) == len(WEIGHTS) + len(trials)
    text = fit.summary()
    assert "eyes open:" in text and "eyes closed:" in text and "trust:" in text


def test_every_parameter_shared_and_a_bad_call_refused(body):
    truth, trials, labels = _subjects(body, 1, False, 5)[0]
    shared = fit_joint(IC, trials[:3], body, labels[:3])  # one condition, nothing per it
    assert shared.per_condition == {"eyes open": {}}
    assert shared.shared["w"] == pytest.approx(WEIGHTS["eyes open"], abs=0.05)
    with pytest.raises(PostureIdError, match="5 condition label.*6 trial"):
        fit_joint(IC, trials, body, labels[:5], ("w",))
    with pytest.raises(PostureIdError, match="'ankle.kp'.*its parameters: kp, kd"):
        fit_joint(IC, trials, body, labels, ("ankle.kp",))


# the answers of fit_frequency_parts before it became fit_joint's special case, recorded on
# the code it replaced (two parts clean, three parts people-like with three starts)
_BEFORE = {
    "two_clean": ([{"kp": 1179.8654016630735, "kd": 262.89531193390013,
                    "delay_s": 0.15067551000513038, "w": 0.5999891724745209,
                    "torque_feedback_gain": 0.20604143769463804,
                    "torque_feedback_time_s": 15.475411807623281},
                   {"w": 0.3497772042408239}], 8.444039313248693, 7),
    "three_people": ([{"kp": 1017.243854933917, "kd": 263.65894594843644,
                       "delay_s": 0.1622702280136471, "w": 0.4377003642100626,
                       "torque_feedback_gain": 2.6778154751584925e-30,
                       "torque_feedback_time_s": 99.99999999999994},
                      {"w": 0.32955129074636436}, {"w": 0.22760604434000983}],
                     127.83502204475496, 8),
}


def _parts(body, ws, amplitudes, share):
    plant = IcPlant.of(body)
    truth = IcParameters(kp=1.8 * plant.mgh, kd=0.4 * plant.mgh, delay_s=0.15, w=0.6,
                         torque_feedback_gain=0.2, torque_feedback_time_s=15.0)
    trials = []
    for part, (amplitude, w) in enumerate(zip(amplitudes, ws, strict=True), 1):
        stimulus = prts(amplitude, cycles=2, states=80)
        recording, _ = ic_recording(body, truth.replace(w=w), stimulus, share, part)
        trials.append(prepare_trial(recording, stimulus))
    return trials


@pytest.mark.parametrize("case", sorted(_BEFORE))
def test_fit_frequency_parts_answers_as_before(case, body):
    if case == "two_clean":
        fit = fit_ic_parts(_parts(body, (0.6, 0.35), (1.0, 3.0), None), body)
    else:
        fit = fit_frequency_parts(IC, _parts(body, (0.6, 0.45, 0.3), (1.0, 2.0, 3.0), 0.4),
                                  body, FrequencyFitOptions(starts=3, seed=5))
    parts, chi2, count = _BEFORE[case]
    assert isinstance(fit, JointFit) and len(fit.parameters) == len(parts)
    # the values were recorded on another processor: the clean fit lands on the same
    # digits, the people-like one (its torque feedback on a bound, a flat valley) stops
    # within the search's own precision of them, a few 1e-6 relative on an AMD EPYC here
    # (its standard errors are percent-level), the objective the same within 1e-9
    rel = 1e-9 if case == "two_clean" else 2e-5
    for got, want in zip(fit.parameters.values(), parts, strict=True):
        for name, value in {**parts[0], **want}.items():
            assert getattr(got, name) == pytest.approx(value, rel=rel, abs=1e-12), name
    assert fit.chi2 == pytest.approx(chi2, rel=1e-9)
    assert fit.identified_count == count
    assert fit.w_by_part == tuple(p.w for p in fit.parameters.values())


class _Linear(Evaluator):
    """residual(q) = A·q − b: a stand-in for a trial's evaluator."""

    def __init__(self, a: np.ndarray, b: np.ndarray) -> None:
        super().__init__(np.zeros((0, 0)))
        self.a, self.b = a, b

    def residual(self, q):
        return self.a @ q - self.b

    def jacobian(self, q, free, residual):
        return self.a[:, free]


def test_the_condition_evaluator_reads_and_differentiates_the_extended_unknowns():
    """Shared unknowns read by every trial, per-condition ones by their condition's only;
    its Jacobian equals finite differences; with nothing per condition it is the joint
    evaluator of the shared polish, every trial's residual and Jacobian stacked."""
    rng = np.random.default_rng(0)
    parts = [_Linear(rng.normal(size=(5, 4)), rng.normal(size=5)) for _ in range(3)]
    joint = ConditionEvaluator(parts)  # every unknown shared
    q = rng.normal(size=4)
    stacked = np.concatenate([p.residual(q) for p in parts])
    assert np.array_equal(joint.residual(q), stacked)
    assert np.array_equal(joint.jacobian(q, [0, 2, 3], stacked),
                          np.vstack([p.a[:, [0, 2, 3]] for p in parts]))
    by = ConditionEvaluator(parts, [0, 1, 1], (2,), 4)
    x = by.extended(q, 2)
    x[4] += 0.5  # condition 1's own value of unknown 2
    assert np.array_equal(by.q_of(x, 0), q)
    assert by.q_of(x, 1)[2] == q[2] + 0.5
    free = [0, 1, 2, 3, 4]
    r = by.residual(x)
    jac = by.jacobian(x, free, r)
    step = 1e-6
    numeric = np.column_stack([(by.residual(x + step * np.eye(5)[k]) - r) / step
                               for k in free])
    assert np.allclose(jac, numeric, atol=1e-6)
    assert np.all(jac[:5, 4] == 0) and np.all(jac[5:, 2] == 0)


def test_a_third_model_fits_jointly_through_the_protocol(body):
    """The PD model of tests/pd_model.py, its Kp per condition, knows nothing of the joint
    fit: fitted through the model protocol alone."""
    from pd_model import PD, PdParameters

    plant = PD.plant(body)
    truth = {"a": 1.6 * plant.mgh, "b": 2.2 * plant.mgh}
    trials, labels = [], []
    for k, (label, kp) in enumerate(truth.items()):
        params = PdParameters(kp=kp, kd=0.35 * plant.mgh, delay_s=0.12)
        stimulus = prts(1.0, 2, 80)
        recording = PD.simulate(body, params, stimulus).with_sensor_noise(0.02, k)
        trials.append(prepare_trial(replace(recording, name=f"pd {label}"), stimulus))
        labels.append(label)
    fit = fit_joint(PD, trials, body, labels, ("kp",))
    for label, kp in truth.items():
        assert fit.per_condition[label]["kp"] == pytest.approx(kp, rel=0.03)
    assert set(fit.shared) == {"kd", "delay_s"}
    json.loads(fit.to_json())


def test_dec_ankle_kp_per_condition(body):
    """A DEC subject whose ankle Kp is 30 % higher on foam than on a firm platform, two
    PRTS trials per condition (1° and 2°): one joint fit finds both Kp within 2 % and
    the shared Kd and delay within 10 %; the untouched shared fit stays DEC's
    fit_recordings_jointly."""
    from posture_id.dec.parameters import default_parameters
    from posture_id.models.dec import DEC

    defaults = default_parameters(body)
    truth = {"firm": defaults["ankle"].kp, "foam": 1.3 * defaults["ankle"].kp}
    trials, labels = [], []
    for c, (label, kp) in enumerate(truth.items()):
        params = defaults.replace("ankle", kp=kp)
        for j, amplitude in enumerate((1.0, 2.0)):
            stimulus = prts(amplitude, 2, 80)
            recording = DEC.simulate(body, params, stimulus).with_sensor_noise(0.02, 10 * c + j)
            trials.append(prepare_trial(replace(recording, name=f"{label} {amplitude:g}°"),
                                        stimulus))
            labels.append(label)
    fit = fit_joint(DEC, trials, body, labels, ("ankle.kp",))
    for label, kp in truth.items():
        assert fit.per_condition[label]["ankle.kp"] == pytest.approx(kp, rel=0.02)
        assert fit.parameters[label]["ankle"].kp == fit.per_condition[label]["ankle.kp"]
    assert fit.shared["ankle.kd"] == pytest.approx(defaults["ankle"].kd, rel=0.1)
    assert fit.shared["ankle.delay_s"] == pytest.approx(defaults["ankle"].delay_s, rel=0.1)
    assert "ankle.kp" not in fit.shared and fit.consistent
    data = json.loads(fit.to_json())
    assert data["model"] == "dec" and data["per_condition"]["foam"]["ankle.kp"] > 0
    with pytest.raises(PostureIdError, match="ankle.kp, ankle.ki, ankle.kd, ankle.delay_s"):
        fit_joint(DEC, trials, body, labels, ("knee.kp",))


@pytest.fixture(scope="module")
def ic_csvs(tmp_path_factory, body):
    """Four IC recordings of one subject: two 80-state PRTS trials (1° and 2°) with W 0.4,
    two with W 0.7."""
    folder = tmp_path_factory.mktemp("joint")
    plant = IcPlant.of(body)
    truth = IcParameters(kp=1.8 * plant.mgh, kd=0.4 * plant.mgh, delay_s=0.15, w=0.4,
                         torque_feedback_gain=0.2, torque_feedback_time_s=15.0)
    paths = []
    for c, w in enumerate((0.4, 0.7)):
        for j, amplitude in enumerate((1.0, 2.0)):
            recording = simulate_ic(body, truth.replace(w=w), prts(amplitude, 3, 80), FINE
                                    ).with_sensor_noise(0.02, 10 * c + j)
            path = folder / f"w{c}_{j}.csv"
            recording.to_csv(path)
            paths.append(str(path))
    return folder, paths


def test_the_command_fits_several_recordings_jointly(ic_csvs, tmp_path, capsys):
    folder, paths = ic_csvs
    out, plot = tmp_path / "joint.json", tmp_path / "joint.png"
    assert main(["fit", *paths, "--model", "ic", "--body", str(WINTER1), "--per-trial", "W",
                 "--conditions", "open", "open", "closed", "closed", "--out", str(out),
                 "--plot", str(plot)]) == 0
    data = json.loads(out.read_text())
    assert data["model"] == "ic"
    assert data["per_condition"]["open"]["w"] == pytest.approx(0.4, abs=0.03)
    assert data["per_condition"]["closed"]["w"] == pytest.approx(0.7, abs=0.03)
    assert [t["condition"] for t in data["trials"]] == ["open", "open", "closed", "closed"]
    assert plot.stat().st_size > 0
    assert "closed:" in capsys.readouterr().out
    # without --per-trial every parameter is shared; each recording its own condition
    assert main(["fit", *paths[:2], "--model", "ic", "--body", str(WINTER1), "--out",
                 str(out)]) == 0
    data = json.loads(out.read_text())
    assert data["per_condition"] == {"w0_0.csv": {}, "w0_1.csv": {}}
    assert data["shared"]["w"] == pytest.approx(0.4, abs=0.03)


@pytest.mark.parametrize("flags, said", [
    (["--per-trial", "X"], "'X' is not a parameter of the IC model that a joint fit "
                           "identifies (its parameters: kp, kd, delay_s, w"),
    (["--per-trial", "W", "--conditions", "a", "b"], "--conditions: 2 label(s) for 4 "
                                                     "recordings"),
    (["--init", "x.json"], "--init: go with one recording"),
])
def test_the_command_refuses_in_one_line(flags, said, ic_csvs, tmp_path, capsys):
    folder, paths = ic_csvs
    out = tmp_path / "x.json"
    assert main(["fit", *paths, "--model", "ic", "--body", str(WINTER1), *flags, "--out",
                 str(out)]) == 2
    err = capsys.readouterr().err
    assert said in err and len(err.strip().splitlines()) == 1
    assert not out.exists()


def test_one_recording_refuses_per_trial(ic_csvs, tmp_path, capsys):
    folder, paths = ic_csvs
    assert main(["fit", paths[0], "--model", "ic", "--body", str(WINTER1), "--per-trial", "W",
                 "--out", str(tmp_path / "x.json")]) == 2
    assert "--per-trial: go with several recordings" in capsys.readouterr().err


def test_the_command_names_decs_parameters(ic_csvs, tmp_path, capsys):
    """DEC's per-condition parameters are its modules' (``ankle.kp``): another name is
    refused with them, before any fit."""
    folder, paths = ic_csvs
    assert main(["fit", *paths[:2], "--body", str(WINTER1), "--per-trial", "kp", "--out",
                 str(tmp_path / "x.json")]) == 2
    err = capsys.readouterr().err
    assert ("'kp' is not a parameter of the DEC model that a joint fit identifies (its "
            "parameters: ankle.kp, ankle.ki, ankle.kd, ankle.delay_s)") in err


def test_a_jacobians_null_space_names_the_undetermined_parameters():
    from posture_id.fitting.frequency import undetermined

    rng = np.random.default_rng(0)
    full = rng.normal(size=(12, 4))
    assert not undetermined(full).any()
    traded = full.copy()
    traded[:, 3] = 2 * traded[:, 1] - traded[:, 0]  # the fourth trades off with two others
    assert list(undetermined(traded)) == [True, True, False, True]
    assert undetermined(rng.normal(size=(2, 6))).all()  # 2 numbers for 6 parameters


def test_one_sinusoid_trial_leaves_the_ic_parameters_undetermined_and_says_so():
    from posture_id.bodies.anthropometry import winter_body_file
    from posture_id.bodies.body import load_body
    from posture_id.fitting.frequency import fit_ic
    from posture_id.models.ic.model import IC
    from posture_id.models.ic.subjects import ic_recording
    from posture_id.models.protocol import TrustLevel
    from posture_id.simulation.protocols import SumOfSinesProtocol
    from posture_id.trials import prepare_trial

    body = load_body(winter_body_file(1.75, 70.0, 1))
    sine = SumOfSinesProtocol(frequencies_hz=(0.2,), amplitudes_deg=(1.0,), cycles=8)
    recording, _ = ic_recording(body, IC.default_parameters(body), sine.profile(), None, 3)
    fit = fit_ic(prepare_trial(recording, None, rate_hz=50.0), body)
    assert fit.harmonics == 1 and set(fit.undetermined) == set(fit.free)
    assert fit.trust_level is TrustLevel.IMPRECISE
    assert "not determined by this recording" in fit.verdict_line()
    plant = IC.plant(body)
    for name in fit.free:  # no interval narrower than what 2 numbers can tell
        low, high = IC.search_bounds[name]
        assert fit.intervals[name] == pytest.approx((low * IC.scale(name, plant),
                                                     high * IC.scale(name, plant)))
