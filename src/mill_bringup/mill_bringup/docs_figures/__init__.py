"""Executable documentation: every figure of README.md and docs/*.md printed by a command.

A figure in the markdown carries an invisible marker, `<!-- fig ID -->VALUE` (markers.py).
The registry (registry.py) maps each ID to the group that computes it: a group runs the
offline runs it needs once and formats each figure as the docs print it. `docs_figures`
(cli.py) prints every figure, checks the docs against them or rewrites them (`--write`);
src/mill_bringup/test/test_docs_figures.py runs the check. How to add a figure:
docs/architecture.md, "Figures in the docs".
"""
