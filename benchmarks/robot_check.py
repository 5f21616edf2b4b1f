"""The robot check over the three humanoid presets: each whole body in MuJoCo, DEC at its
lumped joints, against its lumped chain simulated by posture_id (docs/robots.md).

TALOS, the Unitree G1 and the example-robot-data human, each lumped to 3 segments (the
default of docs/bodies.md), TALOS also to 2; one 60.5 s cycle of the 1° PRTS (242
states); the lumped chain's default DEC parameters. Five runs a body:

- **check**: as ``posture-id robot check`` runs it: the held joints' servos at the default
  ``WholeBodyOptions`` (100× m·g·h, critically damped), MuJoCo RK4 at the step chosen for
  the body (``posture_id.robots.stability.choose_step``), a figure;
- **half step**: the same at half that step (step-halving: the check is converged when
  the two agree);
- **rigid**: every held joint welded, exactly as the lumping assumes (what the servos'
  compliance adds is the check less this);
- **welds 1 ms**: rigid, with the feet's welds at half their time constant, 0.5 ms steps
  (what the welds' compliance adds);
- **solver 1e-8**: the check at MuJoCo's own constraint-solver tolerance instead of the
  project's 1e-15 (the defect put back: its force errors turn into sway through DEC's loop).

Per run: the variance of the MuJoCo sway the lumped prediction explains per segment and of
the body COM, the gain % and phase ° differences at every FRF point from 0.05 to 1 Hz,
whether it stays up, the run time, the step and how it was chosen, every armature added;
per body, the RMS difference of the MuJoCo sway between the check and each other run, as
a share of the sway's RMS.

Run:  .venv/bin/python benchmarks/robot_check.py
(about 8 minutes here; writes docs/results/robot_check/report.md, results.json and one
figure per body, the RobotCheck's own plot: talos.png, talos_2segments.png, g1.png,
human.png)
"""

from __future__ import annotations

import argparse
import dataclasses
import time
from pathlib import Path

import numpy as np

from posture_id.fileio import atomic_write_text, json_text
from posture_id.robots.check import CheckOptions, robot_check
from posture_id.robots.errors import require_mujoco
from posture_id.robots.mujoco_model import MujocoOptions
from posture_id.robots.whole_body import HeldJoints, WholeBodyOptions
from posture_id.simulation import prts

ROOT = Path(__file__).resolve().parents[1]
COMMAND = ".venv/bin/python benchmarks/robot_check.py"
#: (preset, segments, figure name): the bodies.
BODIES = (("talos", 3, "talos"), ("talos", 2, "talos_2segments"), ("g1", 3, "g1"),
          ("human", 3, "human"))
#: The runs of each body (the module's docstring), the check first.
ROLES = ("check", "half step", "rigid", "welds 1 ms", "solver 1e-8")


def _settings(role: str, chosen_ms: float | None) -> tuple[MujocoOptions, WholeBodyOptions]:
    """The MuJoCo and whole-body options of a run; ``chosen_ms`` the check's step."""
    mujoco, body = MujocoOptions(), WholeBodyOptions()
    if role == "half step":
        mujoco = MujocoOptions(timestep_s=chosen_ms / 2000)
    elif role == "rigid":
        body = WholeBodyOptions(held=HeldJoints.RIGID)
    elif role == "welds 1 ms":
        mujoco = MujocoOptions(timestep_s=0.0005)
        body = WholeBodyOptions(held=HeldJoints.RIGID, weld_timeconst_s=0.001)
    elif role == "solver 1e-8":
        mujoco = MujocoOptions(timestep_s=chosen_ms / 1000, solver_tolerance=1e-8,
                               solver_iterations=100)
    return mujoco, body


def run_one(preset: str, segments: int, role: str, chosen_ms: float | None, stimulus,
            figure: Path | None) -> tuple[dict, np.ndarray]:
    """One run: its JSON (what the report reads) and its MuJoCo sway (S, channels) °."""
    mujoco_options, body_options = _settings(role, chosen_ms)
    result = robot_check(preset, stimulus, options=CheckOptions(segments=segments),
                         mujoco_options=mujoco_options, whole_body_options=body_options)
    if figure is not None:
        result.plot(figure)
    saved = result.to_dict()
    for series in ("time_s", "tilt_deg", "engine_sway_deg", "lumped_sway_deg"):
        saved.pop(series)  # the figure shows them; the JSON keeps what the report reads
    held = saved["details"].pop("held_joints")
    saved["details"]["armature"] = {g["joint"]: g["armature_kgm2"] for g in held
                                    if g["armature_kgm2"] > 0}
    saved["details"]["held_joints"] = len(held)
    saved["details"]["locked_joints"] = [g["joint"] for g in held if g["locked"]]
    saved.update(preset=preset, segments=segments, role=role,
                 step_ms=1000 * saved["details"]["mujoco_timestep_s"],
                 solver_tolerance=mujoco_options.solver_tolerance,
                 weld_ms=1000 * body_options.weld_timeconst_s,
                 held=body_options.held.value,
                 integrator=mujoco_options.integrator,
                 figure=None if figure is None else figure.name)
    print(f"  {role}: {saved['step_ms']:g} ms, {saved['seconds']:.1f} s, "
          f"stays up: {saved['stays_up']}", flush=True)
    return saved, np.asarray(result.engine_sway, dtype=float)


