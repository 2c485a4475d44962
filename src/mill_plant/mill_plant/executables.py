"""The console scripts of this package: each holds SIGINT and SIGTERM from its first line
(mill_common.executable), then runs its module's main()."""

from mill_common.executable import entry

plant_node = entry('mill_plant.plant_node')
force_process_node = entry('mill_plant.force_process_node')
