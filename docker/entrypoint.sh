#!/usr/bin/env bash
# Activate the suite's environment (ROS, its virtual environment and the
# built overlay), then run the given command.
set -e
profile="${FASTRTPS_DEFAULT_PROFILES_FILE-}"
# shellcheck disable=SC1091
source /ws/ros2_ws/env.sh
# The container has a network namespace of its own: Fast DDS's defaults
# apply there unless the run names a profile (docker/README.md).
if [ -n "$profile" ]; then
  export FASTRTPS_DEFAULT_PROFILES_FILE="$profile" FASTDDS_DEFAULT_PROFILES_FILE="$profile"
else
  unset FASTRTPS_DEFAULT_PROFILES_FILE FASTDDS_DEFAULT_PROFILES_FILE
fi
exec "$@"
