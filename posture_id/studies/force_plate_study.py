"""A force-plate study as a posture lab runs one, simulated: the shipped example trial and
the tutorial's study (docs/tutorials/force_plate_study.py).

    python -m posture_id.studies.force_plate_study posture_id/studies/examples   # the trial
    python -m posture_id.studies.force_plate_study STUDY_FOLDER --study          # a study

Each subject (height and mass drawn around 1.75 m and 70 kg, a one-segment Winter body)
stands on a tilting platform over a force plate, eyes open and eyes closed, through
sinusoids at 0.1, 0.2 and 0.4 Hz (±1°): the platform level for 30 s, a 5 s fade-in, the
oscillation, a 5 s fade-out, level again for 30 s, sampled at 100 Hz. The subject is the
independent-channel model (docs/model.md §8) with Kp, Kd, the delay and the torque
feedback their own, drawn within :data:`SUBJECT_RANGES` (drawn again where the closed
loop peaks above three times the tilt: the subject stands through every trial), and the
proprioceptive weight W set by the condition (0.35 eyes open, 0.6 eyes closed: with the
eyes closed the body follows the platform more); motor noise leaves half of the body COM
sway locked. The file is what the plate records
(:func:`~posture_id.force_plate.writing.write_force_plate_csv`, the posturography export:
tab-separated, a title line, ms, ``COP AP [mm]``, ``Fz [N]``), with 0.2 mm of COP
noise. The study's ``manifest.csv`` names each trial's subject, condition, file, height and
mass; ``truth.json`` holds every subject's parameters.
"""

from __future__ import annotations

import argparse
from dataclasses import replace
from pathlib import Path

import numpy as np

from posture_id.errors import SimulationError
from posture_id.fileio import atomic_write_text, json_text

__all__ = ["CONDITIONS", "FREQUENCIES_HZ", "EXAMPLE_TRIAL", "lab_sinusoid",
           "write_trial", "make_example_trial", "make_study"]

#: The conditions and the proprioceptive weight W of each.
CONDITIONS = {"eyes_open": 0.35, "eyes_closed": 0.6}
#: The sinusoids' frequencies, Hz, and amplitude, deg (half the peak-to-peak).
FREQUENCIES_HZ = (0.1, 0.2, 0.4)
AMPLITUDE_DEG = 1.0
LEAD_S, MOVING_S, TAIL_S, FADE_S, RATE_HZ = 30.0, 80.0, 30.0, 5.0, 100.0
LOCKED_SHARE, COP_NOISE_MM = 0.5, 0.2
#: The subjects' own parameters: Kp and Kd as shares of m·g·h, the delay (s), the torque
#: feedback's gain and time constant (s); drawn uniformly.
SUBJECT_RANGES = {"kp": (1.5, 2.3), "kd": (0.3, 0.5), "delay_s": (0.12, 0.18),
                  "torque_feedback_gain": (0.0, 0.3), "torque_feedback_time_s": (10.0, 30.0)}
#: The shipped example: subject 1, eyes closed, 0.2 Hz.
EXAMPLE_TRIAL = "force_plate_trial.txt"


def lab_sinusoid(f_hz: float, amplitude_deg: float = AMPLITUDE_DEG):
    """The tilt a lab runs (:class:`~posture_id.simulation.stimulus.TiltProfile`): level,
    a raised-cosine fade-in, the sinusoid, a fade-out, level; at :data:`RATE_HZ`."""
    from posture_id.simulation.stimulus import tilt_from_array

    t = np.arange(int(round((LEAD_S + MOVING_S + TAIL_S) * RATE_HZ)) + 1) / RATE_HZ
    tau = t - LEAD_S
    envelope = ((tau >= 0) & (tau <= MOVING_S)).astype(float)
    rising, falling = (tau >= 0) & (tau < FADE_S), (tau > MOVING_S - FADE_S) & (tau <= MOVING_S)
    envelope[rising] = 0.5 - 0.5 * np.cos(np.pi * tau[rising] / FADE_S)
    envelope[falling] = 0.5 - 0.5 * np.cos(np.pi * (MOVING_S - tau[falling]) / FADE_S)
    tilt = np.radians(amplitude_deg * np.sin(2 * np.pi * f_hz * tau)) * envelope
    return tilt_from_array(t, tilt, f"sinusoid {f_hz:g} Hz ±{amplitude_deg:g}° (a lab's)")


