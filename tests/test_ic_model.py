"""The IC model (docs/model.md §8): its body against Pinocchio, its closed-loop response against a
hand-derived special case and against its own time-domain simulation, exact derivatives,
stability, parameter files, and the fit recovering the parameters of IC recordings."""

from __future__ import annotations

import math

import numpy as np
import pytest

from posture_id.errors import ParameterError
from posture_id.fitting.frequency import fit_ic
from posture_id.models.ic import IcParameters, IcPlant, closed_loop, default_ic_parameters
from posture_id.models.ic.response import PARAMETER_ORDER, rightmost_pole
from posture_id.models.ic.simulation import ic_sway, simulate_ic
from posture_id.simulation.options import SimulationOptions
from posture_id.simulation.stimulus import prts
from posture_id.trials import prepare_trial


def test_the_locked_body_inertia_is_pinocchios_about_the_ankle(any_body):
    """J = 1ᵀM(0)1 equals Pinocchio's joint-space inertia of the chain turning as one
    (relative joint angles: the ankle's diagonal term)."""
    import pinocchio as pin

    model = any_body.model
    data = model.createData()
    mass_matrix = pin.crba(model, data, pin.neutral(model))
    assert IcPlant.of(any_body).inertia == pytest.approx(mass_matrix[0, 0], rel=1e-9)
    assert IcPlant.of(any_body).mgh == pytest.approx(any_body.mgh[0])


def test_without_delay_and_torque_feedback_the_response_is_the_second_order_closed_form(tip):
    """H = W(Kp + Kd s)/(J s² + Kd s + Kp − mgh): its static gain W·Kp/(Kp − mgh), and at
    ω_n = √((Kp − mgh)/J) the gain W·|Kp + j Kd ω_n| / (Kd ω_n) (derived by hand)."""
    plant = IcPlant.of(tip)
    p = IcParameters(kp=1.6 * plant.mgh, kd=0.3 * plant.mgh, delay_s=0.0, w=0.7)
    static = closed_loop(p, plant, np.array([1e-9j]))[0]
    assert static.real == pytest.approx(0.7 * p.kp / (p.kp - plant.mgh), rel=1e-6)
    omega_n = math.sqrt((p.kp - plant.mgh) / plant.inertia)
    at_wn = closed_loop(p, plant, np.array([1j * omega_n]))[0]
    assert abs(at_wn) == pytest.approx(0.7 * abs(p.kp + 1j * p.kd * omega_n)
                                       / (p.kd * omega_n), rel=1e-9)
    assert np.angle(at_wn) == pytest.approx(np.angle(p.kp + 1j * p.kd * omega_n) - np.pi / 2)


def test_derivatives_are_exact(tip):
    plant = IcPlant.of(tip)
    p = IcParameters(kp=700.0, kd=160.0, delay_s=0.15, w=0.6, torque_feedback_gain=0.3,
                     torque_feedback_time_s=20.0, ki=5.0, kpas=50.0, bpas=10.0)
    s = 2j * np.pi * np.array([0.02, 0.3, 1.7])
    _, grad = closed_loop(p, plant, s, gradient=True)
    for k, name in enumerate(PARAMETER_ORDER):
        step = 1e-6 * max(abs(getattr(p, name)), 1e-3)
        up = closed_loop(p.replace(**{name: getattr(p, name) + step}), plant, s)
        down = closed_loop(p.replace(**{name: getattr(p, name) - step}), plant, s)
        np.testing.assert_allclose(grad[k], (up - down) / (2 * step), rtol=1e-5, atol=1e-12)


def _steady_cycle_response(params, plant, dt):
    """The last cycle's harmonics of the time-domain sway over the tilt's: (f, H)."""
    stimulus = prts(1.0, 4, 80)
    options = SimulationOptions(dt=dt)
    time, theta = ic_sway(params, plant, stimulus, options)
    period = int(round(stimulus.period_s * options.sample_rate_hz))
    last = slice(len(theta) - 1 - period, len(theta) - 1)
    u = np.fft.rfft(stimulus.angle(time)[last])
    y = np.fft.rfft(theta[last])
    f = np.fft.rfftfreq(period, 1 / options.sample_rate_hz)
    excited = np.abs(u) > 1e-3 * np.abs(u).max()
    excited &= (f > 0) & (f <= 2.0)
    return f[excited], y[excited] / u[excited]


def test_the_response_is_the_time_domain_simulations_on_a_prts(tip):
    """The steady-state cycles of the 2 ms simulation against H(jω) at every excited
    harmonic up to 2 Hz; halving the step halves the difference (first order, Euler)."""
    plant = IcPlant.of(tip)
    p = default_ic_parameters(plant.mgh).replace(torque_feedback_time_s=5.0)
    f, coarse = _steady_cycle_response(p, plant, 0.002)
    _, fine = _steady_cycle_response(p, plant, 0.001)
    h = closed_loop(p, plant, 2j * np.pi * f)
    error_coarse = np.max(np.abs(coarse - h) / np.abs(h))
    error_fine = np.max(np.abs(fine - h) / np.abs(h))
    assert error_coarse < 0.02
    assert error_fine < 0.6 * error_coarse


