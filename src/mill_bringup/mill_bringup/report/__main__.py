"""`python -m mill_bringup.report BAG ...`: the `report` command (mill_bringup.report.cli)."""

from mill_bringup.report.cli import main

raise SystemExit(main())
