"""The robot checks without their optional extra: importing ``posture_id.robots`` does not
import MuJoCo, and using it without MuJoCo stops with one line naming the extra."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from posture_id.errors import PostureIdError
from posture_id.robots import ROBOTS_EXTRA, MissingExtraError, simulate_mujoco
from posture_id.robots.mujoco_model import MujocoOptions
from posture_id.robots.stability import GROWTH_SLACK, choose_step, one_step_radius
from posture_id.robots.whole_body import (
    HeldJoints,
    WholeBodyModel,
    WholeBodyOptions,
    WholeBodySpec,
    simulate_whole_body,
)


def test_importing_the_robot_checks_does_not_import_mujoco():
    code = ("import sys, posture_id.robots, posture_id.cli; "
            "print('mujoco' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True)
    assert out.stdout.strip() == "False"


def test_without_mujoco_one_line_names_the_extra(monkeypatch, tip):
    monkeypatch.setitem(sys.modules, "mujoco", None)  # import mujoco → ImportError
    with pytest.raises(MissingExtraError) as err:
        simulate_mujoco(tip)
    message = str(err.value)
    assert isinstance(err.value, PostureIdError)
    assert "\n" not in message and ROBOTS_EXTRA in message
    assert ROBOTS_EXTRA == "pip install posture_id[robots]"


# --- the checks themselves (MuJoCo needed from here on) ---------------------------------

TIP_URDF = Path(__file__).resolve().parents[1] / "urdf" / "tip_default.urdf"


def _mujoco():
    return pytest.importorskip("mujoco")


def _robots() -> None:
    """Skip where example-robot-data (it ships files, no importable module) is missing."""
    from posture_id.bodies.lumping import robots_dir

    try:
        robots_dir()
    except PostureIdError as exc:
        pytest.skip(str(exc))


def _one_cycle():
    from posture_id.simulation import prts

    return prts(cycles=1)  # 60.5 s, 1° p-p


def _weak(params):
    """The same DEC with a tenth of the ankle's active and passive stiffness: less than the
    body's m·g·h, so it cannot hold the body up."""
    ankle = params.joints[0]
    module = params.modules[ankle]
    return params.replace(ankle, kp=0.1 * module.kp, kpas=0.1 * module.kpas, ki=0.0)


def test_the_tip_chain_in_mujoco_agrees_with_the_compiled_simulator():
    """The TIP URDF's chain (it *is* the lumped model) in MuJoCo (RK4, 1 ms) against the
    compiled simulator (2 ms), one 60.5 s PRTS cycle, default DEC. Measured: gain within
    0.7 %, phase within 0.7° at every FRF point 0.08-1 Hz, 100.0 % of each sway explained."""
    _mujoco()
    from posture_id.robots.check import BODY_COM, robot_check

    result = robot_check(TIP_URDF, _one_cycle())
    assert result.kind == "chain" and result.stays_up and result.lumped_fall_s is None
    assert result.channels == ("shank", "thigh", "trunk", BODY_COM)
    assert result.frequencies_hz.min() >= 0.05 - 1e-9 and result.frequencies_hz.max() <= 1.0
    assert len(result.frequencies_hz) >= 20
    assert np.max(np.abs(result.gain_difference_percent)) < 1.0
    assert np.max(np.abs(result.phase_difference_deg)) < 1.0
    assert np.all(result.variance_explained > 0.99)
    # the FRF itself is a body's (a gain that is not ~1 and falls with frequency)
    assert 0.3 < result.engine_gain[0, -1] < 3.0
    assert result.engine_gain[-1, -1] < result.engine_gain[0, -1]


@pytest.mark.slow("MuJoCo at a 1 ms step, TALOS whole body")
def test_talos_whole_body_follows_its_lumped_chain_to_one_hertz():
    """TALOS (33 DoF, half-sitting) in MuJoCo, lumped to 3 segments, its lumped chain's
    default DEC split between the two legs, the other joints servoed at 100× m·g·h, one 1°
    PRTS cycle at the chosen step (1 ms; ~11 s here). Measured (benchmarks/robot_check.py):
    every segment and the body COM within 1.3 % in gain and 0.9° in phase of the lumped
    chain at every FRF point from 0.08 to 1 Hz, 100.0 % of each one's variance explained.
    The bounds leave about 1.5× that margin."""
    _mujoco()
    _robots()
    from posture_id.robots.check import BODY_COM, CheckOptions, robot_check

    result = robot_check("talos", _one_cycle(), options=CheckOptions(segments=3))
    assert result.kind == "whole body" and result.stays_up and result.lumped_fall_s is None
    assert result.channels == ("shank", "thigh", "trunk", BODY_COM)
    assert result.frequencies_hz.max() > 0.95 and len(result.frequencies_hz) >= 25
    assert np.max(np.abs(result.gain_difference_percent)) < 2.0, result.gain_difference_percent
    assert np.max(np.abs(result.phase_difference_deg)) < 1.5, result.phase_difference_deg
    assert np.all(result.variance_explained > 0.999), result.variance_explained
    assert result.details["mujoco_timestep_s"] == 0.001
    assert "1 ms is stable" in result.details["step_choice_sentence"]
    assert result.details["dofs"] > 30 and 90 < result.details["mass_kg"] < 100
    held = {g["joint"]: g for g in result.details["held_joints"]}
    assert held["leg_left_6_joint"]["locked"]  # the feet's roll joints: the support
    assert not held["arm_left_4_joint"]["locked"] and held["arm_left_4_joint"][
        "stiffness_nm_rad"] > 0
    # each servo reports the static torque it holds its posture with (the waist's pitch:
    # measured 4.4 N·m)
    assert abs(held["torso_2_joint"]["feedforward_nm"]) > 1.0


