#!/usr/bin/env bash
# Installs everything (scripts/install.sh), checks style and types (ruff, mypy on
# the packages under src/) and runs the test suite: unit tests of every package and
# system tests that start real ROS 2 processes (on loopback, in private domains). Extra
# arguments go to pytest (every run).
#
# `--all` (first argument) also runs the extended suite, the tests marked `slow`: the docs'
# command lines that take minutes (test_docs_commands.py), the figures of the papers other
# than the main job's (test_docs_figures.py), and the further variants of system tests whose
# first variant runs here (test.conftest.EXTENDED). CI runs without it: on a 2-core machine
# the whole suite takes about twice CI's 15 minutes.
#
# Two runs. The first on every core (pytest-xdist; tests marked xdist_group share one worker,
# so that the offline runs they cache are made once): the unit tests and the system tests
# whose graphs step in lockstep (their results do not depend on the machine's load, and a
# graph waits for discovery and messages more than it computes: a run of them one after the
# other kept one core of two busy). The second alone on the machine, one after the other:
# the system tests marked `serial`, which check timing under load (realtime runs, busy
# cores, two graphs side by side).
set -euo pipefail
extended=false
if [ "${1:-}" = "--all" ]; then extended=true; shift; fi
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
bash "$root/scripts/install.sh"
export ROS_AUTOMATIC_DISCOVERY_RANGE=${ROS_AUTOMATIC_DISCOVERY_RANGE:-LOCALHOST}
cd "$root"
"$root/.venv/bin/ruff" check src test
"$root/.venv/bin/mypy"  # settings and the package list: [tool.mypy] in pyproject.toml
pytest_part() {  # exit code 5: none of the chosen tests is of this part
    "$root/.venv/bin/python" -m pytest "$@" || [ $? -eq 5 ]
}
pytest_part -m 'not slow and not serial' -n auto --dist loadgroup "$@"
pytest_part -m 'serial and not slow' "$@"
if $extended; then
    pytest_part -m 'slow and not serial' -n auto --dist loadgroup "$@"
    pytest_part -m 'slow and serial' "$@"
fi
