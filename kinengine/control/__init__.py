"""The control layer: the Task (a controller's one-call update), inverse kinematics, singularity
measures (manipulability, velocity ellipsoids) and the continuity rules of pose parameters."""
