#!/usr/bin/env bash
# Installs ROS 2 Kilted's rclpy and the message packages the gateway tests use, from PyPI's
# ros-* wheels (~25 s, ~260 MB), into the git-ignored venv .venv-ros/ (or $ROS_VENV).
# Idempotent: when the venv already imports every package it returns at once.
# Prints the venv directory on success (tests read it from ROS_VENV).
set -euo pipefail
cd "$(dirname "$0")/../.."
venv=${ROS_VENV:-$PWD/.venv-ros}
packages=(ros-rclpy ros-std-msgs ros-sensor-msgs ros-geometry-msgs ros-std-srvs
          ros-trajectory-msgs ros-diagnostic-msgs ros-rmw-fastrtps-cpp)
probe='import rclpy, std_msgs.msg, sensor_msgs.msg, geometry_msgs.msg, std_srvs.srv, trajectory_msgs.msg, diagnostic_msgs.msg'
if [[ -x $venv/bin/python ]] && "$venv/bin/python" -c "$probe" 2>/dev/null; then
    echo "$venv"; exit 0
fi
python3 -m venv "$venv" >&2
"$venv/bin/pip" install -q "${packages[@]}" >&2
"$venv/bin/python" -c "$probe" >&2
echo "$venv"
