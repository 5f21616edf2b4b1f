"""The force-plate route (posture_id/force_plate/cop.py): the body's angular momentum about
the ankle against Pinocchio, a simulated trial's COP turned back into its COM sway, the
plate's tilt and height, and the range where a bending body departs from the route."""

from __future__ import annotations

import math

import numpy as np
import pytest

from posture_id.bodies.anthropometry import winter_body_file
from posture_id.bodies.body import load_body
from posture_id.errors import RecordingError
from posture_id.force_plate import (
    BodyLoad,
    CopOptions,
    CopUnit,
    ankle_momentum,
    com_angle_from_cop,
    cop_of_motion,
)
from posture_id.frf import frequency_response
from posture_id.recording import Recording, TimeUnit
from posture_id.simulation import simulate
from posture_id.simulation.noise import MotorNoise
from posture_id.simulation.options import SimulationOptions
from posture_id.simulation.protocols import SumOfSinesProtocol
from posture_id.simulation.stimulus import prts
from posture_id.trials import prepare_trial

RATE_HZ = 100.0


def winter(segments: int):
    return load_body(winter_body_file(1.75, 70.0, segments))


def test_the_angular_momentum_about_the_ankle_is_pinocchios():
    import pinocchio as pin

    body = winter(3)
    rng = np.random.default_rng(0)
    model = body.model
    data = model.createData()
    for _ in range(5):
        theta = rng.normal(0, 0.1, 3)
        rates = rng.normal(0, 0.5, 3)
        q = np.diff(np.concatenate([[0.0], theta]))  # joint angles, a level platform
        v = np.diff(np.concatenate([[0.0], rates]))
        pin.computeCentroidalMomentum(model, data, q, v)
        com, momentum = data.com[0], data.hg
        # about the ankle (the origin): L_G + c × m·v_G, about the common axis
        about_ankle = np.asarray(momentum.angular) + np.cross(com, momentum.linear)
        expected = float(np.asarray(body.axis) @ about_ankle)
        got = float(ankle_momentum(body, theta[None], rates[None])[0])
        assert got == pytest.approx(expected, rel=1e-9, abs=1e-12)


def test_the_load_is_the_bodys():
    body = winter(2)
    load = BodyLoad.of(body)
    assert load.mass_kg == pytest.approx(body.total_mass)
    assert load.mgh == pytest.approx(body.mgh[0])
    # the one-segment Winter body is the same body rigid: its inertia about the ankle
    single = winter(1)
    assert load.inertia_kg_m2 == pytest.approx(single.inertias[0] + single.total_mass
                                               * single.com_height_above[0] ** 2, rel=1e-9)
    assert 0.3 < load.corner_hz < 0.7


def _trial(body, stimulus, seed=0, motor_deg=0.0):
    motor = MotorNoise(motor_deg, 1.0, seed) if motor_deg else None
    result = simulate(body, None, stimulus, SimulationOptions(sample_rate_hz=RATE_HZ),
                      motor_noise=motor)
    assert result.stable
    return result.to_recording()


def test_a_one_segment_bodys_cop_gives_back_its_com_sway_exactly():
    body = winter(1)
    recording = _trial(body, prts(amplitude_deg=2.0), motor_deg=0.3)
    cop, force = cop_of_motion(body, recording.theta, recording.tilt, RATE_HZ)
    com = com_angle_from_cop(1e3 * cop, RATE_HZ, BodyLoad.of(body), recording.tilt)
    truth = body.com_angles(recording.theta)[:, 0]
    inner = slice(int(2 * RATE_HZ), -int(2 * RATE_HZ))  # the ends feel the mirroring
    error = (com - truth + truth.mean())[inner]
    assert np.sqrt(np.mean(error**2)) < 0.005 * np.std(truth)
    # and the COP is not the COM: it leads it, by more at higher frequencies
    assert np.std(cop) > 1.05 * np.std(truth * BodyLoad.of(body).com_height_m)


