#!/usr/bin/env bash
# An environment of the core alone, without ROS, on a chosen Python:
#   bash tools/core_env.sh 3.12 .venv-core-py312
# installs rpr3_gwr_core from its setup.py, so pip checks its declared
# version ranges, with the floor versions (ros2_ws/requirements-floor.txt)
# as constraints, and the test tools.  The ROS wheels exist for Python 3.11
# only: this is how the core is tested on Python 3.12, a stock Jazzy's.
# Quick when nothing changed since the last run; when only the core's
# sources did, the core alone is installed again.
set -euo pipefail

if [ $# -ne 2 ]; then
  echo "usage: bash tools/core_env.sh PYTHON_VERSION VENV" >&2
  exit 2
fi
version="$1"
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
venv="$root/$2"
ws="$root/ros2_ws"

log() { printf 'rpr3-gwr core env: %s\n' "$*" >&2; }

python=""
for candidate in "python$version" "${PYENV_ROOT:-$HOME/.pyenv}"/versions/"$version"*/bin/python"$version"; do
  # A pyenv shim is on the PATH even where it has no such version, so the
  # interpreter is asked to run, not only looked up.
  if "$candidate" -c 'import sys' >/dev/null 2>&1; then
    python="$candidate"
    break
  fi
done
if [ -z "$python" ]; then
  log "no Python $version found (python$version on the PATH, or under pyenv)"
  exit 1
fi

inputs="$("$python" --version 2>&1) $(cat "$0" "$ws"/requirements*.txt \
  "$ws/requirements.py" "$root/src/rpr3_gwr_core/setup.py" | sha256sum | cut -c1-16)"
stamp="$venv/.rpr3-gwr-core-env"
sources="$(cd "$root/src/rpr3_gwr_core" && find . -path '*/__pycache__' -prune -o -type f -print |
  LC_ALL=C sort | xargs sha256sum | sha256sum | cut -c1-16)"
source_stamp="$venv/.rpr3-gwr-core-sources"

# From a copy: setuptools writes its build and egg-info folders beside
# setup.py, and the colcon build's stamp covers every file of src/.
staging="$(mktemp -d)"
trap 'rm -rf "$staging"' EXIT
tar -C "$root/src/rpr3_gwr_core" --exclude=__pycache__ -cf - . | tar -C "$staging" -xf -

if [ "$(cat "$stamp" 2>/dev/null)" = "$inputs" ]; then
  if [ "$(cat "$source_stamp" 2>/dev/null)" != "$sources" ]; then
    log "installing the core's changed sources into ${venv#"$root"/}"
    "$venv/bin/python" -m pip install -qq --no-deps --force-reinstall "$staging"
    echo "$sources" > "$source_stamp"
  fi
  exit 0
fi
log "creating ${venv#"$root"/} with $("$python" --version 2>&1) and the floor versions"
rm -rf "$venv"
"$python" -m venv "$venv"
"$venv/bin/python" -m pip install -qq --upgrade pip
"$python" "$ws/requirements.py" merge "$ws/requirements-ros.txt" "$ws/requirements.txt" \
  --floor "$ws/requirements-floor.txt" > "$venv/constraints.txt"
# pip runs with -qq, as in setup.sh: a machine's pip configuration may name
# index folders that do not exist.
"$venv/bin/python" -m pip install -qq -c "$venv/constraints.txt" "$staging" pytest hypothesis
"$venv/bin/python" -m pip list --format=freeze 2>/dev/null |
  grep -iE '^(numpy|scipy|networkx|matplotlib|pyyaml|numba|llvmlite|pytest|hypothesis)==' |
  paste -sd ' ' | sed 's/^/rpr3-gwr core env: installed /' >&2
echo "$inputs" > "$stamp"
echo "$sources" > "$source_stamp"
