"""`python -m mill_bag recover BAG`: see mill_bag.cli."""

from mill_bag.cli import main

raise SystemExit(main())
