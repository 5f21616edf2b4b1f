"""``robot_check``: a body's sway in MuJoCo beside the lumped model posture_id simulates.

Two checks, one result (:class:`RobotCheck`):

- **the lumped chain** (a :class:`~posture_id.bodies.body.Body`, or a chain URDF): the chain
  in MuJoCo (:func:`~posture_id.robots.mujoco_sim.simulate_mujoco`) against posture_id's
  compiled simulator on the same stimulus: the oracle (docs/robots.md);
- **the whole body** (a preset name, or a :class:`~posture_id.robots.whole_body
  .WholeBodySpec`): the humanoid's full model in MuJoCo with DEC at its lumped joints
  (:func:`~posture_id.robots.whole_body.simulate_whole_body`) against the lumped chain
  simulated by posture_id.

Each sway's FRF (segments and body COM, relative to the tilt; 0.05–1 Hz) is computed by
:func:`posture_id.frf.frequency_response` on the recording of each simulation; the
differences are the engine's over the lumped prediction (gain, %) and engine less lumped
(phase, °).
"""

from __future__ import annotations

import time as _time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from posture_id.bodies.body import Body
from posture_id.fileio import Result
from posture_id.robots.errors import RobotError, require_mujoco

__all__ = ["RobotCheck", "CheckOptions", "robot_check", "BODY_COM"]

#: The name of the body-COM channel (α_1,S: the COM above the ankles).
BODY_COM = "body COM"


@dataclass(frozen=True)
class CheckOptions:
    """What the check compares.

    Attributes:
        low_hz, high_hz: the FRF's frequency range, Hz (0.05–1).
        segments: 1-3, the lumping of a whole body (default 3; a chain keeps its own).
        report_hz: frequencies the summary and report show (the nearest excited one each).
    """

    low_hz: float = 0.05
    high_hz: float = 1.0
    segments: int = 3
    report_hz: tuple[float, ...] = (0.05, 0.1, 0.2, 0.5, 1.0)

    def __post_init__(self) -> None:
        if not (0 < self.low_hz < self.high_hz):
            raise RobotError(f"CheckOptions: need 0 < low_hz < high_hz, got {self.low_hz} "
                             f"and {self.high_hz}")
        if self.segments not in (1, 2, 3):
            raise RobotError(f"CheckOptions.segments must be 1, 2 or 3, got {self.segments}")


