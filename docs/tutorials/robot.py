# %% [markdown]
# # A humanoid's URDF to its identified DEC parameters, in Python
#
# A jupytext "percent" script (`python docs/tutorials/robot.py`; it writes into the folder
# it runs in); `make test` runs it (`tests/test_tutorials.py`). The same by the command
# line: `posture-id body --from-robot talos --out talos.urdf`, then `simulate` and
# `identify` with `--body talos.urdf`.

# %%
import numpy as np

import posture_id as pid

# 1. Lump the robot's whole-body URDF (here TALOS from example-robot-data; for your own:
#    pid.lump_robot("robot.urdf", ankle=(L, R), knee=(L, R), hip=(L, R))) into the chain
#    DEC balances: support, shank, thigh, trunk, each with its mass, COM and inertia.
lumped = pid.preset_body("talos")
body = pid.load_body(lumped.write("talos.urdf"))
print(body.name, body.segment_names, "m·g·h", np.round(body.mgh, 1), "N·m/rad")

# 2. A DEC controller for it: the defaults are the paper's ratios times its m·g·h.
controller = pid.default_parameters(body)

# 3. The robot on the tilting platform: the 242-state PRTS, 2 cycles, 1° peak to peak,
#    recorded with 0.01° of sensor noise.
trial = pid.simulate(body, controller, pid.prts(amplitude_deg=1.0, cycles=2))
assert trial.stable
recording = trial.to_recording().with_sensor_noise(0.01, seed=1)

# %%
# 4. Identify it with the bundled universal network, refined where needed (the default).
result = pid.identify(recording, body)
print(result.summary())

# 5. Every module's class is the controller's, and each Kp within 10 % of it.
for joint in body.joint_names:
    found, true = result.parameters[joint], controller[joint]
    print(f"{joint}: {found.controls} Kp {found.kp:.0f} against {true.kp:.0f} N·m/rad")
    assert found.controls == true.controls
    assert abs(found.kp / true.kp - 1) < 0.1
result.to_json("talos_result.json")