def _rms_share(a: np.ndarray, b: np.ndarray) -> list[float | None]:
    """Per channel, RMS(a − b) / RMS(b) of two sways (S, C) (None where either fell)."""
    if not (np.all(np.isfinite(a)) and np.all(np.isfinite(b))):
        return [None] * b.shape[1]
    n = min(len(a), len(b))
    diff = np.sqrt(np.mean((a[:n] - b[:n]) ** 2, axis=0))
    return (diff / np.sqrt(np.mean(b[:n] ** 2, axis=0))).tolist()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=ROOT / "docs" / "results" / "robot_check")
    args = parser.parse_args()
    mujoco = require_mujoco()
    stimulus = prts(cycles=1)  # 60.5 s, 242 states, 1° p-p
    args.out.mkdir(parents=True, exist_ok=True)
    start = time.perf_counter()
    runs = []
    for preset, segments, figure in BODIES:
        print(f"{preset}, {segments} segments ...", flush=True)
        check, sway = run_one(preset, segments, "check", None, stimulus,
                              args.out / f"{figure}.png")
        check["rms_difference_to_check"] = None
        runs.append(check)
        for role in ROLES[1:]:
            other, other_sway = run_one(preset, segments, role, check["step_ms"], stimulus,
                                        None)
            other["rms_difference_to_check"] = _rms_share(other_sway, sway)
            runs.append(other)
    results = {"command": COMMAND, "mujoco_version": mujoco.__version__,
               "seconds": time.perf_counter() - start, "stimulus": stimulus.description,
               "whole_body_options": dataclasses.asdict(WholeBodyOptions()) | {
                   "held": WholeBodyOptions().held.value},
               "mujoco_options": dataclasses.asdict(MujocoOptions()), "runs": runs}
    atomic_write_text(args.out / "results.json", json_text(results))
    atomic_write_text(args.out / "report.md", report(results))
    print(f"wrote {args.out / 'report.md'}, results.json and the figures")


def _cell(gain: float, phase: float) -> str:
    return f"{gain:+.1f} / {phase:+.1f}"


def _largest(run: dict, channel: str) -> tuple[float, float]:
    """The largest |gain difference| % and |phase difference| ° of a channel to 1 Hz."""
    per = run["per_channel"][channel]
    return (float(np.max(np.abs(per["gain_difference_percent"]))),
            float(np.max(np.abs(per["phase_difference_deg"]))))


def _sentence(body_runs: dict) -> str:
    """What the check's difference from the lumped chain comes from, from the runs."""
    check, rigid, welds = body_runs["check"], body_runs["rigid"], body_runs["welds 1 ms"]
    half = body_runs["half step"]
    if not (check["stays_up"] and rigid["stays_up"] and welds["stays_up"]):
        return "a run fell: no attribution."
    com = check["channels"][-1]
    worst = max(check["channels"], key=lambda c: _largest(check, c)[0])
    g_c, p_c = _largest(check, worst)
    g_r, p_r = _largest(rigid, worst)
    welds_moved = max(abs(a - b) for a, b in zip(
        welds["per_channel"][worst]["gain_difference_percent"],
        rigid["per_channel"][worst]["gain_difference_percent"], strict=True))
    step_moved = max(v for v in half["rms_difference_to_check"] if v is not None)
    g_com, p_com = _largest(check, com)
    return (f"Body COM within {g_com:.1f} % / {p_com:.1f}° of the lumped chain to 1 Hz; the "
            f"largest difference, {worst}'s ({g_c:.1f} % / {p_c:.1f}°), is "
            f"{g_r:.1f} % / {p_r:.1f}° with every held joint rigid, so the held joints' "
            f"servo compliance accounts for {max(g_c - g_r, 0.0):.1f} points of its gain; "
            f"halving the feet's weld time constant moves {worst}'s gain difference by at "
            f"most {welds_moved:.1f} points, and halving the step moves the sway by "
            f"{100 * step_moved:.2f} % of its RMS.")


