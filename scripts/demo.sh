#!/usr/bin/env bash
# Installs everything (scripts/install.sh) and runs the main job: the Beltrán
# 2013 slotting job with every node in its own process, ending with a summary.
# Extra arguments go to run_scenario (e.g. --controller pd, --duration 10).
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
bash "$root/scripts/install.sh"
# DDS stays on this machine unless you say otherwise.
export ROS_AUTOMATIC_DISCOVERY_RANGE=${ROS_AUTOMATIC_DISCOVERY_RANGE:-LOCALHOST}
cd "$root"
exec "$root/.venv/bin/python" -m mill_bringup.runner slotting "$@"