def test_a_plate_below_the_ankle_on_a_tilting_platform_is_accounted_for():
    body = winter(1)
    load = BodyLoad.of(body)
    recording = _trial(body, prts(amplitude_deg=4.0))
    cop, force = cop_of_motion(body, recording.theta, recording.tilt, RATE_HZ,
                               ankle_height_m=0.08)
    truth = body.com_angles(recording.theta)[:, 0]
    inner = slice(int(2 * RATE_HZ), -int(2 * RATE_HZ))

    def error(height):
        com = com_angle_from_cop(1e3 * cop, RATE_HZ, load, recording.tilt, force,
                                 CopOptions(ankle_height_m=height))
        return np.sqrt(np.mean((com - truth + truth.mean())[inner] ** 2)) / np.std(truth)

    assert error(0.08) < 0.005
    assert error(0.0) > 0.1  # the weight's share along the tilted plate, left out


def _frf_ratio(body, stimulus, seed, frequencies):
    """(F,) complex: the COM FRF from the COP over the FRF of the COM itself; the platform
    level for 5 s after the stimulus (the route's end effect outside the analysed cycles,
    as in a lab's trial)."""
    stimulus = stimulus.spanning(stimulus.duration + 5.0)
    recording = _trial(body, stimulus, seed=seed, motor_deg=0.3)
    cop, _ = cop_of_motion(body, recording.theta, recording.tilt, RATE_HZ)
    com = com_angle_from_cop(1e3 * cop, RATE_HZ, BodyLoad.of(body), recording.tilt)
    truth = frequency_response(prepare_trial(recording, stimulus, rate_hz=None), body)
    from_cop = frequency_response(prepare_trial(
        Recording(recording.time, recording.tilt, com[:, None], ("COM",)), stimulus,
        rate_hz=None))
    ratio = from_cop.response[:, 0] / truth.response[:, -1]
    f = truth.frequencies_hz
    return np.array([ratio[np.argmin(np.abs(f - x))] for x in frequencies])


@pytest.mark.slow("FRFs of five simulated trials with motor noise")
@pytest.mark.parametrize("segments, highest_hz", [(1, 1.0), (2, 0.5)])
def test_the_com_frf_from_the_cop_is_the_coms_within_5_percent_and_3_degrees(segments,
                                                                            highest_hz):
    """Both PRTSs and sinusoids at 0.1, 0.2 and 0.4 Hz, motor noise: the gain within 5 %
    and the phase within 3° from 0.05 Hz to 1 Hz for a body that turns as one, to 0.5 Hz
    for one that bends at the hip (whose own motion the COP sees and the COM does not:
    the phase lags by more above, docs/lab_recordings.md)."""
    body = winter(segments)
    wanted = np.array([0.05, 0.1, 0.2, 0.3, 0.4, 0.5, 0.7, 0.9, 1.0])
    wanted = tuple(wanted[wanted <= highest_hz + 1e-9])
    checks = [(prts(cycles=2, states=242), wanted), (prts(cycles=4, states=80), wanted[1:])]
    for f in (0.1, 0.2, 0.4):
        protocol = SumOfSinesProtocol(frequencies_hz=(f,), amplitudes_deg=(1.0,),
                                      cycles=int(round(8 * f * 10)))
        checks.append((protocol.profile(), (f,)))
    for seed, (stimulus, frequencies) in enumerate(checks):
        ratio = _frf_ratio(body, stimulus, seed, frequencies)
        assert np.all(np.abs(np.abs(ratio) - 1) < 0.05), (stimulus.description, ratio)
        assert np.all(np.abs(np.degrees(np.angle(ratio))) < 3.0), (stimulus.description,
                                                                   ratio)


def test_units_and_forces_that_are_not_a_standing_bodys_are_refused():
    load = BodyLoad.of(winter(1))
    cop = np.sin(np.arange(500) / 50.0)
    in_cm = com_angle_from_cop(cop, RATE_HZ, load, options=CopOptions(unit=CopUnit.CM))
    in_mm = com_angle_from_cop(cop, RATE_HZ, load)
    assert np.allclose(in_cm, 10 * in_mm)
    with pytest.raises(RecordingError, match="normal force's median"):
        com_angle_from_cop(cop, RATE_HZ, load, normal_force_n=np.full(500, 68.0))
    with pytest.raises(RecordingError, match="not finite"):
        com_angle_from_cop(np.where(np.arange(500) == 7, np.nan, cop), RATE_HZ, load)
    with pytest.raises(RecordingError, match="ankle height"):
        CopOptions(ankle_height_m=-0.1)
    assert math.isfinite(float(in_mm.sum()))


# ---------------------------------------------------------------- a force plate's file


