# %% [markdown]
# # A cohort: every subject with a body of their own
#
# A jupytext "percent" script (`python docs/tutorials/cohort.py`; it writes into the folder
# it runs in); `make test` runs it (`tests/test_tutorials.py`).
#
# A lab measured three subjects. Each gets an anthropometric body from their height and
# mass (Winter's tables, 2 segments: legs and trunk), and the cohort is identified in one
# command: `--bodies` names the folder of the subjects' bodies, one URDF per recording.
# Here the recordings are simulated, so that the answers can be checked.

# %%
import csv
import subprocess
import sys
from pathlib import Path

from posture_id import load_body, sample_parameters, simulate
from posture_id.identify import Identifier
from posture_id.identify.cohort import find_recordings, identify_cohort

posture_id_command = str(Path(sys.executable).with_name("posture-id"))  # in the venv
recordings, bodies = Path("recordings"), Path("bodies")
recordings.mkdir(exist_ok=True)
bodies.mkdir(exist_ok=True)
subjects = {"ann": (1.62, 58.0), "bob": (1.85, 90.0), "cem": (1.74, 71.0)}
truths = {}
for seed, (name, (height, mass)) in enumerate(subjects.items()):
    urdf = bodies / f"{name}.urdf"
    subprocess.run([posture_id_command, "body", "--height", str(height), "--mass", str(mass),
                    "--segments", "2", "--out", str(urdf)], check=True, capture_output=True)
    body = load_body(urdf)
    while True:  # a subject from docs/model.md §5's prior who keeps their balance
        import numpy as np

        truth = sample_parameters(body, 1, np.random.default_rng(seed)).trial(
            0, body.joint_names)
        trial = simulate(body, truth)
        seed += 10
        if trial.stable:
            break
    trial.to_recording().with_sensor_noise(0.01, seed).to_csv(recordings / f"{name}.csv")
    truths[name] = truth

# %% [markdown]
# ## The cohort, by the command line
#
# One JSON per recording and `summary.csv` (status, body, method, classes, E_rel, every
# module's parameters); a run stopped part-way continues where it stopped. The default
# method, the CNN, takes milliseconds a recording; `--method hybrid` refines each answer
# by least squares; the fit model is compiled once for all the subjects' bodies (their
# constants are inputs of the compiled code, docs/fit.md).

# %%
subprocess.run([posture_id_command, "identify", str(recordings), "--bodies", str(bodies),
                "--out", "results"], check=True)
for row in csv.DictReader(Path("results/summary.csv").open()):
    print(row["recording"], row["body"], row["classes"], f"Kp ankle {float(row['ankle_kp']):.0f}")

# %% [markdown]
# ## Its summary plot, and the answers against the truth
#
# In Python the same cohort is one call; finished recordings are read back, not redone.

# %%
result = identify_cohort(find_recordings(recordings), "results", Identifier(load_body()),
                         bodies=bodies)
result.plot("cohort.png")
for row in result.rows:
    name = Path(row["recording"]).stem
    truth = truths[name]
    error = row["ankle_kp"] / truth["ankle"].kp - 1
    right = row["classes"] == "/".join(m.controls for m in truth.modules.values())
    print(f"{name}: classes {row['classes']} (right: {right}), ankle Kp {100 * error:+.1f} % "
          "from the truth")
    assert right and abs(error) < 0.15
