"""Results of simulations: one trial (:class:`SimulationResult`) or a batch
(:class:`BatchResult`), each a :class:`~posture_id.fileio.Result`."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from posture_id.bodies.body import Body
from posture_id.dec.parameters import DecParameters, ParameterArrays
from posture_id.fileio import Result
from posture_id.plotting import plot_batch, plot_trial
from posture_id.provenance import body_identity, provenance
from posture_id.recording import Recording
from posture_id.simulation.options import SimulationOptions

__all__ = ["SimulationResult", "BatchResult"]


class _OnBody:
    """What both results share: built from a simulator's step-grid tilt and a body."""

    @classmethod
    def on_body(cls, options: SimulationOptions, tilt: np.ndarray, body: Body,
                parameters: DecParameters | ParameterArrays, description: str,
                **samples: np.ndarray):
        """The result of a run on ``body`` under ``parameters``: ``tilt`` (K + 1,) rad of
        the step grid is sampled by ``options``; ``samples`` are theta, alpha, abort_time."""
        sample_time, sample_tilt = options.sampled(tilt)
        return cls(time=sample_time, tilt=sample_tilt, segments=body.segment_names,
                   joints=body.joint_names, parameters=parameters, description=description,
                   options=options, body_identity=body_identity(body), **samples)


@dataclass(frozen=True)
class SimulationResult(_OnBody, Result):
    """One simulated trial, sampled at ``sample_rate_hz``.

    Attributes:
        time: (S,) s. tilt: (S,) rad, α_FS.
        theta: (S, N) rad, segment angles in space (NaN from an abort on).
        alpha: (S, N) rad, COM-above angles α_i,S (alpha[:, 0] is the body sway α_BS).
        abort_time: s at which a segment left the sway limit, or None.
        segments, joints: URDF names, support upward.
        parameters: the DEC parameters simulated.
        description: the stimulus.
    """

    time: np.ndarray
    tilt: np.ndarray
    theta: np.ndarray
    alpha: np.ndarray
    abort_time: float | None
    segments: tuple[str, ...]
    joints: tuple[str, ...]
    parameters: DecParameters = field(repr=False)
    description: str = ""
    options: SimulationOptions = field(default_factory=SimulationOptions, repr=False)
    body_identity: dict = field(default_factory=dict, repr=False)

    @property
    def stable(self) -> bool:
        """True when the trial stayed within the sway limit to the end."""
        return self.abort_time is None

    def to_recording(self) -> Recording:
        """The trial as a :class:`~posture_id.recording.Recording` (what a lab records)."""
        return Recording(self.time, self.tilt, self.theta, self.segments)

    def to_csv(self, path) -> None:
        """Write the recording CSV (``time_s,tilt_deg,<segment>_deg,...``, degrees)."""
        self.to_recording().to_csv(path)

    def to_dict(self) -> dict:
        """JSON-ready summary (no sample arrays): stimulus, parameters, outcome, provenance."""
        return {
            "stimulus": self.description,
            "samples": len(self.time),
            "sample_rate_hz": self.options.sample_rate_hz,
            "stable": self.stable,
            "abort_time_s": self.abort_time,
            "max_sway_deg": dict(zip(self.segments, map(float, np.degrees(
                np.nanmax(np.abs(self.theta), axis=0))), strict=True)),
            "parameters": self.parameters.to_dict(),
            "provenance": {**provenance(self.options), "body": self.body_identity},
        }

    def summary(self) -> str:
        """One line: stimulus, length, outcome and the largest sway."""
        sway = np.degrees(np.nanmax(np.abs(self.theta)))
        outcome = ("stable" if self.stable
                   else f"left the ±{self.options.sway_limit_deg:g}° limit at "
                        f"t = {self.abort_time:.3f} s")
        return (f"{self.description}: {len(self.time)} samples at "
                f"{self.options.sample_rate_hz:g} Hz, {outcome}, largest sway {sway:.3f}°")

    def plot(self, path=None, ax=None, title: str | None = None):
        """Tilt and segment sway against time; saved to ``path`` when given. With ``ax``
        (a pair of axes) it draws into them."""
        return plot_trial(self, path=path, ax=ax, title=title)


@dataclass(frozen=True)
class BatchResult(_OnBody, Result):
    """B simulated trials with the same stimulus.

    Attributes:
        time: (S,) s. tilt: (S,) rad.
        theta, alpha: (B, S, N) rad, NaN from each trial's abort on.
        abort_time: (B,) s, NaN for a trial that stayed within the sway limit.
        segments, joints: URDF names. parameters: the (B, N) parameter arrays.
    """

    time: np.ndarray
    tilt: np.ndarray
    theta: np.ndarray
    alpha: np.ndarray
    abort_time: np.ndarray
    segments: tuple[str, ...]
    joints: tuple[str, ...]
    parameters: ParameterArrays = field(repr=False)
    description: str = ""
    options: SimulationOptions = field(default_factory=SimulationOptions, repr=False)
    body_identity: dict = field(default_factory=dict, repr=False)

    @property
    def stable(self) -> np.ndarray:
        """(B,) bool, True for trials that stayed within the sway limit."""
        return np.isnan(self.abort_time)

    def __len__(self) -> int:
        return self.theta.shape[0]

    def trial(self, b: int) -> SimulationResult:
        """Trial ``b`` as a :class:`SimulationResult`."""
        abort = self.abort_time[b]
        return SimulationResult(
            time=self.time, tilt=self.tilt, theta=self.theta[b], alpha=self.alpha[b],
            abort_time=None if np.isnan(abort) else float(abort), segments=self.segments,
            joints=self.joints, parameters=self.parameters.trial(b, self.joints),
            description=self.description, options=self.options,
            body_identity=self.body_identity,
        )

    def to_dict(self) -> dict:
        """JSON-ready summary (no sample arrays): counts, abort times, provenance."""
        return {
            "stimulus": self.description,
            "trials": len(self),
            "stable": int(self.stable.sum()),
            "samples": len(self.time),
            "abort_time_s": [None if np.isnan(a) else float(a) for a in self.abort_time],
            "provenance": {**provenance(self.options), "body": self.body_identity},
        }

    def summary(self) -> str:
        """One line: trials, how many stayed within the sway limit."""
        return (f"{self.description}: {len(self)} trials, {int(self.stable.sum())} stable, "
                f"{len(self.time)} samples each")

    def plot(self, path=None, ax=None):
        """Tilt and every trial's body COM sway α_BS against time (a pair of axes)."""
        return plot_batch(self.time, self.tilt, self.alpha[:, :, 0], self.stable,
                          self.description, path=path, ax=ax)
