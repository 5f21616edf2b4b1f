"""Real bodies: whole-body humanoid URDFs lumped into the sagittal chain."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from posture_id.bodies.body import load_body
from posture_id.bodies.lumping import PRESETS, lump_robot, preset_body, robots_dir
from posture_id.errors import BodyError
from posture_id.simulation import simulate


def _full_model(preset):
    """The preset's whole-body model and its reference configuration, independently."""
    root = robots_dir()
    model = pin.buildModelFromUrdf(str(root / preset.urdf), pin.JointModelFreeFlyer())
    q = pin.neutral(model)
    if preset.srdf:
        pin.loadReferenceConfigurations(model, str(root / preset.srdf[0]), False)
        q = np.array(model.referenceConfigurations[preset.srdf[1]])
    if any(preset.base_rpy):
        rot = pin.rpy.rpyToMatrix(*preset.base_rpy)
        quat = pin.Quaternion(rot @ pin.Quaternion(q[6], *q[3:6]).matrix())
        q[3:7] = [quat.x, quat.y, quat.z, quat.w]
    return model, q


def _above(model, data, joint_pairs):
    """Mass and world COM of the whole model minus the subtrees of the given joints."""
    mass = data.mass[0]
    moment = data.mass[0] * data.com[0]
    for j in joint_pairs:
        world_com = data.oMi[j].act(data.com[j])  # subtree COMs are in the joint frame
        mass -= data.mass[j]
        moment = moment - data.mass[j] * world_com
    return mass, moment / mass


@pytest.mark.parametrize("name", sorted(PRESETS))
@pytest.mark.parametrize("segments", [3, 2])
def test_lumped_body_keeps_mass_com_and_mgh(tmp_path, name, segments):
    preset = PRESETS[name]
    path = preset_body(name, segments).write(tmp_path / f"{name}.urdf")
    body = load_body(path)
    assert body.n_segments == segments

    model, q = _full_model(preset)
    data = model.createData()
    pin.centerOfMass(model, data, q, True)
    pin.forwardKinematics(model, data, q)
    g = np.linalg.norm(model.gravity.linear)

    def point(pair):
        return (data.oMi[model.getJointId(pair[0])].translation
                + data.oMi[model.getJointId(pair[1])].translation) / 2

    def ids(pair):
        return [model.getJointId(n) for n in pair]

    ankle = point(preset.ankle)
    # total mass of the segments = whole robot minus both feet
    m_body, com_body = _above(model, data, ids(preset.ankle))
    assert body.total_mass == pytest.approx(m_body, rel=1e-6)
    # whole-body COM height above the ankle, from the lumped model by Pinocchio
    lumped = body.model
    ldata = lumped.createData()
    pin.centerOfMass(lumped, ldata, pin.neutral(lumped), True)
    assert ldata.com[1][2] == pytest.approx(com_body[2] - ankle[2], rel=1e-6)
    # and the total including the feet, carried by the support link
    assert ldata.mass[0] + lumped.inertias[0].mass == pytest.approx(
        sum(i.mass for i in model.inertias), rel=1e-6)
    # per-module m·g·h
    roles = [preset.ankle, preset.knee, preset.hip] if segments == 3 else [preset.ankle, preset.hip]
    for i, pair in enumerate(roles):
        mass, com = _above(model, data, ids(pair))
        lever = com - point(pair)
        expected = mass * g * np.hypot(lever[0], lever[2])
        assert body.mgh[i] == pytest.approx(expected, rel=1e-6), (name, i)


@pytest.mark.parametrize("name", sorted(PRESETS))
def test_preset_defaults_are_stable(tmp_path, name):
    body = load_body(preset_body(name).write(tmp_path / f"{name}.urdf"))
    result = simulate(body)
    assert result.stable, (name, result.abort_time)


def test_shipped_preset_urdfs_are_current(tmp_path):
    """urdf/<preset>_tip.urdf is what `make bodies` writes today (to rounding)."""
    from pathlib import Path

    urdf_dir = Path(__file__).resolve().parents[1] / "urdf"
    for name in PRESETS:
        shipped = load_body(urdf_dir / f"{name}_tip.urdf")
        fresh = load_body(preset_body(name).write(tmp_path / f"{name}.urdf"))
        np.testing.assert_allclose(shipped.mgh, fresh.mgh, rtol=1e-12)
        np.testing.assert_allclose(shipped.coupling, fresh.coupling, rtol=1e-12, atol=1e-15)
        np.testing.assert_allclose(shipped.inertias, fresh.inertias, rtol=1e-12)


def _g1(**overrides):
    preset = PRESETS["g1"]
    kwargs = dict(urdf=robots_dir() / preset.urdf, ankle=preset.ankle, knee=preset.knee,
                  hip=preset.hip)
    kwargs.update(overrides)
    return lump_robot(**kwargs)


@pytest.mark.parametrize(
    "overrides, fragment",
    [
        ({"ankle": ("left_ankle_pitch", "right_ankle_pitch_joint")},
         "ankle joint 'left_ankle_pitch' is not in the model (did you mean"),
        ({"hip": ("left_hip_roll_joint", "right_hip_pitch_joint")},
         "hip joint 'left_hip_roll_joint' does not pitch"),
        ({"posture": np.zeros(10)}, "posture has 10 values"),
        ({"ankle": ("left_knee_joint", "right_knee_joint"),
          "knee": ("left_ankle_pitch_joint", "right_ankle_pitch_joint")}, "is not below"),
        ({"knee": None}, "needs the knee joints"),
        ({"urdf": "missing.urdf"}, "no such URDF"),
    ],
)
def test_lumping_errors(overrides, fragment):
    with pytest.raises(BodyError) as err:
        _g1(**overrides)
    assert fragment in str(err.value)
    assert "\n" not in str(err.value)


def test_unknown_preset():
    with pytest.raises(BodyError, match="unknown robot 'atlas'"):
        preset_body("atlas")
