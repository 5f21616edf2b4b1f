# %% [markdown]
# # The independent-channel model beside DEC
#
# A jupytext "percent" script (`python docs/tutorials/ic_model.py`; `make test` runs it,
# `tests/test_tutorials.py`). Most posture-control studies report the parameters of
# Peterka's independent-channel (IC) model; posture_id fits it to the same recordings as
# DEC (docs/model.md §8, `docs/ic.md`) and says which of the two a recording supports.

# %%
import json
import subprocess
import sys
from pathlib import Path

from posture_id import load_body
from posture_id.bodies.anthropometry import straight_links, winter_segments
from posture_id.bodies.urdf_writer import write_chain_urdf
from posture_id.comparison.models import compare_models
from posture_id.fitting.frequency import fit_ic
from posture_id.models.ic import IcParameters, IcPlant, simulate_ic
from posture_id.simulation.stimulus import prts
from posture_id.studies.demo import EXAMPLES_DIR as EXAMPLES  # the shipped examples
from posture_id.trials import prepare_trial

# a 1.75 m, 70 kg subject as legs and trunk (Winter's anthropometry)
write_chain_urdf("subject.urdf", "subject", straight_links(winter_segments(1.75, 70.0, 2)))
body = load_body("subject.urdf")
plant = IcPlant.of(body)  # the body as one pendulum: J about the ankle, m·g·h
print(f"J = {plant.inertia:.1f} kg·m², m·g·h = {plant.mgh:.0f} N·m/rad")

# %% [markdown]
# ## A subject balanced by the IC model, and its parameters back
#
# Parameters in SI units; W is the proprioceptive weight (how much of the platform's tilt
# the subject takes as vertical), G and τ_f the positive torque feedback.

# %%
truth = IcParameters(kp=1.8 * plant.mgh, kd=0.4 * plant.mgh, delay_s=0.16, w=0.5,
                     torque_feedback_gain=0.25, torque_feedback_time_s=15.0)
stimulus = prts(1.0, 6, 80)  # the 80-state PRTS, 6 cycles of 20 s
recording = simulate_ic(body, truth, stimulus).with_sensor_noise(0.02, seed=1)
fit = fit_ic(prepare_trial(recording, stimulus), body)
print(fit.summary())
for name in ("kp", "kd", "delay_s", "w"):
    error = getattr(fit.parameters, name) / getattr(truth, name) - 1
    print(f"{name}: {100 * error:+.2f} %")
    assert abs(error) < 0.05
fit.plot("ic_fit.png")  # the locked FRF of the COM sway with the model over it

# %% [markdown]
# ## Which model does the sway support?
#
# `compare` fits both and judges them on every harmonic up to 2 Hz, the stimulated ones
# and the others, in units of the recording's noise: a model is preferred only when the
# other misses the sway beyond its noise, by an information criterion that counts
# parameters, and when the held-out cycle does not say otherwise.

# %%
ic_verdict = compare_models(prepare_trial(recording, stimulus), body)
print(ic_verdict.summary())
assert ic_verdict.preferred == "ic"
ic_verdict.plot("compare_ic_subject.png")

# %% [markdown]
# ## A lab's recording by the command line
#
# The shipped lab-like example (the COM only, an 80-state PRTS started part-way into its
# cycle, 100 Hz): the IC parameters, then both models side by side. Its subject was made by
# DEC with people's noise: both models explain its locked sway within the noise, and the
# comparison says the recording cannot tell them apart.

# %%
posture_id_command = str(Path(sys.executable).with_name("posture-id"))
lab = [str(EXAMPLES / "lab_subject.csv"), "--body", str(EXAMPLES / "lab_subject.urdf"),
       "--angle-columns", "COM_x", "--time-column", "time", "--tilt-column", "platform"]
shown = subprocess.run([posture_id_command, "fit", *lab, "--model", "ic", "--out",
                        "lab_ic.json"], capture_output=True, text=True)
print(shown.stdout)
assert shown.returncode in (0, 1)  # 1: written, its verdict doubtful
shown = subprocess.run([posture_id_command, "compare", *lab, "--out", "lab_compare.json",
                        "--plot", "lab_compare.png"], capture_output=True, text=True)
print(shown.stdout)
verdict = json.loads(Path("lab_compare.json").read_text())
print("preferred:", verdict["preferred"], "|", verdict["reason"])
assert verdict["preferred"] in ("dec", "undecided")
