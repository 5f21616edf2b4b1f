# %% [markdown]
# # A lab's recording to DEC parameters
#
# A jupytext "percent" script: run it as it is (`python docs/tutorials/lab_recording.py`;
# it writes its result and plot in the folder it runs in) or open it as a notebook with
# jupytext. `make test` runs it (`tests/test_tutorials.py`).
#
# The file is a lab's, as the lab wrote it (`posture_id/studies/examples/lab_subject.csv`,
# made by `make examples`): the body-COM sway of one subject at 100 Hz, columns
# `time,platform,COM_x` in seconds and degrees; an 80-state PRTS started part-way into its
# cycle after a lead-in, with a platform lag, and a level stretch after the last cycle.
# Nobody says which stimulus it was.

# %%
import json
import subprocess
import sys
from pathlib import Path

from posture_id import DecParameters, load_body
from posture_id.fitting import FitOptions
from posture_id.frf.locked import LockedOptions
from posture_id.identify import Identifier, Method
from posture_id.recording import Recording, RecordingColumns
from posture_id.studies.demo import EXAMPLES_DIR as EXAMPLES  # the shipped examples

recording_file = EXAMPLES / "lab_subject.csv"
body = load_body(EXAMPLES / "lab_subject.urdf")  # 1 segment: the lab records the COM only
print(recording_file.read_text().splitlines()[:3])

# %% [markdown]
# ## By the command line alone
#
# Name the columns; the stimulus is found in the platform column. The locked fit compares
# only the stimulus-locked sway (real sway is mostly not locked), with a prior that keeps
# what the recording does not determine near the defaults.

# %%
posture_id_command = str(Path(sys.executable).with_name("posture-id"))  # in the venv
command = [posture_id_command, "identify", str(recording_file),
           "--body", str(body.urdf_path), "--angle-columns", "COM_x", "--time-column", "time",
           "--tilt-column", "platform", "--method", "fit", "--locked", "--prior-sd", "0.5",
           "--out", "lab_subject.result.json"]
print(subprocess.run(command, check=True, capture_output=True, text=True).stdout)
result = json.loads(Path("lab_subject.result.json").read_text())
segment = body.segment_names[0]
print("locked sway explained:", result["segments"][segment]["locked_variance_explained"])

# %% [markdown]
# ## The same in Python
#
# An `Identifier` is built once (for a body, a method and its options) and identifies as
# many recordings as you give it.

# %%
columns = RecordingColumns(time="time", tilt="platform", angles=("COM_x",))
recording = Recording.from_lab_csv(recording_file, columns, body.segment_names)
identifier = Identifier(body, Method.FIT,
                        fit_options=FitOptions(locked=LockedOptions(), prior_sd=0.5))
answer = identifier.identify(recording)
print(answer.summary())

# %% [markdown]
# The example is simulated, so its truth is known: how close did it get?

# %%
truth = DecParameters.from_json(EXAMPLES / "lab_subject.truth.json", body)
joint = body.joint_names[0]
error = answer.parameters[joint].kp / truth[joint].kp - 1
print(f"Kp {answer.parameters[joint].kp:.0f} N·m/rad against {truth[joint].kp:.0f}: "
      f"{100 * error:+.1f} %")
low, high = answer.intervals.lower_si[0, 0], answer.intervals.upper_si[0, 0]
inside = low <= truth[joint].kp <= high
print(f"its 90 % interval [{low:.0f}, {high:.0f}] holds the truth: {inside}")
assert abs(error) < 0.1 and answer.segments[0].locked_variance_explained > 0.9
answer.plot("lab_subject.png")

# %% [markdown]
# ## When the platform's angle was not recorded, and the onset is only roughly known
#
# Some labs keep only the sway; the stimulus is then named by its flags, and its onset
# rests on the lab's clock. Here the same file without its `platform` column, with the
# onset given 2 s late (3.97 s for 1.97 s). The default method notices that its answer
# leaves more than the recording's noise on a stimulus that was named, not recorded,
# finds in the sway where the stimulus really ran (within half a cycle), and identifies
# the recording there; it says so in a notice.

# %%
sway_only = Path("lab_subject.sway_only.csv")
lines = recording_file.read_text().splitlines()
sway_only.write_text("\n".join(",".join(line.split(",")[::2]) for line in lines) + "\n")
print(sway_only.read_text().splitlines()[:2])  # time,COM_x
named = ["--states", "80", "--cycles", "3", "--amplitude-deg", "1", "--start-state", "36.48",
         "--lag-s", "0.04", "--onset-s", "3.97"]  # the lab's onset: 1.97 s
command = [posture_id_command, "identify", str(sway_only), "--body", str(body.urdf_path),
           "--time-column", "time", "--tilt-column", "none", "--angle-columns", "COM_x",
           *named, "--out", "lab_subject.onset.json"]
shown = subprocess.run(command, check=True, capture_output=True, text=True).stdout
print(shown)
result = json.loads(Path("lab_subject.onset.json").read_text())
check = result["trust"]["noise_check"]
print(f"trust: {result['trust']['level']}; locked residual {check['ratio']:.2f}× the noise")
assert check["consistent"] or "--max-offset-s" in shown
assert any("the sway says it ran -2.0" in notice for notice in result["notices"])
