"""`python -m mill_analysis.report BAG ...`: the `report` command (mill_analysis.report.cli)."""

from mill_analysis.report.cli import main

raise SystemExit(main())