def write_trial(path: Path, body, params, f_hz: float, seed: int,
                title: str) -> Path:
    """One trial of ``params`` (IC) on ``body`` at ``f_hz``, written as the plate's export."""
    from posture_id.force_plate.writing import LAB_EXPORT, write_force_plate_csv
    from posture_id.models.ic.subjects import ic_recording
    from posture_id.simulation.options import SimulationOptions

    stimulus = lab_sinusoid(f_hz)
    recording, _ = ic_recording(body, params, stimulus, LOCKED_SHARE, seed,
                                sensor_noise_deg=0.0, options=SimulationOptions(
                                    sample_rate_hz=RATE_HZ))
    if not np.all(np.isfinite(recording.theta)):
        raise SimulationError(f"{path.name}: the simulated subject falls ({params})")
    return write_force_plate_csv(path, body, recording, COP_NOISE_MM, seed,
                                 replace(LAB_EXPORT, title=title))


def _subject(k: int, attempt: int = 0):
    """Subject ``k``'s height, mass, body and shared IC parameters (``attempt``: drawn
    again after a subject who fell)."""
    from posture_id.bodies.anthropometry import winter_body_file
    from posture_id.bodies.body import load_body
    from posture_id.models.ic.model import IC
    from posture_id.models.ic.parameters import IcParameters

    rng = np.random.default_rng([k, 2026] + ([attempt] if attempt else []))
    height = round(float(rng.uniform(1.60, 1.90)), 2)
    mass = round(float(rng.uniform(55.0, 90.0)), 1)
    body = load_body(winter_body_file(height, mass, 1))
    plant = IC.plant(body)
    s = 2j * np.pi * np.linspace(0.05, 1.0, 96)
    while True:  # a subject who stands through every condition (no resonance above ×3)
        draw = {name: float(rng.uniform(*span)) for name, span in SUBJECT_RANGES.items()}
        params = IcParameters(**{**draw, "kp": draw["kp"] * plant.mgh,
                                 "kd": draw["kd"] * plant.mgh, "w": 0.5})
        if all(IC.is_stable(replace(params, w=w), plant)
               and np.abs(IC.closed_loop(replace(params, w=w), plant, s)).max() < 3.0
               for w in CONDITIONS.values()):
            return height, mass, body, params


def make_example_trial(folder: str | Path) -> Path:
    """Write the shipped example (:data:`EXAMPLE_TRIAL`) into ``folder``."""
    height, mass, body, params = _subject(1)
    params = replace(params, w=CONDITIONS["eyes_closed"])
    return write_trial(Path(folder) / EXAMPLE_TRIAL, body, params, 0.2, 101,
                       f"Posturography export, subject S01 ({height:g} m, {mass:g} kg), "
                       "eyes closed, sinusoid 0.2 Hz")


def _write_subject(folder: Path, name: str, body, params, frequencies_hz, k: int
                   ) -> list[tuple[str, str]]:
    """Every trial of one subject; (condition, file) each."""
    files = []
    for c, (condition, w) in enumerate(CONDITIONS.items()):
        for j, f in enumerate(frequencies_hz):
            file = f"{name}_{condition}_{f:g}Hz.txt"
            write_trial(folder / file, body, replace(params, w=w), f, 1000 * k + 10 * c + j,
                        f"Posturography export, subject {name}, {condition}, "
                        f"sinusoid {f:g} Hz")
            files.append((condition, file))
    return files


def make_study(folder: str | Path, subjects: int = 6,
               frequencies_hz: tuple[float, ...] = FREQUENCIES_HZ) -> Path:
    """Write a study of ``subjects`` subjects × :data:`CONDITIONS` × ``frequencies_hz``
    trials into ``folder``, with ``manifest.csv`` and ``truth.json``; the manifest's path."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    rows, truth = ["subject,condition,file,height_m,mass_kg"], {}
    for k in range(1, subjects + 1):
        name = f"S{k:02d}"
        for attempt in range(20):  # motor noise can tip a subject over: draw another
            height, mass, body, params = _subject(k, attempt)
            try:
                files = _write_subject(folder, name, body, params, frequencies_hz, k)
                break
            except SimulationError:
                continue
        else:
            raise SimulationError(f"{name}: no subject drawn stands through every trial")
        truth[name] = {"height_m": height, "mass_kg": mass,
                       "shared": {n: getattr(params, n) for n in
                                  ("kp", "kd", "delay_s", "torque_feedback_gain",
                                   "torque_feedback_time_s")},
                       "w": dict(CONDITIONS)}
        rows += [f"{name},{condition},{file},{height:g},{mass:g}"
                 for condition, file in files]
    atomic_write_text(folder / "truth.json", json_text(truth))
    return atomic_write_text(folder / "manifest.csv", "\n".join(rows) + "\n")


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("folder", type=Path)
    parser.add_argument("--study", action="store_true",
                        help="write a whole study (else the shipped example trial)")
    parser.add_argument("--subjects", type=int, default=6)
    args = parser.parse_args(argv)
    if args.study:
        print(make_study(args.folder, args.subjects))
    else:
        print(make_example_trial(args.folder))


if __name__ == "__main__":
    main()