@dataclass(frozen=True)
class RobotCheck(Result):
    """A body in MuJoCo against the lumped model posture_id simulates, same stimulus.

    Attributes:
        name: the body. kind: ``"chain"`` (the lumped chain in MuJoCo) or ``"whole body"``.
        channels: (M,) the segments, then :data:`BODY_COM`.
        time: (S,) s. tilt: (S,) rad.
        engine_sway, lumped_sway: (S, M) rad: segment angles in space and the body COM
            angle α_1,S, MuJoCo's and the lumped model's (NaN after a fall).
        frequencies_hz: (F,) the stimulus's excited frequencies in the range.
        engine_gain, lumped_gain: (F, M) deg/deg; engine_phase_deg, lumped_phase_deg:
            (F, M) °; None where that body fell (no FRF).
        variance_explained: (M,) 1 − var(engine − lumped)/var(engine) over the time both
            stood.
        engine_fall_s, lumped_fall_s: when each left the sway limit, s, or None.
        stimulus: its description. seconds: the run's wall time, s.
        details: what the engine was (MuJoCo's version, step, integrator; the held
            joints' servos for a whole body).
    """

    name: str
    kind: str
    channels: tuple[str, ...]
    time: np.ndarray = field(repr=False)
    tilt: np.ndarray = field(repr=False)
    engine_sway: np.ndarray = field(repr=False)
    lumped_sway: np.ndarray = field(repr=False)
    frequencies_hz: np.ndarray
    engine_gain: np.ndarray | None
    engine_phase_deg: np.ndarray | None
    lumped_gain: np.ndarray | None
    lumped_phase_deg: np.ndarray | None
    variance_explained: np.ndarray
    engine_fall_s: float | None
    lumped_fall_s: float | None
    stimulus: str
    seconds: float
    details: dict = field(default_factory=dict, repr=False)
    report_hz: tuple[float, ...] = (0.05, 0.1, 0.2, 0.5, 1.0)

    @property
    def engine_label(self) -> str:
        return "MuJoCo chain" if self.kind == "chain" else "whole body (MuJoCo)"

    @property
    def lumped_label(self) -> str:
        return "compiled simulator" if self.kind == "chain" else "lumped (posture_id)"

    @property
    def stays_up(self) -> bool:
        """The MuJoCo body stayed within the sway limit for the whole stimulus."""
        return self.engine_fall_s is None

    @property
    def gain_difference_percent(self) -> np.ndarray | None:
        """(F, M) 100·(engine gain / lumped gain − 1), or None when one fell."""
        if self.engine_gain is None or self.lumped_gain is None:
            return None
        return 100.0 * (self.engine_gain / self.lumped_gain - 1.0)

    @property
    def phase_difference_deg(self) -> np.ndarray | None:
        """(F, M) engine phase − lumped phase, wrapped to (−180, 180] °, or None."""
        if self.engine_phase_deg is None or self.lumped_phase_deg is None:
            return None
        diff = self.engine_phase_deg - self.lumped_phase_deg
        return -((-diff + 180.0) % 360.0 - 180.0)

    def at(self, hz: float) -> int:
        """Index of the excited frequency nearest ``hz``."""
        return int(np.argmin(np.abs(np.log(self.frequencies_hz / hz))))

    def to_dict(self) -> dict:
        def arr(x):
            return None if x is None else np.asarray(x).tolist()

        gain_diff, phase_diff = self.gain_difference_percent, self.phase_difference_deg
        columns = {"engine_gain": self.engine_gain, "engine_phase_deg": self.engine_phase_deg,
                   "lumped_gain": self.lumped_gain, "lumped_phase_deg": self.lumped_phase_deg,
                   "gain_difference_percent": gain_diff, "phase_difference_deg": phase_diff}
        per_channel = {}
        for m, name in enumerate(self.channels):
            per_channel[name] = {
                "variance_explained": float(self.variance_explained[m]),
                **{key: None if x is None else arr(x[:, m]) for key, x in columns.items()},
                "max_abs_gain_difference_percent": (
                    None if gain_diff is None else float(np.max(np.abs(gain_diff[:, m])))),
                "max_abs_phase_difference_deg": (
                    None if phase_diff is None else float(np.max(np.abs(phase_diff[:, m])))),
            }
        return {
            "name": self.name, "kind": self.kind, "stimulus": self.stimulus,
            "engine": self.engine_label, "lumped": self.lumped_label,
            "stays_up": self.stays_up, "engine_fall_s": self.engine_fall_s,
            "lumped_stays_up": self.lumped_fall_s is None, "lumped_fall_s": self.lumped_fall_s,
            "seconds": self.seconds, "channels": list(self.channels),
            "frequencies_hz": arr(self.frequencies_hz), "per_channel": per_channel,
            "details": self.details,
            "time_s": arr(self.time), "tilt_deg": arr(np.degrees(self.tilt)),
            "engine_sway_deg": {name: arr(np.degrees(self.engine_sway[:, m]))
                                for m, name in enumerate(self.channels)},
            "lumped_sway_deg": {name: arr(np.degrees(self.lumped_sway[:, m]))
                                for m, name in enumerate(self.channels)},
        }

    def summary(self) -> str:
        lines = [f"robot check of {self.name} ({self.kind}): {self.engine_label} against the "
                 f"{self.lumped_label}; {self.stimulus}; {self.seconds:.1f} s"]
        for label, fall in ((self.engine_label, self.engine_fall_s),
                            (self.lumped_label, self.lumped_fall_s)):
            lines.append(f"  {label}: " + ("stays up" if fall is None
                                            else f"FELL at t = {fall:.2f} s"))
        step = self.details.get("mujoco_timestep_s")
        if step is not None:
            how = self.details.get("step_choice_sentence")
            held = self.details.get("held")
            lines.append(f"  MuJoCo step {1000 * step:g} ms" + (f" ({how})" if how else "")
                         + (f"; held joints: {held}" if held else ""))
        lines.append("  variance of the MuJoCo sway the lumped prediction explains: " + ", ".join(
            f"{name} {100 * v:.1f} %" for name, v in zip(self.channels, self.variance_explained,
                                                         strict=True)))
        gain, phase = self.gain_difference_percent, self.phase_difference_deg
        if gain is None:
            lines.append("  no FRF: a body fell")
            return "\n".join(lines)
        shown = sorted({self.at(hz) for hz in self.report_hz})
        lines.append(f"  FRF difference ({self.engine_label} vs {self.lumped_label}), gain % / "
                     "phase °:")
        lines.append(f"  {'channel':<10}" + "".join(
            f"{self.frequencies_hz[k]:>16.3f} Hz" for k in shown))
        for m, name in enumerate(self.channels):
            lines.append(f"  {name:<10}" + "".join(
                f"{gain[k, m]:>+10.1f} /{phase[k, m]:>+6.1f}" for k in shown) + "   ")
        return "\n".join(line.rstrip() for line in lines)

    def plot(self, path: str | Path | None = None, ax=None):
        from posture_id.plotting import plot_robot_check

        return plot_robot_check(self, path=path, ax=ax)


