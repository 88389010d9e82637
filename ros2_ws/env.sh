# Activation of the rpr3-gwr workspace:  source ros2_ws/env.sh
# Puts the virtual environment (the ROS prefix when ROS comes from wheels) or
# /opt/ros/jazzy, the built overlay and the loopback-only DDS settings in the
# current shell.  Run ros2_ws/setup.sh (or make build) first, with the same
# RPR3_GWR_PROFILE (pinned, the default, or floor).
_rpr3_ws="$(cd "$(dirname "${BASH_SOURCE[0]:-$0}")" && pwd)"
_rpr3_root="$(dirname "$_rpr3_ws")"
case "${RPR3_GWR_PROFILE:-pinned}" in
  floor)
    _rpr3_venv="$_rpr3_root/.venv-floor" _rpr3_colcon="$_rpr3_ws/floor"
    # numba's cache of another version beside the sources would be
    # overwritten at each switch between the environments.
    export NUMBA_CACHE_DIR="$_rpr3_venv/numba-cache" ;;
  *) _rpr3_venv="$_rpr3_root/.venv" _rpr3_colcon="$_rpr3_ws" ;;
esac
if [ -f /opt/ros/jazzy/setup.bash ]; then
  # shellcheck disable=SC1091
  source /opt/ros/jazzy/setup.bash
fi
if [ ! -f "$_rpr3_venv/bin/activate" ]; then
  echo "rpr3-gwr: no ${_rpr3_venv#"$_rpr3_root"/} yet; run ros2_ws/setup.sh first" >&2
  unset _rpr3_ws _rpr3_root _rpr3_venv _rpr3_colcon
  return 1 2>/dev/null || exit 1
fi
# shellcheck disable=SC1091
source "$_rpr3_venv/bin/activate"
if [ ! -f /opt/ros/jazzy/setup.bash ]; then
  # The wheels install ROS into the virtual environment itself.
  export AMENT_PREFIX_PATH="$VIRTUAL_ENV${AMENT_PREFIX_PATH:+:$AMENT_PREFIX_PATH}"
  export CMAKE_PREFIX_PATH="$VIRTUAL_ENV${CMAKE_PREFIX_PATH:+:$CMAKE_PREFIX_PATH}"
fi
if [ -f "$_rpr3_colcon/install/setup.bash" ]; then
  # shellcheck disable=SC1091
  source "$_rpr3_colcon/install/setup.bash"
fi
export RMW_IMPLEMENTATION=rmw_fastrtps_cpp
export FASTRTPS_DEFAULT_PROFILES_FILE="$_rpr3_ws/fastdds_localhost.xml"
export FASTDDS_DEFAULT_PROFILES_FILE="$_rpr3_ws/fastdds_localhost.xml"
# With LOCALHOST, rmw_fastrtps replaces the profile's transports with its own
# and opens sockets on other interfaces (seen with ss -uanp); the profile
# alone keeps every socket on 127.0.0.1.
unset ROS_AUTOMATIC_DISCOVERY_RANGE ROS_STATIC_PEERS
# ROS_DOMAIN_ID stays the user's: set, every node of this shell uses it;
# unset, the nodes run by hand use ROS's domain 0, and the demo, the tests
# and bench/bench_service.py each pick a random one in 1..100 so that their
# runs do not meet other graphs.
unset _rpr3_ws _rpr3_root _rpr3_venv _rpr3_colcon