def _lab_file(tmp_path, segments=2, export=None, seed=3):
    """A DEC subject's trial on the 80-state PRTS with a level tail, written as the plate
    exports it; (path, body, true body-COM sway (S,) rad on the file's samples)."""
    from posture_id.force_plate.writing import LAB_EXPORT, write_force_plate_csv

    body = winter(segments)
    stimulus = prts(cycles=3, states=80)
    stimulus = stimulus.spanning(stimulus.duration + 5.0)
    recording = _trial(body, stimulus, seed=seed, motor_deg=0.2)
    path = write_force_plate_csv(tmp_path / "trial.txt", body, recording, 0.1, seed,
                                 export or LAB_EXPORT)
    return path, body, body.com_angles(recording.theta)[:, 0]


def test_a_force_plate_file_is_read_as_the_body_com_sway(tmp_path):
    from dataclasses import replace

    from posture_id.force_plate.reading import ForcePlateColumns, read_force_plate
    from posture_id.force_plate.writing import LAB_EXPORT

    path, body, truth = _lab_file(tmp_path, segments=1,
                                  export=replace(LAB_EXPORT, delimiter=";",
                                                 decimal_comma=True))
    columns = ForcePlateColumns(cop="COP AP", time="Time", tilt="Platform", force="Fz")
    recording = read_force_plate(path, columns, body)
    assert recording.segments == body.segment_names and recording.duration_s == pytest.approx(
        65.0, abs=0.02)
    inner = slice(200, -200)
    error = recording.theta[inner, 0] - truth[inner] + truth.mean()
    assert np.sqrt(np.mean(error**2)) < 0.01 * np.std(truth)
    assert recording.source["force_plate"]["cop_unit"] == "mm"
    # a unit that contradicts the header, a header unit that is no length: refused
    with pytest.raises(RecordingError, match=r"in mm by its header.*--cop-units cm"):
        read_force_plate(path, replace(columns, cop_unit=CopUnit.CM), body)
    with pytest.raises(RecordingError, match="must be a length"):
        read_force_plate(path, replace(columns, cop="Fz", force=None), body)
    with pytest.raises(RecordingError, match="no column|COP XY"):
        read_force_plate(path, replace(columns, cop="COP XY"), body)


def test_the_command_line_reads_a_force_plate_trial_as_a_lab_wrote_it(tmp_path, capsys):
    import json

    from posture_id.cli import main

    path, body, _ = _lab_file(tmp_path, segments=2)
    flags = ["--time-column", "Time", "--time-units", "ms", "--tilt-column", "Platform",
             "--cop-column", "COP AP", "--cop-units", "mm"]
    out = tmp_path / "trial.frf.json"
    assert main(["frf", str(path), "--body", str(body.urdf_path), *flags, "--out",
                 str(out)]) == 0
    err = capsys.readouterr().err
    assert "as one segment" in err  # a 2-segment body: its COM sway is what the plate gives
    frf = json.loads(out.read_text())
    assert list(frf["channels"]) == ["body", "body COM"]
    # how the sway was derived travels with the result
    assert frf["provenance"]["recording_source"]["force_plate"]["body"].startswith(body.name)
    assert min(frf["frequencies_hz"]) == pytest.approx(0.05)
    for bad, why in ((["frf", str(path), *flags, "--out", str(out)], "--body"),
                     (["frf", str(path), "--body", str(body.urdf_path), *flags,
                       "--angle-columns", "Platform", "--out", str(out)], "two sources"),
                     (["frf", str(path), "--body", str(body.urdf_path), "--cop-units", "mm",
                       "--out", str(out)], "go with --cop-column")):
        assert main(bad) == 2
        assert why in capsys.readouterr().err


