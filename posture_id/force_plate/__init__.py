"""Force-plate recordings: the centre of pressure turned into the body-COM sway angle
(:mod:`posture_id.force_plate.cop`)."""

from posture_id.force_plate.cop import (
    BodyLoad,
    CopOptions,
    CopUnit,
    ankle_momentum,
    ankle_torque_of_motion,
    com_angle_from_cop,
    cop_of_motion,
    normal_force_of_motion,
    shear_force_of_motion,
)

__all__ = ["BodyLoad", "CopOptions", "CopUnit", "ankle_momentum", "ankle_torque_of_motion",
           "com_angle_from_cop", "cop_of_motion", "normal_force_of_motion", "shear_force_of_motion"]