def test_stability_is_the_simulations(tip):
    plant = IcPlant.of(tip)
    stable = default_ic_parameters(plant.mgh)
    weak = stable.replace(kp=0.9 * plant.mgh)  # less than gravity: falls
    late = stable.replace(delay_s=0.6, kd=0.1 * plant.mgh)  # delay beyond the margin
    assert rightmost_pole(stable, plant) < 0
    assert rightmost_pole(weak, plant) > 0 and rightmost_pole(late, plant) > 0
    for p, falls in ((stable, False), (weak, True), (late, True)):
        _, theta = ic_sway(p, plant, prts(1.0, 2, 80))
        assert (np.max(np.abs(theta)) > 0.5) == falls


def test_parameter_files_round_trip_and_bad_fields_are_named(tmp_path):
    p = default_ic_parameters(700.0)
    path = tmp_path / "ic.json"
    p.to_json(path)
    assert IcParameters.from_json(path) == p
    for data, named in (({"kp": 1}, "\"model\" must be \"ic\""),
                        ({"model": "ic", "kp": 700, "kd": 100, "delay_s": 0.1}, "missing"),
                        ({"model": "ic", "kp": 700, "kd": 100, "delay_s": 150, "w": 0.5},
                         "in seconds"),
                        ({"model": "ic", "kp": 700, "kd": 100, "delay_s": 0.1, "w": 2},
                         "w (the proprioceptive weight)"),
                        ({"model": "ic", "kp": 700, "kd": 100, "delay_s": 0.1, "w": 0.5,
                          "gain": 1}, "unknown field")):
        with pytest.raises(ParameterError, match=named.replace("(", "\\(").replace(")", "\\)")):
            IcParameters.from_dict(data)


@pytest.mark.parametrize("body_name, states, amplitude", [("tip", 242, 1.0),
                                                          ("winter2", 80, 2.0),
                                                          ("winter1", 80, 0.5)])
def test_the_fit_recovers_an_ic_recording(body_name, states, amplitude, request):
    body = request.getfixturevalue(body_name)
    plant = IcPlant.of(body)
    truth = IcParameters(kp=1.8 * plant.mgh, kd=0.4 * plant.mgh, delay_s=0.17, w=0.45,
                         torque_feedback_gain=0.2, torque_feedback_time_s=15.0)
    cycles = 2 if states == 242 else 6
    stimulus = prts(amplitude, cycles, states)
    recording = simulate_ic(body, truth, stimulus).with_sensor_noise(0.02, 3)
    result = fit_ic(prepare_trial(recording, stimulus), body)
    for name in ("kp", "kd", "delay_s", "w"):
        assert getattr(result.parameters, name) == pytest.approx(getattr(truth, name),
                                                                 rel=0.05), name
    assert result.consistent and result.stable


@pytest.mark.slow("16 IC fits, 2 segments")
def test_the_design_predicts_the_fits_own_scatter(winter2):
    """The predicted interval width of Kp, Kd, Δ and W for one IC subject and protocol
    against the scatter of the fit over 16 draws of 0.05° sensor noise (the same
    recording otherwise): within a factor 1.6 either way."""
    from posture_id.design.ic import SHOWN, design_ic
    from posture_id.models.ic.model import BOUNDS, parameter_scale
    from posture_id.models.ic.subjects import draw_ic_parameters
    from posture_id.simulation.protocols import PrtsProtocol

    plant = IcPlant.of(winter2)
    protocol = PrtsProtocol(80, 0.25, 1.0, 6)
    predicted = design_ic(winter2, [protocol], sensor_noise_deg=0.05, draws=1, seed=5)
    truth = draw_ic_parameters(np.random.default_rng(5), plant)  # design_ic's subject
    stimulus = protocol.profile()
    clean = simulate_ic(winter2, truth, stimulus)
    estimates = np.array([[getattr(fit_ic(prepare_trial(clean.with_sensor_noise(0.05, k),
                                                        stimulus), winter2).parameters, p)
                           for p in SHOWN] for k in range(16)])
    scatter = estimates.std(axis=0, ddof=1)
    span = np.array([(BOUNDS[p][1] - BOUNDS[p][0]) * parameter_scale(p, plant) for p in SHOWN])
    predicted_sd = predicted.widths[0] * span / (2 * 1.6448536269514722)
    ratio = predicted_sd / scatter
    assert np.all((ratio > 1 / 1.6) & (ratio < 1.6)), dict(zip(SHOWN, ratio, strict=True))


def test_the_design_says_one_sinusoid_cannot_determine_the_ic_model(winter2):
    """One sinusoid gives two numbers for the IC model's parameters: the design calls every
    shown parameter undetermined (its width capped far beyond the search range) and ranks
    it below three sines, which it does not; the pseudo-inverse said 0.000."""
    from posture_id.design.ic import design_ic
    from posture_id.simulation.protocols import SumOfSinesProtocol

    one = SumOfSinesProtocol(frequencies_hz=(0.2,), amplitudes_deg=(1.0,), cycles=12)
    three = SumOfSinesProtocol(frequencies_hz=(0.1, 0.3, 0.7), amplitudes_deg=(0.5, 0.3, 0.2),
                               cycles=6)
    result = design_ic(winter2, [one, three], draws=2, seed=1)
    assert np.all(result.widths[0] >= 1.0)
    assert np.all(result.widths[1] < 1.0)
    assert result.scores[1] < result.scores[0]
