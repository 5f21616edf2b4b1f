"""Robots in an independent physics engine: a posture_id body on its tilting platform
stepped by MuJoCo, DEC in MuJoCo's loop, beside posture_id's own simulator (docs/robots.md).

MuJoCo is an optional extra (``pip install posture_id[robots]``): importing this package
does not import it; building or running a model without it raises
:class:`~posture_id.robots.errors.MissingExtraError`, whose one line names the extra.
"""

from posture_id.robots.errors import ROBOTS_EXTRA, MissingExtraError, RobotError
from posture_id.robots.mujoco_model import ChainModel, MujocoOptions, chain_mjcf
from posture_id.robots.mujoco_sim import simulate_mujoco

__all__ = ["ChainModel", "MujocoOptions", "chain_mjcf", "simulate_mujoco", "RobotError",
           "MissingExtraError", "ROBOTS_EXTRA"]
