# %% [markdown]
# # Norms and groups: is this subject, this patient group, this robot within the human range?
#
# A jupytext "percent" script (`python docs/tutorials/norms.py`; `make test` runs it,
# `tests/test_tutorials.py`). A simulated healthy cohort makes a normative set of FRFs at
# Peterka's 11 points; a healthy subject left out of it, a patient group with a longer
# delay and a humanoid are tested against it (`docs/norms.md`).

# %%
import json
import subprocess
import sys
from pathlib import Path

import numpy as np

import posture_id
from posture_id import load_body
from posture_id.dec.parameters import default_parameters
from posture_id.dec.prior import sample_parameters
from posture_id.frf.analysis import frequency_response
from posture_id.frf.bands import PETERKA_11
from posture_id.frf.response import FrfOptions
from posture_id.norms.norm import Norm, against_norm
from posture_id.norms.readers import frf_from_json
from posture_id.simulation import prts, simulate
from posture_id.simulation.noise import MotorNoise
from posture_id.trials import prepare_trial

posture_id_command = str(Path(sys.executable).with_name("posture-id"))
body = load_body()  # the TIP
stimulus = prts(1.0, 6, 80)  # the 80-state PRTS: a 20 s cycle, six cycles
labs_way = FrfOptions.lab_convention(PETERKA_11)  # first cycle out, no drift removed


def subject_frf(params, seed: int, name: str, who=body) -> Path:
    """One subject's FRF JSON at Peterka's points (people's motor and sensor noise)."""
    recording = simulate(who, params, stimulus, motor_noise=MotorNoise(0.3, seed=seed))
    trial = prepare_trial(recording.to_recording().with_sensor_noise(0.05, seed), stimulus,
                          rate_hz=None)
    path = Path(f"{name}.frf.json")
    frequency_response(trial, who, labs_way).to_json(path)
    return path


rng = np.random.default_rng(7)
classes = default_parameters(body).array("sign")  # everyone controls as the paper's subject


def cohort(n: int):
    """n subjects: gains and delays within ±15 % (docs/model.md §5's prior, narrowed), classes
    the default ones."""
    params = sample_parameters(body, n, rng, sigma=0.15)
    params.sign[:] = classes
    return params


healthy = cohort(20)
healthy_files = [subject_frf(healthy.trial(i, body.joint_names), i, f"healthy{i:02d}")
                 for i in range(20)]
patients = cohort(12)
patients.delay_s[:] *= 1.6  # a patient group with longer delays
patient_files = [subject_frf(patients.trial(i, body.joint_names), 100 + i, f"patient{i:02d}")
                 for i in range(12)]
print(json.loads(healthy_files[0].read_text())["frequencies_hz"])

# %% [markdown]
# ## The norm: 19 healthy subjects, one left out to test

# %%
run = {"capture_output": True, "text": True}
shown = subprocess.run([posture_id_command, "norm", "build", *map(str, healthy_files[1:]),
                        "--channel", "body COM", "--bootstrap", "500", "--out", "norm.json"],
                       check=True, **run)
print(shown.stderr)
left_out = subprocess.run([posture_id_command, "norm", "test", str(healthy_files[0]),
                           "--norm", "norm.json", "--out", "healthy00.test.json",
                           "--plot", "healthy00.test.png"], **run)
print(left_out.stdout)
tested = json.loads(Path("healthy00.test.json").read_text())
assert tested["inside_prediction_band"] and left_out.returncode == 0

# %% [markdown]
# ## Do the patients differ from the healthy, and where?

# %%
shown = subprocess.run([posture_id_command, "norm", "compare", "--group",
                        *map(str, healthy_files), "--group", *map(str, patient_files),
                        "--names", "healthy", "patients", "--channel", "body COM",
                        "--permutations", "999", "--bootstrap", "300", "--out",
                        "groups.json", "--plot", "groups.png"], check=True, **run)
print(shown.stdout)
groups = json.loads(Path("groups.json").read_text())
assert groups["p_value"] < 0.01

# %% [markdown]
# ## How human-like is a humanoid?
#
# TALOS lumped into three segments (a bent posture), with the default DEC gains for its
# own m·g·h: its body COM FRF against the norm, its score beside the healthy members'.

# %%
robot = load_body(Path(posture_id.__file__).parents[1] / "urdf" / "talos_tip.urdf")
robot_file = subject_frf(None, 999, "talos", robot)
shown = subprocess.run([posture_id_command, "norm", "test", str(robot_file), "--norm",
                        "norm.json", "--out", "talos.test.json"], **run)
print(shown.stdout)
robot_score = json.loads(Path("talos.test.json").read_text())["human_likeness"]
norm = Norm.from_json("norm.json")
members = [against_norm(norm, *frf_from_json(f, norm.channels)[:2]).human_likeness
           for f in healthy_files[1:]]
patients_scores = [against_norm(norm, *frf_from_json(f, norm.channels)[:2]).human_likeness
                   for f in patient_files]
print(f"human-likeness: the norm's members {min(members):.1f}–{max(members):.1f}, the "
      f"left-out healthy subject {tested['human_likeness']:.1f}, the patients "
      f"{min(patients_scores):.1f}–{max(patients_scores):.1f}, TALOS {robot_score:.1f}")
assert np.median(patients_scores) > np.median(members)
