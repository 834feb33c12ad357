"""The rig's wire format without ROS: its topics (``rig_topics``, the one table of names, types,
directions, QoS and fields), QoS as plain data (``qos``), CDR encoders and decoders (``cdr``)
and the rig's messages as CDR bytes (``rig_messages``).

Nothing here imports rclpy or the physics core, so the node, the driver, the bag tools and the
benchmarks all read the same definitions, online or offline.
"""


class WireError(ValueError):
    """A message cannot be encoded or decoded: a value does not fit its field, or the bytes do
    not hold the expected message."""
