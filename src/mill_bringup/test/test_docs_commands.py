"""The command lines docs/papers.md prints, run as a reader runs them.

test_docs_figures.py computes every marked figure in-process from the runs its registry
names; this runs the printed command lines themselves (`offline_sim …`, `docs_figures …`,
`python -m mill_…`), so a renamed variant, option or parameter, or a command that now fails,
cannot hide behind figures that are computed another way. A line with a placeholder (NAME,
BAG, RUN, …) is not runnable and is left out; `run_scenario` and `report` need ROS processes
or a bag (the system tests run them).

The lines that take more than about 10 s of wall time on the 2-core machine are marked
`slow` (pyproject.toml): scripts/test.sh leaves them out, so that the suite stays under
15 minutes; `python -m pytest -m slow src/mill_bringup/test/test_docs_commands.py` runs them
(about 16 minutes on the loaded machine, 12 of them `offline_sim chavez_conde --skip 0`).
"""

from __future__ import annotations

import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[3]
DOC = REPO / 'docs' / 'papers.md'
COMMAND = re.compile(r'`((?:offline_sim|docs_figures|python -m mill_)[^`]*)`')
PLACEHOLDERS = ('NAME', 'BAG', 'RUN', '...', '…')
# Measured wall time above ~12 s on the 2-core machine, loaded by other runs (4 December
# 2026), by command line; the fast ones took 0.2-11 s each, 42 s together.
SLOW = frozenset(
    {
        'offline_sim beltran',  # 117 s (loaded machine, 4 December 2026)
        'offline_sim beltran --variant adrc',  # 21 s
        'offline_sim beltran --variant adrc -p plant.kline.specific_energy=3.0e10',  # 28 s
        'offline_sim beltran --variant pd -p plant.kline.chip=tool',  # 33 s
        "offline_sim beltran --variant adrc -p '*_observer.gpi.discretisation=predictor'",
        "offline_sim beltran --variant adrc -p '*_observer.gpi.discretisation=continuous'",
        'offline_sim chavez_conde --skip 0',  # 691 s: 22 variants
        'offline_sim maharof',  # 26 s
        'offline_sim hatwesh_velocity --skip 0',  # 15 s
        'docs_figures --check',  # every group: the docs check itself
    }
)
FAST_LIMIT = 120  # [s] a fast line that takes this long has become slow: mark it


def printed() -> list[str]:
    """Every runnable command line of the document, once each, spaces normalised."""
    out: list[str] = []
    for m in COMMAND.finditer(DOC.read_text(encoding='utf-8')):
        line = ' '.join(m.group(1).split())
        if not any(p in line for p in PLACEHOLDERS) and line not in out:
            out.append(line)
    return out


def argv(line: str) -> list[str]:
    """The line's argv: the console scripts and `python` of this interpreter."""
    args = shlex.split(line)
    if args[0] == 'python':
        return [sys.executable, *args[1:]]
    return [str(Path(sys.executable).parent / args[0]), *args[1:]]


def test_the_document_prints_runnable_commands_and_the_slow_list_is_current() -> None:
    lines = printed()
    assert len(lines) >= 10
    assert sorted(SLOW - set(lines)) == []  # a slow line that left the docs: drop it


@pytest.mark.parametrize(
    'line', [pytest.param(c, marks=[pytest.mark.slow] if c in SLOW else []) for c in printed()]
)
def test_a_printed_command_line_runs(line: str) -> None:
    timeout = None if line in SLOW else FAST_LIMIT
    done = subprocess.run(
        argv(line), cwd=REPO, capture_output=True, text=True, timeout=timeout, check=False
    )
    assert done.returncode == 0, done.stderr[-2000:]
    assert done.stdout.strip()
