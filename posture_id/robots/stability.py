"""The whole body's step: the largest at which MuJoCo's one step is stable.

A humanoid held by stiff servos and welded to its platform has modes far faster than its
balance (a servo on a light link, a weld): RK4 at 1 ms integrates TALOS stably, but the
Unitree G1 and the example-robot-data human diverge within its first steps. Whether a step
``dt`` is stable is read from the step itself: the one-step map x_{k+1} = Φ(x_k) of MuJoCo
(its integrator, constraints and servos; x = (q, q̇) in MuJoCo's tangent space) linearised
at the reference posture at rest by central differences, and its spectral radius ρ(dt).
A mode of the body itself (the standing body is an inverted pendulum, unstable without
DEC) has the eigenvalue e^{λ·dt}, so that ρ(dt) = ρ(dt/2)²; a mode the integrator makes
unstable grows far faster at the longer step. The step is stable when ρ(dt) ≤
ρ(dt/2)²·:data:`GROWTH_SLACK` (the two on the same model: the same armature), and the
chosen step is the largest of :data:`CANDIDATE_STEPS_S` that is.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from posture_id.robots.errors import RobotError, require_mujoco

__all__ = ["CANDIDATE_STEPS_S", "GROWTH_SLACK", "StepChoice", "one_step_radius",
           "choose_step"]

#: s, the steps tried, largest first.
CANDIDATE_STEPS_S = (1e-3, 5e-4, 2.5e-4, 1.25e-4)
#: ρ(dt) may exceed ρ(dt/2)² by this factor and the step still count as stable (the
#: central differences' error; an unstable step's ρ(dt) is 1.5 to 1000 times it).
GROWTH_SLACK = 1.01


def one_step_radius(model, eps: float = 1e-7) -> float:
    """The spectral radius of the Jacobian of one ``mj_step`` of ``model`` (an
    ``mujoco.MjModel``, its own ``opt.timestep``) at ``qpos0`` at rest, by central
    differences of size ``eps`` (rad, rad/s) in MuJoCo's tangent space (2·nv states)."""
    mujoco = require_mujoco()
    nv = model.nv
    origin = mujoco.MjData(model)
    mujoco.mj_forward(model, origin)
    data = mujoco.MjData(model)
    moved = np.zeros(nv)

    def step_from(dq: np.ndarray, dv: np.ndarray) -> np.ndarray:
        mujoco.mj_resetData(model, data)
        mujoco.mj_integratePos(model, data.qpos, dq, 1.0)
        data.qvel[:] = dv
        mujoco.mj_step(model, data)
        mujoco.mj_differentiatePos(model, moved, 1.0, origin.qpos, data.qpos)
        return np.concatenate([moved, data.qvel])

    jacobian = np.zeros((2 * nv, 2 * nv))
    for k in range(2 * nv):
        e = np.zeros(2 * nv)
        e[k] = eps
        jacobian[:, k] = (step_from(e[:nv], e[nv:]) - step_from(-e[:nv], -e[nv:])) / (2 * eps)
    return float(np.max(np.abs(np.linalg.eigvals(jacobian))))


@dataclass(frozen=True)
class StepChoice:
    """The chosen step and what decided it.

    Attributes:
        step_s: s, the chosen step.
        tried: (step s, ρ(step), ρ(step/2)) of every step tried, largest first.
    """

    step_s: float
    tried: tuple[tuple[float, float, float], ...]

    def sentence(self) -> str:
        """'1 ms is unstable (ρ 3.05 against 1.009² at half of it); 0.5 ms is stable'."""
        parts = []
        for step, rho, half in self.tried:
            word = "stable" if step == self.step_s else "unstable"
            parts.append(f"{step * 1000:g} ms is {word} (ρ {rho:.4g} against {half:.4g}² "
                         "at half of it)")
        return "; ".join(parts)

    def to_dict(self) -> dict:
        return {"step_s": self.step_s,
                "tried": [{"step_s": s, "radius": r, "radius_at_half": h}
                          for s, r, h in self.tried]}


def choose_step(build: Callable[[float], object]) -> StepChoice:
    """The largest of :data:`CANDIDATE_STEPS_S` at which the model ``build(step)`` returns
    (an ``mujoco.MjModel`` made for that step) is stable (see the module).

    Raises:
        RobotError: no candidate step is stable."""
    tried = []
    for step in CANDIDATE_STEPS_S:
        model = build(step)
        rho = one_step_radius(model)
        model.opt.timestep = step / 2
        half = one_step_radius(model)
        model.opt.timestep = step
        tried.append((step, rho, half))
        if rho <= GROWTH_SLACK * half**2:
            return StepChoice(step, tuple(tried))
    raise RobotError("MuJoCo's step is unstable down to "
                     f"{CANDIDATE_STEPS_S[-1] * 1000:g} ms ("
                     + StepChoice(float("nan"), tuple(tried)).sentence()
                     + "): give a smaller --timestep-ms, or softer servos")
