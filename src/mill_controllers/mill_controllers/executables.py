"""The console scripts of this package: each holds SIGINT and SIGTERM from its first line
(mill_common.executable), then runs its module's main()."""

from mill_common.executable import entry

axis_controller_node = entry('mill_controllers.axis_controller_node')
force_controller_node = entry('mill_controllers.force_controller_node')