def report(r: dict) -> str:
    servos, engine = r["whole_body_options"], r["mujoco_options"]
    lines = [
        "# The robot check over the humanoid presets",
        "",
        f"Made by `{r['command']}` ({r['seconds']:.0f} s on this 2-core machine; what it "
        f"does: the script's docstring). {r['stimulus']} (one cycle, 60.5 s); each lumped "
        "chain's default DEC parameters; MuJoCo "
        f"{r['mujoco_version']} through `posture_id.robots.check.robot_check` (the whole "
        "body on the tilting platform, DEC at its lumped joints shared by the two legs, every "
        "other joint held by a PD servo: docs/robots.md) against the lumped chain simulated "
        f"by posture_id. The held joints' servos (the check's): stiffness "
        f"{servos['stiffness_factor']:g}× m·g·h of the mass each carries (lever at least "
        f"{servos['min_lever_m']:g} m), damping ratio {servos['damping_ratio']:g}, an "
        f"armature added where B·dt/I or √(K/I)·dt exceeds {servos['max_step_rate']:g} at "
        f"the step; the feet welded to the platform (time constant "
        f"{1000 * servos['weld_timeconst_s']:g} ms); MuJoCo's constraint solver at "
        f"tolerance {engine['solver_tolerance']:g}; the step the largest of 1, 0.5, 0.25 and "
        "0.125 ms at which the body's one step is stable (`posture_id.robots.stability`).",
        "",
        "## What the differences come from",
        "",
    ]
    bodies = {}
    for run in r["runs"]:
        bodies.setdefault(run["name"], {})[run["role"]] = run
    for name, body_runs in bodies.items():
        check = body_runs["check"]
        lines.append(f"- **{name}** (step {check['step_ms']:g} ms: "
                     f"{check['details'].get('step_choice_sentence', 'given')}): "
                     + _sentence(body_runs))
    lines += [
        "",
        "## Summary",
        "",
        "Variance of the MuJoCo sway the lumped prediction explains (per segment, then the "
        "body COM); body COM gain difference (MuJoCo over lumped, %) / phase difference "
        "(MuJoCo less lumped, °) at the excited frequencies nearest 0.1, 0.2, 0.5 and 1 Hz; "
        "the RMS difference of the MuJoCo sway from the check's, largest over the channels, "
        "as a share of its RMS.",
        "",
        "| body | run | step | held joints | stays up | variance explained | 0.1 Hz | 0.2 Hz "
        "| 0.5 Hz | 1 Hz | from the check | run |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for run in r["runs"]:
        com = run["per_channel"][run["channels"][-1]]
        variance = "–" if not run["stays_up"] else " / ".join(
            f"{100 * run['per_channel'][c]['variance_explained']:.1f}"
            for c in run["channels"]) + " %"
        up = "yes" if run["stays_up"] else f"**falls at {run['engine_fall_s']:.3f} s**"
        cells = []
        for hz in (0.1, 0.2, 0.5, 1.0):
            if com["gain_difference_percent"] is None:
                cells.append("–")
                continue
            k = int(np.argmin(np.abs(np.log(np.asarray(run["frequencies_hz"]) / hz))))
            cells.append(_cell(com["gain_difference_percent"][k],
                               com["phase_difference_deg"][k]))
        moved = run["rms_difference_to_check"]
        moved = "–" if moved is None else (
            "fell" if None in moved else f"{100 * max(moved):.2f} %")
        held = (f"servos, armature on {len(run['details']['armature'])}"
                if run["held"] == "servos" else "rigid")
        lines.append(f"| {run['name']} | {run['role']} | {run['integrator']} "
                     f"{run['step_ms']:g} ms | {held} | {up} | {variance} | "
                     + " | ".join(cells) + f" | {moved} | {run['seconds']:.0f} s |")
    for run in (run for run in r["runs"] if run["role"] == "check"):
        lines += ["", f"## {run['name']}: the check", ""]
        up = "yes" if run["stays_up"] else f"no, falls at {run['engine_fall_s']:.3f} s"
        lines.append(f"- stays up: {up}; the lumped chain: "
                     f"{'yes' if run['lumped_stays_up'] else 'no'}; run {run['seconds']:.1f} s")
        lines.append(f"- MuJoCo {run['integrator']}, step {run['step_ms']:g} ms; "
                     f"{run['details']['dofs']} DoF, {run['details']['mass_kg']:.1f} kg; "
                     f"{run['details']['held_joints']} held joints (servo stiffness "
                     f"{servos['stiffness_factor']:g}× m·g·h), "
                     f"{len(run['details']['locked_joints'])} of them locked")
        armature = run["details"]["armature"]
        lines.append("- armature added: " + (", ".join(
            f"{joint} {value:.3g} kg·m²" for joint, value in armature.items())
            if armature else "none"))
        lines.append(f"- figure: [{run['figure']}]({run['figure']})")
        if not run["stays_up"]:
            lines += ["", "No variance explained and no FRF: the MuJoCo body fell."]
            continue
        lines += ["", "Variance explained: " + ", ".join(
            f"{c} {100 * run['per_channel'][c]['variance_explained']:.1f} %"
            for c in run["channels"]) + "."]
        lines += ["", "Gain difference % / phase difference ° (MuJoCo against lumped) at "
                  "every FRF point from 0.05 to 1 Hz (the first at "
                  f"{run['frequencies_hz'][0]:.3f} Hz on one 60.5 s cycle):", "",
                  "| Hz | " + " | ".join(run["channels"]) + " |",
                  "|---|" + "---|" * len(run["channels"])]
        for k, hz in enumerate(run["frequencies_hz"]):
            lines.append(f"| {hz:.3f} | " + " | ".join(
                _cell(run["per_channel"][c]["gain_difference_percent"][k],
                      run["per_channel"][c]["phase_difference_deg"][k])
                for c in run["channels"]) + " |")
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    main()