def _sway(result) -> np.ndarray:
    """(S, N + 1): segment angles and α_1,S, rad."""
    return np.column_stack([result.theta, result.alpha[:, 0]])


def _frf(result, stimulus, options: CheckOptions):
    """(frequencies (F,), gain (F, M), phase (F, M) °) of θ and α_1,S over the tilt, or
    Nones for a body that fell."""
    from posture_id.frf import FrfOptions, frequency_response
    from posture_id.recording import Recording
    from posture_id.trials import prepare_trial

    if result.abort_time is not None:
        return None, None, None
    sway = _sway(result)
    names = (*result.segments, "body_com")
    recording = Recording(result.time, result.tilt, sway, names)
    trial = prepare_trial(recording, stimulus, rate_hz=None)
    cycles = stimulus.cycles
    drift = 1 if cycles is None or cycles >= 2 else 0  # one cycle: no drift to tell apart
    frf = frequency_response(trial, options=FrfOptions(max_frequency_hz=options.high_hz,
                                                       drift_order=drift))
    keep = frf.frequencies_hz >= options.low_hz * (1 - 1e-9)
    return frf.frequencies_hz[keep], frf.gain[keep], frf.phase_deg[keep]


def _variance_explained(engine: np.ndarray, lumped: np.ndarray) -> np.ndarray:
    both = np.all(np.isfinite(engine), axis=1) & np.all(np.isfinite(lumped), axis=1)
    if both.sum() < 3:
        return np.full(engine.shape[1], np.nan)
    e, p = engine[both], lumped[both]
    return 1.0 - np.var(e - p, axis=0) / np.var(e, axis=0)


