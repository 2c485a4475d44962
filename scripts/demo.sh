#!/usr/bin/env bash
# Installs everything (scripts/install.sh) and runs the main job: the Beltrán
# 2013 slotting job with every node in its own process, recorded to a rosbag2
# bag (MCAP), ending with a summary; then the report of the bag (table,
# report.md and plots). Everything goes to runs/slotting-TIME/ (bag/, report/).
# Extra arguments go to run_scenario (e.g. --controller pd, --duration 10).
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
bash "$root/scripts/install.sh"
# DDS stays on this machine unless you say otherwise.
export ROS_AUTOMATIC_DISCOVERY_RANGE=${ROS_AUTOMATIC_DISCOVERY_RANGE:-LOCALHOST}
cd "$root"
run_dir=runs/slotting-$(date +%Y%m%d-%H%M%S)
"$root/.venv/bin/python" -m mill_bringup.runner slotting --output "$run_dir" --record "$run_dir/bag" "$@"
exec "$root/.venv/bin/python" -m mill_analysis.report "$run_dir/bag" --out "$run_dir/report"
