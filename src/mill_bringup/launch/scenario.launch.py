"""Start every node of a scenario with a full ROS 2 install:

    ros2 launch mill_bringup scenario.launch.py scenario:=slotting
    ros2 launch mill_bringup scenario.launch.py scenario:=slotting namespace:=machine2 \
        params_file:=my_gains.yaml timing:=lockstep log_level:=warn
    ros2 launch mill_bringup scenario.launch.py scenario:=slotting layout:=single
    ros2 launch mill_bringup scenario.launch.py --show-args

What it starts is decided by mill_bringup.launch_plan (tested without `launch`): the
scenario file's nodes, each with its merged parameters, in the namespace, and the
job_watch node, the machine_view node (URDF and tool trace) and, where it is installed,
robot_state_publisher (else an INFO line says it is not); with a layout other than
processes, the nodes it puts together run in one mill_container process each (they keep
their names, parameters and topics). The node that clocks the job (plant or force
process), or the container holding it, is required: when it exits by itself the launch
ends with its exit code. When the trajectory reports the job done, job_watch exits and the
launch ends (code 0). Ctrl-C ends every node.
run_scenario adds the results summary; this launch file only runs the graph.
"""

import atexit
import logging
import os
import sys

from launch import LaunchDescription
from launch.actions import (
    DeclareLaunchArgument,
    LogInfo,
    OpaqueFunction,
    RegisterEventHandler,
    Shutdown,
)
from launch.event_handlers import OnProcessExit
from launch.substitutions import LaunchConfiguration
from launch_ros.actions import Node

from mill_bringup import launch_plan

_exit = {'code': 0}


def _exit_with_code() -> None:
    """At interpreter exit: `ros2 launch` returns 0 or 1; end with the clock node's code."""
    if _exit['code']:
        logging.shutdown()
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(_exit['code'])


def _on_exit(required, event, context):
    """A required node ended: the launch ends; the clock node's own exit sets its code."""
    if not context.is_shutdown and required.name != launch_plan.JOB_WATCH.name:
        code = launch_plan.exit_code(event.returncode)
        if code and not _exit['code']:
            _exit['code'] = code
            atexit.register(_exit_with_code)
    return [Shutdown(reason=f'{required.name} exited with code {event.returncode}')]


def _graph(context):
    values = {a.name: LaunchConfiguration(a.name).perform(context) for a in launch_plan.ARGUMENTS}
    plan = launch_plan.plan(**values)
    launch_plan.write_parameters(plan)
    actions: list = [LogInfo(msg=note) for note in plan.notes]
    for spec in plan.nodes:
        node = Node(
            package=spec.package,
            executable=spec.executable,
            # A container gets no node name (it would rename every node in it): its nodes,
            # given as arguments, keep the scenario's names.
            name=None if spec.nodes else spec.name,
            arguments=list(spec.nodes),
            namespace=spec.namespace,
            parameters=spec.parameters,
            remappings=spec.remappings,
            ros_arguments=spec.ros_arguments,
            output='screen',
        )
        actions.append(node)
        if spec.required:
            actions.append(
                RegisterEventHandler(
                    OnProcessExit(
                        target_action=node,
                        on_exit=lambda event, ctx, spec=spec: _on_exit(spec, event, ctx),
                    )
                )
            )
    return actions


def generate_launch_description() -> LaunchDescription:
    arguments = [
        DeclareLaunchArgument(a.name, default_value=a.default, description=a.description)
        for a in launch_plan.ARGUMENTS
    ]
    return LaunchDescription([*arguments, OpaqueFunction(function=_graph)])
