"""A third model plugs in through the model protocol alone (tests/pd_model.py): it is
simulated, fitted, compared with the IC model and run over a cohort by the project's own
stages, none of which knows it; and the check suite every model passes."""

from __future__ import annotations

import csv
import json
import math

import numpy as np
import pytest
from pd_model import PD, PdParameters

from posture_id.bodies.body import load_body
from posture_id.comparison.cohort import compare_cohort
from posture_id.comparison.models import compare_models
from posture_id.errors import PostureIdError
from posture_id.fitting.frequency import IcFitOptions
from posture_id.fitting.models import fit_model
from posture_id.frf.locked import LockedOptions
from posture_id.models import DEC, IC, Capability, Model, TrustLevel, model_named
from posture_id.models.ic import IcParameters
from posture_id.simulation.stimulus import prts
from posture_id.trials import prepare_trial

STIMULUS = prts(cycles=3)
WINTER_2SEG = "posture_id/bodies/data/winter_1.75m_70kg_2seg.urdf"


@pytest.fixture(scope="module")
def body():
    return load_body()


@pytest.fixture(scope="module")
def pd_truth(body):
    mgh = PD.plant(body).mgh
    return PdParameters(kp=1.8 * mgh, kd=0.45 * mgh, delay_s=0.12)


@pytest.fixture(scope="module")
def pd_trial(body, pd_truth):
    recording = PD.simulate(body, pd_truth, STIMULUS).with_sensor_noise(0.02, 1)
    return prepare_trial(recording, STIMULUS)


def test_the_third_model_is_a_model_and_known_by_its_name(pd_truth):
    assert isinstance(PD, Model)
    assert model_named("pd") is PD
    assert PD.parameters_from_dict(json.loads(json.dumps(pd_truth.to_dict()))) == pd_truth


def test_the_third_model_is_fitted_by_the_frequency_domain_fit(body, pd_truth, pd_trial):
    fit = fit_model(PD, pd_trial, body, LockedOptions())
    for name in ("kp", "kd", "delay_s"):
        true = getattr(pd_truth, name)
        assert getattr(fit.parameters, name) == pytest.approx(true, rel=0.05), name
        low, high = fit.intervals[name]
        assert low < getattr(fit.parameters, name) < high
    assert fit.consistent and isinstance(fit.trust_level, TrustLevel)
    assert fit.to_dict()["model"] == "pd"
    # its time-domain simulation and its exact response agree: the fit explains the sway
    assert fit.explained > 0.95


def test_the_comparison_takes_the_third_model_through_the_protocol(body, pd_trial):
    """On PD sway the PD model explains the sway within its noise; the IC model holds it
    (W = 1, G = 0), so with more parameters it cannot be preferred. On IC sway with a
    reweighted tilt (W 0.4) and torque feedback, the PD model cannot follow: IC is
    preferred."""
    on_pd = compare_models(pd_trial, body, models=(PD, IC), held_out=False)
    assert on_pd.within_noise["pd"]
    assert on_pd.preferred in ("pd", "undecided")
    assert "delta_bic_ic_minus_pd" in on_pd.to_dict()
    truth = IcParameters(kp=1.6 * IC.plant(body).mgh, kd=0.4 * IC.plant(body).mgh,
                         delay_s=0.13, w=0.4, torque_feedback_gain=0.3,
                         torque_feedback_time_s=15.0)
    ic_trial = prepare_trial(IC.simulate(body, truth, STIMULUS).with_sensor_noise(0.02, 2),
                             STIMULUS)
    on_ic = compare_models(ic_trial, body, models=(PD, IC))
    assert not on_ic.within_noise["pd"] and on_ic.within_noise["ic"]
    assert on_ic.preferred == "ic"
    assert on_ic.held_out is not None and on_ic.held_out["ic"] < on_ic.held_out["pd"]


