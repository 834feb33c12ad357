"""ROS 2 adapters: the rig node and the scenario driver. Only these import rclpy."""
