"""The console scripts of this package: each holds SIGINT and SIGTERM from its first line
(mill_common.executable), then runs its module's main()."""

from mill_common.executable import entry

recorder = entry('mill_bag.recorder')