def test_talos_at_two_segments_has_its_knees_servoed_with_an_armature():
    """Lumped to 2 segments, TALOS's knees are held by their servos (22.5 kN·m/rad at 100×),
    whose damping on the knee's own light subtree (shank and foot, in MuJoCo's tree rooted
    at the pelvis) is past RK4's reach at 1 ms: the servo gets an armature
    (``WholeBodyOptions.max_step_rate``); rigid, the knee is no joint at all."""
    _mujoco()
    _robots()

    spec = WholeBodySpec.preset("talos")
    step = MujocoOptions(timestep_s=0.001)
    servoed = WholeBodyModel.build(spec, 2, mujoco_options=step)
    knee = servoed.gains["leg_left_4_joint"]
    assert knee.armature > 0 and not knee.locked and knee.stiffness > 2e4
    rigid = WholeBodyModel.build(spec, 2, mujoco_options=step,
                                 options=WholeBodyOptions(held=HeldJoints.RIGID))
    assert all(g.locked for g in rigid.gains.values())
    assert rigid.model.nv == 6 + 2 * 2 + 1  # the base, two legs' ankle and hip, platform
    with pytest.raises(PostureIdError, match="held must be one of servos, rigid"):
        WholeBodyOptions(held="soft")


def test_the_step_is_the_largest_at_which_the_whole_body_is_stable():
    """The G1's servoed whole body at 1 ms: one step's spectral radius 3.8 against 1.002²
    at half of it (RK4 diverges within the first steps, the run falls at 0.01 s); 0.5 ms
    is stable. Rigid, it has no stiff servo: 1 ms. The standing body's own instability
    (an inverted pendulum without DEC) is no reason to shorten it: ρ(dt) = ρ(dt/2)²."""
    _mujoco()
    _robots()

    spec = WholeBodySpec.preset("g1")

    def build(held):
        return lambda step: WholeBodyModel.build(
            spec, 3, mujoco_options=MujocoOptions(timestep_s=step),
            options=WholeBodyOptions(held=held)).model

    servos = choose_step(build(HeldJoints.SERVOS))
    assert servos.step_s == 0.0005
    (one, rho, half), (_, rho_half, quarter) = servos.tried
    assert one == 0.001 and rho > 1.5 * half**2 and rho_half <= GROWTH_SLACK * quarter**2
    assert "1 ms is unstable" in servos.sentence() and "0.5 ms is stable" in servos.sentence()
    assert choose_step(build(HeldJoints.RIGID)).step_s == 0.001
    model = build(HeldJoints.RIGID)(0.001)
    rho = one_step_radius(model)
    model.opt.timestep = 0.0005
    assert rho > 1.0 and abs(rho - one_step_radius(model) ** 2) < 1e-3 * rho


@pytest.mark.slow("MuJoCo at 1 and 0.5 ms steps, TALOS whole body")
def test_the_constraint_solver_is_tight_enough_for_the_step_to_converge():
    """MuJoCo's own solver tolerance (1e-8) leaves weld-force errors that DEC's loop turns
    into sway of its own, different at every step: TALOS rigid on 10 s of the PRTS at 1
    and 0.5 ms then differs by more than the sway's RMS (measured 113–253 %); at the
    project's 1e-15 by under 0.3 % (measured 0.08–0.23 %; ~8 s here)."""
    _mujoco()
    _robots()

    spec = WholeBodySpec.preset("talos")
    stimulus = _one_cycle().spanning(10.0)
    rigid = WholeBodyOptions(held=HeldJoints.RIGID)

    def step_halving(tolerance: float) -> float:
        runs = [simulate_whole_body(spec, 3, stimulus=stimulus, whole_body_options=rigid,
                                    mujoco_options=MujocoOptions(
                                        timestep_s=step, solver_tolerance=tolerance,
                                        solver_iterations=100 if tolerance > 1e-9 else 1000)
                                    )[0].theta for step in (0.001, 0.0005)]
        diff = np.sqrt(np.mean((runs[0] - runs[1]) ** 2, axis=0))
        return float(np.max(diff / np.sqrt(np.mean(runs[1] ** 2, axis=0))))

    assert step_halving(MujocoOptions().solver_tolerance) < 0.003
    assert step_halving(1e-8) > 0.05


