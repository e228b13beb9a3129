#!/usr/bin/env bash
# The real ROS 2 stack (Kilted) from PyPI wheels, for robot_ros2's cross-stack tests:
# rclpy with Fast DDS, the message packages they use, and the rosidl generators that
# build Nav2's NavigateToPose and tf2_msgs' TFMessage types (no wheels exist for them)
# from their .msg/.action files in robot_ros2/tests/ros2/.
# Idempotent: cached under ~/.cache/ivlmap/ros2-venv (IVLMAP_ROS2_VENV overrides), keyed
# by this script's pins; prints the venv's path on stdout when ready.
# usage: scripts/ros2-venv.sh
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
)
stamp="$(printf '%s\n' "${pins[@]}" | sha256sum | cut -c1-16)"
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
echo "$stamp" > "$venv/.ivlmap-stamp"
log "ready in $(( $(date +%s) - t0 )) s"
echo "$venv"
