# %% [markdown]
# # The Python API in ten steps
#
# A jupytext "percent" script (`python docs/tutorials/python_api.py`; it writes into the
# folder it runs in); `make test` runs it (`tests/test_tutorials.py`).

# %%
import numpy as np

from posture_id import Recording, load_body, prts, sample_parameters, simulate
from posture_id.identify import Identifier, Method
from posture_id.trials import prepare_trial

# 1. A body: the default triple inverted pendulum (or any URDF: load_body("robot.urdf")).
body = load_body()
print(body.joint_names, "m·g·h", np.round(body.mgh, 1))

# 2. A subject: DEC parameters drawn from docs/model.md §5's prior, every module's class too.
truth = sample_parameters(body, 1, np.random.default_rng(3)).trial(0, body.joint_names)

# 3. A trial on the tilting platform: the 242-state PRTS, 2 cycles, 1° peak to peak.
trial = simulate(body, truth, prts(amplitude_deg=1.0, cycles=2))
print(trial.summary())
trial.plot("trial.png")

# 4. What a lab would record: the sway with 0.01° of sensor noise, as a CSV.
trial.to_recording().with_sensor_noise(0.01, seed=1).to_csv("subject.csv")

# %%
# 5. Read it back; every recording goes in through one entrance, which finds its
#    stimulus (here the PRTS, recognised in the tilt column) and checks it once.
recording = Recording.from_csv("subject.csv", body.segment_names)
print(prepare_trial(recording).stimulus.description)

# 6. An identifier, built once: the bundled CNN (milliseconds), or Method.HYBRID for the
#    CNN's answer refined by least squares.
identifier = Identifier(body, Method.CNN)
result = identifier.identify(recording)
print(result.summary())

# %%
# 7. Every answer has an interval and a verdict on what the recording determines.
print(result.intervals.sentences())

# 8. The classes, and Kp against the truth (the subject is simulated).
for joint in body.joint_names:
    got, true = result.parameters[joint], truth[joint]
    print(f"{joint}: {got.controls} (truth {true.controls}), Kp {got.kp:.0f} against "
          f"{true.kp:.0f}")
assert result.classes == tuple(truth[j].controls for j in body.joint_names)

# 9. Everything as JSON (strict: its "parameters" object is a parameter file) ...
result.to_json("result.json")
# 10. ... and as plots: recorded against re-simulated sway, and the intervals.
result.plot("result.png")
result.plot_intervals("intervals.png")

# %% [markdown]
# The CNN alone can be some way off, as its intervals say; `Method.HYBRID` refines its
# answer by least squares (seconds a recording once the fit model is compiled: about a
# minute, once per number of segments and recording length: every body shares it).
