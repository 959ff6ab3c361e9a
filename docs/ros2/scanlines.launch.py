"""Launch the scanlines line-extraction node where laser_line_extraction ran.

    ros2 launch docs/ros2/scanlines.launch.py
    ros2 launch docs/ros2/scanlines.launch.py scan_topic:=/front/scan params_file:=/abs/my.yaml

scanlines is not a ROS package: the node is the ``scanlines`` command, installed with
``pip install ".[ros2]"`` in the Python environment ``ros2 launch`` runs in (it needs no
ROS install, only the same ROS_DOMAIN_ID and network). ``Node`` without a package runs that
command with the ROS arguments it builds:

    scanlines ros2 --ros-args -r __node:=scanlines --params-file .../params.yaml -r scan:=...

It publishes laser_line_extraction's ``line_segments`` and ``line_markers`` and a
MarkerArray on ``scanlines/markers``. Under a namespace (``namespace=`` or
``PushRosNamespace``), key the parameters file's entry ``/**/scanlines``.
"""

import os

from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument
from launch.substitutions import LaunchConfiguration
from launch_ros.actions import Node

PARAMS_FILE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "params.yaml")


def generate_launch_description():
    return LaunchDescription(
        [
            DeclareLaunchArgument(
                "scan_topic", default_value="scan", description="The LaserScan topic."
            ),
            DeclareLaunchArgument(
                "params_file",
                default_value=PARAMS_FILE,
                description="The node's parameters file (node: ros__parameters: ...).",
            ),
            Node(
                executable="scanlines",
                arguments=["ros2"],
                name="scanlines",
                output="screen",
                parameters=[LaunchConfiguration("params_file")],
                remappings=[("scan", LaunchConfiguration("scan_topic"))],
            ),
        ]
    )
