"""Start every node of a scenario with a full ROS 2 install:

    ros2 launch mill_bringup scenario.launch.py scenario:=slotting

The node list comes from the scenario file's `mill_scenario` entry, the same
one run_scenario uses; each node gets the file as its parameter file.
run_scenario adds the results summary; this launch file only starts the graph.
"""

from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument, OpaqueFunction
from launch.substitutions import LaunchConfiguration
from launch_ros.actions import Node

from mill_bringup import scenario as scenario_mod


def _nodes(context):
    scen = scenario_mod.load(LaunchConfiguration('scenario').perform(context))
    return [
        Node(
            package=n.package,
            executable=n.executable,
            name=n.name,
            parameters=[str(scen.path)],
            output='screen',
        )
        for n in scen.nodes
    ]


def generate_launch_description() -> LaunchDescription:
    return LaunchDescription(
        [
            DeclareLaunchArgument(
                'scenario',
                default_value='slotting',
                description='scenario name (config/NAME.yaml) or path to a scenario file',
            ),
            OpaqueFunction(function=_nodes),
        ]
    )