def test_a_cohort_of_the_third_model(body, pd_truth, tmp_path):
    folder = tmp_path / "recordings"
    folder.mkdir()
    for k in range(2):
        PD.simulate(body, pd_truth, STIMULUS).with_sensor_noise(0.02, k).to_csv(
            folder / f"s{k}.csv")
    from posture_id.recording import Recording

    def read(path):
        return prepare_trial(Recording.from_csv(path, body.segment_names), STIMULUS)

    recordings = sorted(folder.glob("*.csv"))
    out = tmp_path / "out"
    first = compare_cohort(recordings, out, body, read, IcFitOptions(), held_out=False,
                           models=(PD, IC))
    assert not first.failed
    rows = list(csv.DictReader((out / "summary.csv").open()))
    assert [r["recording"] for r in rows] == ["s0.csv", "s1.csv"]
    assert all(math.isclose(float(r["pd_kp"]), pd_truth.kp, rel_tol=0.05) for r in rows)
    again = compare_cohort(recordings, out, body, read, IcFitOptions(), held_out=False,
                           models=(PD, IC))
    assert {r.status for r in again.rows} == {"skipped"}


# --- the check suite every model passes -----------------------------------------------

MODELS = (DEC, IC, PD)


@pytest.mark.parametrize("model", MODELS, ids=repr)
def test_check_parameters_round_trip_through_json_with_the_model_key(model, body):
    params = model.default_parameters(body)
    data = json.loads(json.dumps(params.to_dict()))
    assert model.parameters_from_dict(data, body) == params
    if model is not DEC:  # a DEC file is keyed by joint, its modules named
        assert data["model"] == model.name


@pytest.mark.parametrize("model", MODELS, ids=repr)
def test_check_bounds_hold_the_defaults(model, body):
    params = model.default_parameters(body)
    for key, (low, high) in model.bounds(body).items():
        joint, _, name = key.rpartition(".")
        value = getattr(params[joint] if joint else params, name)
        assert low <= value <= high, key


@pytest.mark.parametrize("model", MODELS, ids=repr)
def test_check_simulation_is_deterministic_under_a_seed(model, body):
    params = model.default_parameters(body)
    stimulus = prts(cycles=1)
    a = model.simulate(body, params, stimulus, motor_sd_deg=0.05, seed=3)
    b = model.simulate(body, params, stimulus, motor_sd_deg=0.05, seed=3)
    c = model.simulate(body, params, stimulus, motor_sd_deg=0.05, seed=4)
    assert np.array_equal(a.theta, b.theta, equal_nan=True)
    assert not np.array_equal(a.theta, c.theta, equal_nan=True)
    assert a.theta.shape[1] == body.n_segments


@pytest.mark.parametrize("model", [m for m in MODELS
                                   if Capability.FREQUENCY_RESPONSE in m.capabilities],
                         ids=repr)
def test_check_a_fit_is_deterministic_typed_and_has_its_intervals(model, body):
    params = model.default_parameters(body)
    trial = prepare_trial(model.simulate(body, params, STIMULUS).with_sensor_noise(0.05, 5),
                          STIMULUS)
    first = fit_model(model, trial, body, LockedOptions())
    again = fit_model(model, trial, body, LockedOptions())
    assert first.parameters == again.parameters
    assert set(first.intervals) == set(first.free)
    assert isinstance(first.trust_level, TrustLevel)
    assert first.identified_count == len(first.free)


@pytest.mark.parametrize("model", [m for m in MODELS
                                   if Capability.FREQUENCY_RESPONSE in m.capabilities],
                         ids=repr)
def test_check_another_bodys_recording_is_refused(model, body):
    other = load_body(WINTER_2SEG)
    recording = model.simulate(other, model.default_parameters(other), STIMULUS)
    trial = prepare_trial(recording, STIMULUS)
    with pytest.raises(PostureIdError, match="segment"):
        fit_model(model, trial, body, LockedOptions())