def robot_check(body_or_preset, stimulus=None, params=None, options: CheckOptions | None = None,
                simulation_options=None, mujoco_options=None, whole_body_options=None
                ) -> RobotCheck:
    """Simulate a body in MuJoCo and the lumped model in posture_id on one stimulus and
    compare their sway.

    Args:
        body_or_preset: a :class:`~posture_id.bodies.body.Body` or the path of a chain URDF
            (the chain in MuJoCo vs the compiled simulator); a preset's name (``talos``,
            ``g1``, ``human``) or a :class:`~posture_id.robots.whole_body.WholeBodySpec`
            (the whole body in MuJoCo vs its lumped chain, lumped to
            ``options.segments``).
        stimulus: any :class:`~posture_id.simulation.stimulus.TiltProfile` (default: the
            121 s PRTS, 1° p-p).
        params: DEC parameters of the (lumped) chain (default: its defaults).
        options: :class:`CheckOptions`. simulation_options: sampling, sway limit, dead-band.
        mujoco_options: MuJoCo's step and integrator. whole_body_options: the held joints'
            servos (:class:`~posture_id.robots.whole_body.WholeBodyOptions`).
    Returns:
        :class:`RobotCheck`.
    Raises:
        MissingExtraError: MuJoCo is not installed. RobotError, BodyError: a body,
            parameters or options that cannot be checked (one line).
    """
    from posture_id.bodies.body import load_body
    from posture_id.bodies.lumping import PRESETS
    from posture_id.robots.mujoco_sim import simulate_mujoco
    from posture_id.robots.whole_body import (
        WholeBodyOptions,
        WholeBodySpec,
        lumped_body,
        simulate_whole_body,
    )
    from posture_id.simulation import prts, simulate

    mujoco = require_mujoco()
    options = options or CheckOptions()
    stimulus = stimulus or prts()
    start = _time.perf_counter()
    spec = None
    if isinstance(body_or_preset, WholeBodySpec):
        spec = body_or_preset
    elif isinstance(body_or_preset, str) and body_or_preset in PRESETS:
        spec = WholeBodySpec.preset(body_or_preset)
    elif isinstance(body_or_preset, (str, Path)):
        body = load_body(body_or_preset)
    elif isinstance(body_or_preset, Body):
        body = body_or_preset
    else:
        raise RobotError(f"robot_check needs a body, a chain URDF, a preset "
                         f"({', '.join(PRESETS)}) or a WholeBodySpec, got "
                         f"{type(body_or_preset).__name__}")
    if spec is None:
        kind, name = "chain", body.name
        engine = simulate_mujoco(body, params, stimulus, simulation_options, mujoco_options)
        lumped = simulate(body, params, stimulus, simulation_options)
        details = {"engine": engine.description,
                   "mujoco_timestep_s": engine.options.dt}
    else:
        kind, name = "whole body", f"{spec.name} ({options.segments} segments)"
        body = lumped_body(spec, options.segments)
        engine, model = simulate_whole_body(spec, options.segments, params, stimulus,
                                            simulation_options, mujoco_options,
                                            whole_body_options, lumped=body)
        lumped = simulate(body, params, stimulus, simulation_options)
        details = {"engine": engine.description, "mujoco_timestep_s": engine.options.dt,
                   "urdf": str(spec.urdf), "dofs": int(model.model.nv),
                   "mass_kg": model.total_mass,
                   "welds": "both feet welded to the platform; the base free",
                   "held": (whole_body_options or WholeBodyOptions()).held.value,
                   "held_joints": [g.to_dict() for g in model.gains.values()]}
        if model.step_choice is not None:
            details["step_choice"] = model.step_choice.to_dict()
            details["step_choice_sentence"] = model.step_choice.sentence()
    details["mujoco_version"] = mujoco.__version__
    e_sway, l_sway = _sway(engine), _sway(lumped)
    f_e, g_e, p_e = _frf(engine, stimulus, options)
    f_l, g_l, p_l = _frf(lumped, stimulus, options)
    frequencies = f_l if f_l is not None else (f_e if f_e is not None else np.zeros(0))
    return RobotCheck(
        name=name, kind=kind, channels=(*body.segment_names, BODY_COM),
        time=engine.time, tilt=engine.tilt, engine_sway=e_sway, lumped_sway=l_sway,
        frequencies_hz=np.asarray(frequencies), engine_gain=g_e, engine_phase_deg=p_e,
        lumped_gain=g_l, lumped_phase_deg=p_l,
        variance_explained=_variance_explained(e_sway, l_sway),
        engine_fall_s=engine.abort_time, lumped_fall_s=lumped.abort_time,
        stimulus=stimulus.description, seconds=_time.perf_counter() - start,
        details=details, report_hz=options.report_hz,
    )
