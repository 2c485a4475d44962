"""`python -m mill_bringup.runner SCENARIO ...`: the `run_scenario` command (runner.cli)."""

from mill_bringup.runner.cli import main

raise SystemExit(main())
