# %% [markdown]
# # A force-plate study: trials as the lab wrote them, one fit per subject, a paired test
#
# A jupytext "percent" script: run it as it is (`python docs/tutorials/force_plate_study.py`;
# it writes its results in the folder it runs in) or open it as a notebook with jupytext.
# `make test` runs it (`tests/test_tutorials.py`).
#
# The shipped trial `posture_id/studies/examples/force_plate_trial.txt` (made by
# `make examples`: `python -m posture_id.studies.force_plate_study`) is a force plate's
# export as a posturography system writes it: tab-separated, a title line above the
# header, times in ms, the centre of pressure in mm, the platform level for 30 s, a fade-in,
# a ±1° sinusoid at 0.2 Hz, a fade-out and the platform level again. It holds no segment
# angle: the body's sway comes from the COP, through the subject's body.

# %%
import csv
import json
import subprocess
import sys
from pathlib import Path

from posture_id.studies.demo import EXAMPLES_DIR as EXAMPLES  # the shipped examples
from posture_id.studies.force_plate_study import make_study

trial = EXAMPLES / "force_plate_trial.txt"
print("\n".join(trial.read_text(encoding="utf-8").splitlines()[:4]))
posture_id = str(Path(sys.executable).with_name("posture-id"))  # in the venv


def run(*args: str) -> str:
    """The command line, as a user types it; its standard output."""
    done = subprocess.run([posture_id, *args], capture_output=True, text=True)
    print(done.stdout + done.stderr)
    assert done.returncode == 0, done.stderr
    return done.stdout


# %% [markdown]
# ## One trial's FRF
#
# The subject's body from the height and mass in the title line (a Winter body of one
# segment: the plate sees the body's COM), then the FRF with the file's own columns. The
# stimulus is found in the platform column: a sinusoid, its level stretches and fades left
# out, and the FRF lists its one frequency.

# %%
run("body", "--height-m", "1.77", "--mass-kg", "70.4", "--segments", "1", "--out",
    "subject.urdf")
plate = ["--time-column", "Time", "--time-units", "ms", "--tilt-column", "Platform",
         "--cop-column", "COP AP", "--cop-units", "mm"]
run("frf", str(trial), "--body", "subject.urdf", *plate, "--out", "trial.frf.json",
    "--plot", "trial.frf.png")
frf = json.loads(Path("trial.frf.json").read_text())
print("frequencies:", [round(f, 6) for f in frf["frequencies_hz"]])
assert [round(f, 6) for f in frf["frequencies_hz"]] == [0.2]

# %% [markdown]
# ## A study: six subjects, eyes open and closed, three sinusoids each
#
# The same lab's study, written by the project's own command: six subjects, each through
# sinusoids at 0.1, 0.2 and 0.4 Hz with the eyes open and closed (36 trials), and its
# manifest (a row per trial: subject, condition, file, height and mass).

# %%
manifest = make_study("study", subjects=6)
print("\n".join(manifest.read_text().splitlines()[:4]))

# %% [markdown]
# `posture-id study` makes every trial's FRF and fits each subject's six trials at once
# with the independent-channel model: Kp, Kd, the delay and the torque feedback the
# subject's own, shared by the conditions, the proprioceptive weight W one per condition.
# Then it tests, within the subjects, whether the conditions differ.

# %%
summary = run("study", str(manifest), "--out", "results", *plate, "--model", "ic",
              "--per-condition", "w", "--plot", "study.png")
with open("results/summary.csv") as fh:
    rows = list(csv.DictReader(fh))
truth = json.loads(Path("study/truth.json").read_text())
for row in rows:
    print(f"{row['subject']}: W eyes open {float(row['w [eyes_open]']):.2f} "
          f"(true {truth[row['subject']]['w']['eyes_open']}), eyes closed "
          f"{float(row['w [eyes_closed]']):.2f} "
          f"(true {truth[row['subject']]['w']['eyes_closed']})")
assert sum(float(r["w [eyes_closed]"]) > float(r["w [eyes_open]"]) for r in rows) >= 5

# %% [markdown]
# ## One subject, by hand
#
# The joint fit of one subject is `posture-id fit` with every trial and its condition:
# its plot draws every trial's FRF with the model of its condition over it.

# %%
with open(manifest) as fh:
    subject = [r for r in csv.DictReader(fh) if r["subject"] == "S01"]
run("body", "--height-m", subject[0]["height_m"], "--mass-kg", subject[0]["mass_kg"],
    "--segments", "1", "--out", "S01.urdf")
run("fit", *[str(manifest.parent / r["file"]) for r in subject], "--body", "S01.urdf",
    *plate, "--model", "ic", "--per-trial", "w",
    "--conditions", *[r["condition"] for r in subject],
    "--out", "S01.fit.json", "--plot", "S01.fit.png")
fit = json.loads(Path("S01.fit.json").read_text())
print("W per condition:", {c: round(v["w"], 3) for c, v in fit["per_condition"].items()})

# %% [markdown]
# ## The paired test, from the FRFs
#
# `norm compare --paired` takes the same subjects' FRFs in two conditions (the i-th file
# of each group the same subject): here each subject's 0.2 Hz trial, eyes open against
# eyes closed. With the eyes closed the body follows the platform more.

# %%
frfs = {c: sorted(Path("results/frf").glob(f"S*__S*_{c}_0_2Hz.json"))
        for c in ("eyes_open", "eyes_closed")}
run("norm", "compare", "--paired", "--group", *map(str, frfs["eyes_open"]),
    "--group", *map(str, frfs["eyes_closed"]), "--names", "eyes open", "eyes closed",
    "--out", "paired.json", "--plot", "paired.png")
paired = json.loads(Path("paired.json").read_text())
print("whole FRF: p =", paired["p_value"])
assert paired["p_value"] < 0.05
