#!/usr/bin/env bash
# Installs everything (scripts/install.sh), checks style and types (ruff, mypy on
# the packages under src/) and runs the whole test suite: unit tests of every
# package and system tests that start real ROS 2 processes (on loopback, in
# private domains). Extra arguments go to pytest.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
bash "$root/scripts/install.sh"
export ROS_AUTOMATIC_DISCOVERY_RANGE=${ROS_AUTOMATIC_DISCOVERY_RANGE:-LOCALHOST}
cd "$root"
"$root/.venv/bin/ruff" check src test
"$root/.venv/bin/mypy"  # settings and the package list: [tool.mypy] in pyproject.toml
exec "$root/.venv/bin/python" -m pytest "$@"
