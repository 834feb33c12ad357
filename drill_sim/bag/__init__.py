"""rosbag2 bags in MCAP storage, written and read by the project itself (no rosbag2 on PyPI).

Pure Python over the ``mcap`` library: nothing here imports rclpy, so bags can be made and
inspected offline; the node hands in already-serialized CDR bytes. ``writer.BagWriter`` writes
a bag; ``bag.Bag`` opens one once for every reader (info, metadata, walks, the rig's series).
"""
