"""The console scripts of this package: each holds SIGINT and SIGTERM from its first line
(mill_common.executable), then runs its module's main()."""

from mill_common.executable import entry

run_scenario = entry('mill_bringup.runner.cli')
job_watch = entry('mill_bringup.job_watch')
job_server = entry('mill_bringup.job_server')
mill_container = entry('mill_bringup.container')
machine_view = entry('mill_bringup.machine_view')
