"""Bodies: URDF loading, validation, m·g·h, and the planar plant against Pinocchio."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from posture_id.bodies.anthropometry import default_tip_segments, straight_links
from posture_id.bodies.body import DEFAULT_URDF, load_body
from posture_id.bodies.urdf_writer import chain_urdf
from posture_id.errors import BodyError
from posture_id.simulation.kernel import LANES, kernels


def test_default_body_mgh_matches_paper(tip):
    np.testing.assert_allclose(tip.mgh, [465.975, 245.25, 73.575], rtol=1e-12)
    assert tip.segment_names == ("shank", "thigh", "trunk")
    assert tip.joint_names == ("ankle", "knee", "hip")
    assert tip.total_mass == pytest.approx(50.0)
    np.testing.assert_allclose([s.length for s in tip.segments], [0.5, 0.5, 0.5])
    np.testing.assert_allclose(tip.inertias, [10 * 0.25 / 12, 10 * 0.25 / 12, 30 * 0.25 / 12])


def test_shipped_default_urdf_is_the_generator_output():
    expected = chain_urdf("tip_default", straight_links(default_tip_segments()))
    assert DEFAULT_URDF.read_text() == expected


def test_winter_body_mgh(winter):
    # docs/model.md §1: 1.80 m, 80 kg gives m·g·h ≈ 770, 447, 173 N·m/rad
    np.testing.assert_allclose(winter.mgh, [770, 447, 173], atol=1.0)


def test_mgh_from_pinocchio_equals_planar_levers(any_body):
    planar = any_body.gravity * np.abs(np.cumsum(any_body.gravity_lever[::-1])[::-1])
    np.testing.assert_allclose(any_body.mgh, planar, rtol=1e-12)


def test_lumped_winter_bodies_keep_the_ankle_mgh(winter, winter2, winter1):
    for other in (winter2, winter1):
        assert other.mgh[0] == pytest.approx(winter.mgh[0], rel=1e-12)
        assert other.total_mass == pytest.approx(winter.total_mass, rel=1e-12)
    assert winter2.mgh[1] == pytest.approx(winter.mgh[2], rel=1e-12)


def _kernel_state(body, theta, omega, tau):
    """Run the compiled kinematics + dynamics (dt = 0) for lanes of given states."""
    n = body.n_segments
    k = kernels(n)
    r = k.rows
    w = np.zeros(r.count * LANES)
    for row, values in ((r.theta, theta), (r.omega, omega), (r.tau, tau)):
        w[row * LANES : (row + n) * LANES] = np.asarray(values).T.ravel()
    d = body.coupling
    s = body.gravity_lever
    k.kinematics(w, s.real.copy(), s.imag.copy(), 10.0)
    k.dynamics(w, d.real.copy(), d.imag.copy(), body.inertias, body.gravity, 0.0)
    acc = w[r.acc * LANES : (r.acc + n) * LANES].reshape(n, LANES).T
    ldl = w[r.mass * LANES : (r.mass + n * n) * LANES].reshape(n, n, LANES)
    return acc, ldl


def test_plant_matches_pinocchio_at_random_states(any_body):
    """Mass matrix, gravity and forward dynamics of the compiled plant vs Pinocchio."""
    body = any_body
    n = body.n_segments
    rng = np.random.default_rng(1)
    q = rng.uniform(-0.25, 0.25, (LANES, n))  # joint angles (θ_1, q_2, ...): |θ| < π/4
    v = rng.uniform(-2, 2, (LANES, n))
    tau = rng.uniform(-300, 300, (LANES, n))
    lower = np.tril(np.ones((n, n)))  # θ = lower @ q
    theta, omega = q @ lower.T, v @ lower.T
    acc, ldl = _kernel_state(body, theta, omega, tau)
    acc_g, _ = _kernel_state(body, theta, np.zeros_like(omega), np.zeros_like(tau))
    model, data = body.model, body.model.createData()
    for lane in range(LANES):
        # M = L·diag(d)·Lᵀ: L unit lower triangular below the diagonal, d on it
        unit_lower = np.tril(ldl[:, :, lane], -1) + np.eye(n)
        m_theta = unit_lower @ np.diag(np.diag(ldl[:, :, lane])) @ unit_lower.T
        m_pin = pin.crba(model, data, q[lane])
        m_pin = np.triu(m_pin) + np.triu(m_pin, 1).T
        np.testing.assert_allclose(lower.T @ m_theta @ lower, m_pin, rtol=1e-12, atol=1e-12)
        g_theta = -m_theta @ acc_g[lane]
        g_pin = pin.computeGeneralizedGravity(model, data, q[lane])
        np.testing.assert_allclose(lower.T @ g_theta, g_pin, rtol=1e-10, atol=1e-9)
        a_pin = pin.aba(model, data, q[lane], v[lane], tau[lane])
        np.testing.assert_allclose(acc[lane], lower @ a_pin, rtol=1e-10, atol=1e-9)


URDF_HEAD = '<?xml version="1.0"?>\n<robot name="bad">\n<link name="foot"/>\n'
INERTIAL = (
    '<inertial><origin xyz="0 0 0.25"/><mass value="10"/>'
    '<inertia ixx="0.2" ixy="0" ixz="0" iyy="0.2" iyz="0" izz="0.01"/></inertial>'
)


def _joint(name, parent, child, kind="revolute", axis="0 1 0", z=0.0):
    return (
        f'<joint name="{name}" type="{kind}"><parent link="{parent}"/><child link="{child}"/>'
        f'<origin xyz="0 0 {z}"/><axis xyz="{axis}"/>'
        '<limit lower="-1" upper="1" effort="1000" velocity="10"/></joint>\n'
    )


def _link(name, inertial=True):
    return f'<link name="{name}">{INERTIAL if inertial else ""}</link>\n'


BAD_URDFS = {
    "prismatic": (
        _link("shank") + _link("thigh") + _joint("ankle", "foot", "shank")
        + _joint("knee", "shank", "thigh", kind="prismatic", axis="0 0 1", z=0.5),
        ["joint 'knee'", "prismatic"],
    ),
    "off_axis": (
        _link("shank") + _link("thigh") + _joint("ankle", "foot", "shank")
        + _joint("knee", "shank", "thigh", axis="1 0 0", z=0.5),
        ["joint 'knee'", "off the common axis"],
    ),
    "vertical_axis": (
        _link("shank") + _joint("ankle", "foot", "shank", axis="0 0 1"),
        ["joint 'ankle'", "not horizontal"],
    ),
    "branching": (
        _link("shank") + _link("left") + _link("right") + _joint("ankle", "foot", "shank")
        + _joint("hip_l", "shank", "left", z=0.5) + _joint("hip_r", "shank", "right", z=0.5),
        ["joints 'hip_l', 'hip_r' branch off link 'shank'", "serial chain",
         "posture-id body --lump"],
    ),
    # a whole humanoid's file: the tree named before its frames' zero masses
    "branching_behind_a_fixed_frame": (
        _link("pelvis") + _link("left") + _link("right") + '<link name="camera">'
        '<inertial><mass value="0"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" '
        'izz="1"/></inertial></link>\n' + _joint("base", "foot", "pelvis", kind="fixed")
        + _joint("cam", "pelvis", "camera", kind="fixed")
        + _joint("hip_l", "pelvis", "left") + _joint("hip_r", "pelvis", "right"),
        ["branch off link 'foot'", "posture-id body --lump"],
    ),
    "floating": (
        _link("shank") + _joint("free", "foot", "shank", kind="floating"),
        ["joint 'free' is floating", "posture-id body --lump"],
    ),
    "missing_inertia": (
        _link("shank") + _link("thigh", inertial=False) + _joint("ankle", "foot", "shank")
        + _joint("knee", "shank", "thigh", z=0.5),
        ["link 'thigh'", "no mass"],
    ),
    "no_joint": ("", ["no moving joint"]),
}


@pytest.mark.parametrize("case", sorted(BAD_URDFS))
def test_bad_urdf_gets_a_clear_error(tmp_path, case):
    body, expected = BAD_URDFS[case]
    path = tmp_path / f"{case}.urdf"
    path.write_text(URDF_HEAD + body + "</robot>\n")
    with pytest.raises(BodyError) as err:
        load_body(path)
    message = str(err.value)
    assert "\n" not in message
    assert str(path) in message
    for fragment in expected:
        assert fragment in message


def test_a_massless_frame_fixed_to_a_segment_adds_nothing(tmp_path):
    """A sensor's frame (mass 0, no inertia; an exporter's ±1e-20 kg·m² inertia too) fixed
    to the shank loads, and the body is the one without it."""
    frame = ('<link name="imu"><inertial><mass value="0"/><inertia ixx="1e-20" ixy="0" '
             'ixz="0" iyy="-1e-20" iyz="0" izz="0"/></inertial></link>\n')
    plain = URDF_HEAD + _link("shank") + _joint("ankle", "foot", "shank") + "</robot>\n"
    with_frame = (URDF_HEAD + _link("shank") + frame + _joint("ankle", "foot", "shank")
                  + _joint("imu_mount", "shank", "imu", kind="fixed", z=0.3) + "</robot>\n")
    (tmp_path / "plain.urdf").write_text(plain)
    (tmp_path / "frame.urdf").write_text(with_frame)
    a, b = load_body(tmp_path / "plain.urdf"), load_body(tmp_path / "frame.urdf")
    assert b.n_segments == 1 and np.allclose(a.mgh, b.mgh) and np.allclose(a.inertias, b.inertias)


def test_missing_and_malformed_files(tmp_path):
    with pytest.raises(BodyError, match="no such URDF"):
        load_body(tmp_path / "nope.urdf")
    bad = tmp_path / "broken.urdf"
    bad.write_text("<robot name='x'><link name='a'>")
    with pytest.raises(BodyError, match="not well-formed XML"):
        load_body(bad)
