"""drill_sim: ament_python package, installable with pip and with colcon on ROS 2 Jazzy."""

from glob import glob

from setuptools import find_packages, setup

package_name = "drill_sim"

setup(
    name=package_name,
    version="0.1.0",
    packages=find_packages(exclude=["tests", "tests.*", "benchmarks"]),
    package_data={package_name: ["presets/*.yaml", "scenarios/*.yaml", "config/*.yaml",
                                 "config/*.json", "config/*.xml", "sensor_profiles/*.yaml"]},
    data_files=[
        ("share/ament_index/resource_index/packages", ["resource/" + package_name]),
        ("share/" + package_name, ["package.xml"]),
        ("share/" + package_name + "/presets", glob("drill_sim/presets/*.yaml")),
        ("share/" + package_name + "/scenarios", glob("drill_sim/scenarios/*.yaml")),
        ("share/" + package_name + "/config", glob("drill_sim/config/*.yaml")
         + glob("drill_sim/config/*.json") + glob("drill_sim/config/*.xml")),
        ("share/" + package_name + "/sensor_profiles", glob("drill_sim/sensor_profiles/*.yaml")),
        ("share/" + package_name + "/launch", glob("launch/*.launch.xml")),
    ],
    python_requires=">=3.10",
    install_requires=[
        "ros-jazzy-rclpy[fastrtps]==7.1.6",
        "ros-jazzy-common-interfaces==5.3.6",
        "numpy>=1.26",
        "numba>=0.60",
        "mcap>=1.2",
        "pyyaml>=6",
        "matplotlib>=3.8",
    ],
    extras_require={
        # pytest 9.2 ignores pytest-xdist 3.8's groups (tests/conftest.py checks)
        "test": ["pytest>=8,<9.2", "pytest-xdist>=3.5", "hypothesis>=6.100", "ruff>=0.6",
                 "colcon-common-extensions>=0.3",
                 "rosbags>=0.10", "mcap-ros2-support>=0.5", "dask[distributed]>=2024.1",
                 "mutmut>=3.8,<4", "gymnasium>=1.0", "optuna>=4.0"],
        "gym": ["gymnasium>=1.0"],                      # drill_sim.gym: the rig as an environment
        "tune": ["optuna>=4.0"],                        # drill_sim tune
        "map-cluster": ["dask[distributed]>=2024.1"],   # drill_sim map --scheduler
    },
    zip_safe=False,
    maintainer="drill_sim developers",
    maintainer_email="drill-sim@example.com",
    description="Real-time simulator of a rotary drilling rig's drill string and drag bit "
                "(Richard-Germay-Detournay model) for stick-slip controller testing",
    license="Apache-2.0",
    entry_points={
        "console_scripts": [
            "drill_sim = drill_sim.entry_points:drill_sim",
            "drill_sim_node = drill_sim.entry_points:node",
            "drill_sim_drive = drill_sim.entry_points:drive",
            "drill_sim_controller = drill_sim.entry_points:controller",
            "drill_sim_record = drill_sim.entry_points:record",
            "drill_sim_replay = drill_sim.entry_points:replay",
        ],
    },
)