def test_a_cop_that_is_not_a_standing_persons_is_refused_and_a_negative_force_said(tmp_path):
    """A COP column read in the wrong unit (mm as m: gains 1000 times too large; m as mm)
    or constant is refused, naming the unit that fits; a force whose sign is negative is
    used by its magnitude and said, as is one that falls below half the weight."""
    from dataclasses import replace

    from posture_id.force_plate.reading import ForcePlateColumns, read_force_plate

    path, body, _ = _lab_file(tmp_path, segments=1)
    lines = path.read_text().splitlines()
    bare = tmp_path / "bare.txt"  # the header without its units
    bare.write_text("\n".join([lines[0], "Time\tPlatform\tCOP AP\tFz", *lines[2:]]) + "\n")
    columns = ForcePlateColumns(cop="COP AP", time="Time", tilt="Platform",
                                time_unit=TimeUnit.MILLISECONDS)
    with pytest.raises(RecordingError, match=r"'COP AP'.*spans .* m\).*more than a standing "
                                             r"person's.*is it in mm"):
        read_force_plate(bare, replace(columns, cop_unit=CopUnit.M), body)
    read = read_force_plate(bare, replace(columns, cop_unit=CopUnit.MM), body)
    assert not any("COP" in n or "force" in n for n in read.notices)

    def edited(name, column, change):
        rows = [line.split("\t") for line in lines[2:]]
        for k, row in enumerate(rows):
            row[column] = change(k, float(row[column]))
        out = tmp_path / name
        out.write_text("\n".join(lines[:2] + ["\t".join(r) for r in rows]) + "\n")
        return out

    with pytest.raises(RecordingError, match="the COP is constant"):
        read_force_plate(edited("flat.txt", 2, lambda k, v: "3.5"), columns, body)
    negative = read_force_plate(edited("down.txt", 3, lambda k, v: f"{-v:.1f}"),
                                replace(columns, force="Fz"), body)
    upward = read_force_plate(path, replace(columns, force="Fz"), body)
    np.testing.assert_allclose(negative.theta, upward.theta)
    assert any("normal force is negative" in n for n in negative.notices)
    off = read_force_plate(edited("off.txt", 3, lambda k, v: "20" if 3000 <= k < 3050
                                  else f"{v:.1f}"), replace(columns, force="Fz"), body)
    assert any("below half the body's weight in 50 sample(s) from 30.00" in n
               for n in off.notices)


def test_the_subjects_mass_is_what_the_plate_weighs_while_it_rests_level(tmp_path):
    """Four load cells in kg (a real plate's ``Capteur (Kg)(...)``), the subject shifting
    weight while the platform tilts and a lab's tare drifting at rest: the mass is the
    median of the cells' sum where the platform rests level; a force in N is divided by
    g; a column of another unit, no unit, or a sum that is no person's is refused."""
    from posture_id.force_plate.load import LoadColumns, LoadUnit, standing_mass

    rng = np.random.default_rng(2)
    t = np.arange(6000) / 100.0
    tilt = np.where((t > 20) & (t < 40), 3.0 * np.sin(2 * np.pi * 0.2 * (t - 20)), 0.0)
    weight = 64.3 + 0.1 * rng.standard_normal(len(t)) + np.where(tilt != 0, 4 * tilt, 0)
    shares = (0.3, 0.2, 0.27, 0.23)
    names = [f"Capteur (Kg)({c})" for c in ("NO", "NE", "SO", "SE")]
    path = tmp_path / "plate.txt"
    path.write_text("\t".join(["temps (en ms)", "Angle(degre)", *names, "Fz [N]"]) + "\n"
                    + "".join("\t".join([f"{10 * k}", f"{a:.3f}",
                                         *(f"{w * s:.3f}" for s in shares), f"{9.81 * w:.2f}"])
                              + "\n" for k, (a, w) in enumerate(zip(tilt, weight, strict=True))))
    cells = standing_mass(path, LoadColumns(tuple(names)), "Angle(degre)")
    assert cells.unit is LoadUnit.KG and cells.mass_kg == pytest.approx(64.3, abs=0.02)
    assert cells.samples == int(np.sum(np.abs(tilt) <= 0.05))
    assert "64.3 kg" in cells.notice and "rests level" in cells.notice
    force = standing_mass(path, LoadColumns(("Fz",)), "Angle(degre)")
    assert force.unit is LoadUnit.N and force.mass_kg == pytest.approx(64.3, abs=0.02)
    everything = standing_mass(path, LoadColumns(tuple(names)))  # no tilt: every sample
    assert everything.samples == len(t)
    with pytest.raises(RecordingError, match="plate.txt: the load columns' headers state no unit"):
        standing_mass(path, LoadColumns(("Angle(degre)",)))
    with pytest.raises(RecordingError, match="by their headers, not N"):
        standing_mass(path, LoadColumns(tuple(names), LoadUnit.N))
    with pytest.raises(RecordingError, match="sum to 19.*not a person's"):
        standing_mass(path, LoadColumns((names[0],)), "Angle(degre)")
