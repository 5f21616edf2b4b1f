"""MuJoCo as an oracle of the compiled simulator: the TIP under DEC on the default PRTS,
stepped by both, and step-halved (tests/test_mujoco_oracle.py checks the same).

The default TIP (urdf/tip_default.urdf), its default DEC parameters and the default
stimulus (PRTS 242 states ×2, 1° peak to peak, 121 s): the compiled simulator at
2, 1, 0.5, 0.25 and 0.125 ms (its semi-implicit Euler), MuJoCo (posture_id.robots) with
RK4 at 2, 1 and 0.5 ms, and with its implicit-fast and Euler integrators at 1 ms. Every
run is compared with the compiled simulator at 0.125 ms (the nearest to the common
limit): RMS of the difference over RMS of the sway, per segment and for the body COM
(α_1,S). The limit of each engine is extrapolated from its two finest steps
(Richardson, first order: 2·x(h/2) − x(h)) and the two limits compared. Last, what the
comparison must resolve: the converged sway with one module's delay 1 ms longer.

Run:  .venv/bin/python benchmarks/mujoco_oracle.py
(about 40 s here; writes docs/results/mujoco_oracle/report.md and results.json)
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

from posture_id.bodies.body import load_body
from posture_id.dec.parameters import default_parameters
from posture_id.fileio import atomic_write_text, json_text
from posture_id.robots.errors import require_mujoco
from posture_id.robots.mujoco_model import MujocoOptions
from posture_id.robots.mujoco_sim import simulate_mujoco
from posture_id.simulation import SimulationOptions, prts, simulate

ROOT = Path(__file__).resolve().parents[1]
COMPILED_STEPS_MS = (2.0, 1.0, 0.5, 0.25, 0.125)
MUJOCO_RUNS = (("rk4", 2.0), ("rk4", 1.0), ("rk4", 0.5), ("implicitfast", 1.0),
               ("euler", 1.0))


def relative_rms(x: np.ndarray, reference: np.ndarray) -> list[float]:
    """Per column: RMS of x − reference over RMS of reference."""
    return np.sqrt(np.mean((x - reference) ** 2, axis=0)
                   / np.mean(reference**2, axis=0)).tolist()


def sway(result) -> np.ndarray:
    """(S, N + 1) segment angles and the body COM angle α_1,S, rad."""
    return np.column_stack([result.theta, result.alpha[:, 0]])


def percent(values: list[float], digits: int = 3) -> str:
    return " / ".join(f"{100 * v:.{digits}f}" for v in values)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=ROOT / "docs" / "results" / "mujoco_oracle")
    args = parser.parse_args()
    mujoco = require_mujoco()
    body = load_body()
    params = default_parameters(body)
    stimulus = prts()
    start = time.perf_counter()
    compiled, seconds = {}, {}
    for ms in COMPILED_STEPS_MS:
        t0 = time.perf_counter()
        compiled[ms] = sway(simulate(body, params, stimulus,
                                     SimulationOptions(dt=ms / 1000)))
        seconds[f"compiled {ms:g} ms"] = time.perf_counter() - t0
    engine = {}
    for integrator, ms in MUJOCO_RUNS:
        t0 = time.perf_counter()
        result = simulate_mujoco(body, params, stimulus, mujoco_options=MujocoOptions(
            timestep_s=ms / 1000, integrator=integrator))
        assert result.stable
        engine[(integrator, ms)] = sway(result)
        seconds[f"MuJoCo {integrator} {ms:g} ms"] = time.perf_counter() - t0
        print(f"MuJoCo {integrator} {ms:g} ms: {seconds[f'MuJoCo {integrator} {ms:g} ms']:.1f} s",
              flush=True)
    limit = compiled[0.125]
    rows = [{"engine": "compiled (semi-implicit Euler)", "step_ms": ms,
             "vs_limit": relative_rms(x, limit), "vs_compiled_2ms": relative_rms(x, compiled[2.0])}
            for ms, x in compiled.items()]
    rows += [{"engine": f"MuJoCo {integrator}", "step_ms": ms,
              "vs_limit": relative_rms(x, limit), "vs_compiled_2ms": relative_rms(x, compiled[2.0]),
              "vs_compiled_same_step": relative_rms(x, compiled[ms])}
             for (integrator, ms), x in engine.items()]
    engine_limit = 2.0 * engine[("rk4", 0.5)] - engine[("rk4", 1.0)]
    compiled_limit = 2.0 * compiled[0.125] - compiled[0.25]
    limits = relative_rms(engine_limit, compiled_limit)
    fine = SimulationOptions(dt=0.000125)
    delay_effect = {}
    for joint in body.joint_names:
        later = params.replace(joint, delay_s=params[joint].delay_s + 0.001)
        delay_effect[joint] = relative_rms(sway(simulate(body, later, stimulus, fine)), limit)
    total = time.perf_counter() - start
    channels = [*body.segment_names, "body COM"]
    results = {"command": ".venv/bin/python benchmarks/mujoco_oracle.py",
               "mujoco_version": mujoco.__version__, "seconds": total, "run_seconds": seconds,
               "channels": channels, "stimulus": stimulus.description, "rows": rows,
               "extrapolated_limits_relative_rms": limits,
               "delay_1ms_longer_relative_rms": delay_effect}
    args.out.mkdir(parents=True, exist_ok=True)
    atomic_write_text(args.out / "results.json", json_text(results))
    atomic_write_text(args.out / "report.md", report(results))
    print(f"wrote {args.out / 'report.md'} and results.json")


def report(r: dict) -> str:
    names = " / ".join(r["channels"])
    lines = [
        "# MuJoCo as an oracle of the compiled simulator",
        "",
        f"Made by `{r['command']}` ({r['seconds']:.0f} s on this 2-core machine; what it "
        "does: the script's docstring). The default TIP (`urdf/tip_default.urdf`), its "
        f"default DEC parameters, {r['stimulus']} (121 s); MuJoCo {r['mujoco_version']} "
        "through `posture_id.robots` (the platform prescribed, DEC in its loop, sensors read "
        "from its state: docs/robots.md).",
        "",
        f"RMS of the difference over RMS of the sway, in %, {names}:",
        "",
        "| engine | step | from the limit (compiled at 0.125 ms) | from the compiled "
        "simulator at 2 ms | from the compiled simulator at the same step | run |",
        "|---|---|---|---|---|---|",
    ]
    for row in r["rows"]:
        key = (f"compiled {row['step_ms']:g} ms" if row["engine"].startswith("compiled")
               else f"{row['engine']} {row['step_ms']:g} ms")
        same = row.get("vs_compiled_same_step")
        lines.append(f"| {row['engine']} | {row['step_ms']:g} ms | {percent(row['vs_limit'])} "
                     f"| {percent(row['vs_compiled_2ms'])} | "
                     f"{'' if same is None else percent(same)} | "
                     f"{r['run_seconds'][key]:.1f} s |")
    delay = r["delay_1ms_longer_relative_rms"]
    rows = {(row["engine"], row["step_ms"]): row for row in r["rows"]}
    compiled_2ms = rows[("compiled (semi-implicit Euler)", 2.0)]["vs_limit"]
    engine_1ms = rows[("MuJoCo rk4", 1.0)]["vs_limit"]
    criterion = rows[("MuJoCo rk4", 1.0)]["vs_compiled_2ms"]
    sides = [c / e for c, e in zip(compiled_2ms, engine_1ms, strict=True)]
    resolution = min(v / lim for effect in delay.values()
                     for v, lim in zip(effect, r["extrapolated_limits_relative_rms"], strict=True))
    lines += [
        "",
        "The two limits, each extrapolated from its two finest steps (2·x(h/2) − x(h); "
        "MuJoCo RK4 1 and 0.5 ms, compiled 0.25 and 0.125 ms), differ by "
        f"{percent(r['extrapolated_limits_relative_rms'], 5)} % of the sway.",
        "",
        "What that must resolve: the converged sway with one module's delay 1 ms longer "
        "differs from the default's by "
        + "; ".join(f"{joint} {percent(v)} %" for joint, v in delay.items()) + ".",
        "",
        "## Reading",
        "",
        "- The issue's criterion, MuJoCo RK4 at 1 ms against the compiled simulator at its "
        f"default 2 ms: {percent(criterion, 2)} %, under the 1 % bound.",
        "- Both engines are first order in their step and halve towards one limit: the "
        "controller runs once per step and holds its torque over it, and ∫ε and the tilt "
        "estimate advance by Euler steps, so MuJoCo's RK4 plant does not make its sway "
        "converge faster (its Euler and implicit-fast integrators, identical here since both "
        "treat the joint damping implicitly, are as close to the limit at 1 ms).",
        "- Which side the difference comes from: the compiled simulator at 2 ms is "
        f"{min(sides):.1f}–{max(sides):.1f} times further from the limit than MuJoCo at "
        "1 ms; the difference between the two is mostly the compiled simulator's 2 ms step "
        "(docs/model.md §2's own tolerance), not a difference of model.",
        f"- The extrapolated limits agree at least {resolution:.0f} times more closely "
        "than a 1 ms change of any one delay moves the sway: the two engines simulate the "
        "same continuous model (plant, torque law, delays, dead-band estimator, passive "
        "terms).",
    ]
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    main()
