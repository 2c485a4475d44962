"""The console scripts of this package: each holds SIGINT and SIGTERM from its first line
(mill_common.executable), then runs its module's main()."""

from mill_common.executable import entry

trajectory_node = entry('mill_trajectory.trajectory_node')
gcode_preview = entry('mill_trajectory.preview')