def test_a_chain_with_too_little_gain_is_reported_as_fallen(tmp_path):
    """A tenth of the ankle's stiffness cannot hold the TIP: both engines report the fall,
    with its time, in the result, its JSON and its summary; no FRF of a fallen body."""
    _mujoco()
    from posture_id.bodies.body import load_body
    from posture_id.dec.parameters import default_parameters
    from posture_id.robots.check import robot_check

    tip = load_body(TIP_URDF)
    result = robot_check(tip, _one_cycle(), _weak(default_parameters(tip)))
    assert not result.stays_up
    assert 0.0 < result.engine_fall_s < 60.5
    assert result.lumped_fall_s is not None
    assert abs(result.engine_fall_s - result.lumped_fall_s) < 0.5  # the same body falls
    assert result.gain_difference_percent is None and result.engine_gain is None
    saved = json.loads(result.to_json(tmp_path / "check.json"))
    assert saved["stays_up"] is False and saved["engine_fall_s"] == result.engine_fall_s
    summary = result.summary()
    assert f"FELL at t = {result.engine_fall_s:.2f} s" in summary
    assert "no FRF" in summary


def test_the_whole_body_with_too_little_gain_falls():
    """TALOS's whole body under the weak DEC falls in MuJoCo too (the run stops there)."""
    _mujoco()
    _robots()
    from posture_id.dec.parameters import default_parameters
    from posture_id.robots.check import CheckOptions, robot_check
    from posture_id.robots.whole_body import WholeBodySpec, lumped_body

    spec = WholeBodySpec.preset("talos")
    weak = _weak(default_parameters(lumped_body(spec, 1)))
    result = robot_check(spec, _one_cycle(), weak, CheckOptions(segments=1))
    assert not result.stays_up and 0.0 < result.engine_fall_s < 60.5
    # a fall of the body, not of the integration: near the lumped chain's (measured 5.97 s
    # against 6.42 s)
    assert result.lumped_fall_s is not None
    assert abs(result.engine_fall_s - result.lumped_fall_s) < 1.5
    assert f"FELL at t = {result.engine_fall_s:.2f} s" in result.summary()


def test_the_robot_check_command_on_the_chain(tmp_path, capsys):
    """``posture-id robot check --body CHAIN_URDF`` writes check.json and check.png, prints
    the summary; exit 0 (it stays up)."""
    _mujoco()
    from posture_id.cli import main

    out = tmp_path / "check"
    assert main(["robot", "check", "--body", str(TIP_URDF), "--cycles", "1", "--states",
                 "80", "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "robot check of tip_default (chain)" in printed and "stays up" in printed
    saved = json.loads((out / "check.json").read_text())
    assert saved["kind"] == "chain" and saved["stays_up"] is True
    assert saved["channels"] == ["shank", "thigh", "trunk", "body COM"]
    assert (out / "check.png").stat().st_size > 10_000


def test_the_robot_check_command_reports_a_fall(tmp_path, capsys):
    """A DEC file with too little gain: exit 1 (doubtful), the fall in the summary."""
    _mujoco()
    from posture_id.bodies.body import load_body
    from posture_id.cli import main
    from posture_id.dec.parameters import default_parameters

    tip = load_body(TIP_URDF)
    params = tmp_path / "weak.json"
    _weak(default_parameters(tip)).to_json(params)
    out = tmp_path / "check"
    assert main(["robot", "check", "--body", str(TIP_URDF), "--params", str(params),
                 "--cycles", "1", "--states", "80", "--out", str(out)]) == 1
    assert "FELL at t = " in capsys.readouterr().out
    assert json.loads((out / "check.json").read_text())["engine_fall_s"] > 0


@pytest.mark.parametrize("body, fragment", [
    ("atlas", "'atlas' is neither a preset (talos, g1, human) nor a URDF file"),
    ("missing.urdf", "neither a preset"),
])
def test_the_robot_check_command_refuses_in_one_line(tmp_path, capsys, body, fragment):
    _mujoco()
    from posture_id.cli import main

    assert main(["robot", "check", "--body", body, "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and fragment in err and err.startswith("posture-id: error: ")
    assert not (tmp_path / "o").exists()


def test_the_robot_check_command_without_mujoco_names_the_extra(monkeypatch, tmp_path,
                                                                capsys):
    monkeypatch.setitem(sys.modules, "mujoco", None)  # import mujoco → ImportError
    from posture_id.cli import main

    assert main(["robot", "check", "--body", "talos", "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and ROBOTS_EXTRA in err
    assert not (tmp_path / "o").exists()


def test_check_options_are_refused_in_one_line():
    from posture_id.robots.check import CheckOptions
    from posture_id.robots.errors import RobotError

    with pytest.raises(RobotError, match="low_hz < high_hz"):
        CheckOptions(low_hz=1.0, high_hz=0.5)
    with pytest.raises(RobotError, match="segments must be 1, 2 or 3"):
        CheckOptions(segments=4)
