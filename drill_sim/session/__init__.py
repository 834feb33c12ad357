"""A rig session without ROS: the rig, its sensors, the commands and their rules, pause, step,
reset and run-time parameter changes, the tick, pacing and lockstep, diagnostics, and what a
bag records; and the re-simulation of a recorded session. The node (``drill_sim.ros``) only
binds a ``RigSession`` to topics and services; ``drill_sim bag resim`` re-runs a bag through the
same object.
"""
