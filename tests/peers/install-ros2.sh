#!/usr/bin/env bash
# Installs rclpy and the message packages the gateway and launcher tests use, from PyPI's
# ROS 2 wheels, into a venv (~25 s, ~260 MB once; cached).
#
#   install-ros2.sh [kilted|jazzy]      # default kilted
#
# kilted: the unprefixed `ros-*` wheels (cp311..cp313), venv $ROS_VENV (default .venv-ros/).
# jazzy:  the `ros-jazzy-*` wheels, which exist for Python 3.12 only, venv $ROS_JAZZY_VENV
#         (default .venv-ros-jazzy/); the Python 3.12 is $ROS_JAZZY_PYTHON, else
#         `python3.12` on PATH, else pyenv's newest 3.12; none: exit 1 saying so.
# Idempotent: when the venv already imports every package it returns at once.
# Prints the venv directory on success (tests read it from ROS_VENV / ROS_JAZZY_VENV).
set -euo pipefail
cd "$(dirname "$0")/../.."
distro=${1:-kilted}
# nav-msgs and visualization-msgs: types outside the gateway's built-in catalog, which it
# reads from their definitions (share/<pkg>/msg in the venv) at run time. test-msgs: the
# actions (Fibonacci) and services rosidl tests with, their definitions and hashes.
names=(rclpy std-msgs sensor-msgs geometry-msgs std-srvs trajectory-msgs diagnostic-msgs
       nav-msgs visualization-msgs test-msgs rmw-fastrtps-cpp)
# icub-models: the iCubs' URDFs (share/iCub/robots/<robot>/model.urdf), for TF checks.
data=(icub-models)
probe='import icub_models, rclpy, rclpy.action, std_msgs.msg, sensor_msgs.msg, geometry_msgs.msg, std_srvs.srv, trajectory_msgs.msg, diagnostic_msgs.msg, nav_msgs.msg, visualization_msgs.msg, test_msgs.action, test_msgs.srv'
case $distro in
    kilted)
        venv=${ROS_VENV:-$PWD/.venv-ros}
        prefix=ros-
        python=python3
        ;;
    jazzy)
        venv=${ROS_JAZZY_VENV:-$PWD/.venv-ros-jazzy}
        prefix=ros-jazzy-
        python=${ROS_JAZZY_PYTHON:-}
        ;;
    *)
        echo "install-ros2.sh: unknown distro '$distro' (kilted or jazzy)" >&2
        exit 2
        ;;
esac
# Interfaces PyPI has no wheel for (tests/peers/interfaces/<pkg>/msg/*.idl): only their
# type-description JSON (with the REP-2016 hashes), made by the venv's own `rosidl hash`,
# lands in the venv's share/<pkg>/msg/, where the catalog test reads every type's hash.
extra_interfaces() {
    local src=$PWD/tests/peers/interfaces dir pkg idl out
    for dir in "$src"/*/; do
        pkg=$(basename "$dir")
        for idl in "$dir"msg/*.idl; do
            out=$(mktemp -d)
            AMENT_PREFIX_PATH=$venv "$venv/bin/rosidl" hash -o "$out" \
                -I "$venv/share/geometry_msgs" -I "$venv/share/std_msgs" \
                -I "$venv/share/builtin_interfaces" \
                "$pkg" "${dir%/}:msg/$(basename "$idl")" >/dev/null 2>&1
            mkdir -p "$venv/share/$pkg/msg"
            cp "$out/msg/"*.json "$venv/share/$pkg/msg/"
            rm -rf "$out"
        done
    done
    # control_msgs (FollowJointTrajectory; not on PyPI either): the gateway's copy of the
    # release this distro ships, installed as a package installs it (definitions and their
    # rosidl JSON), so tests read it at run time as a sourced ROS gives it.
    local files=(gateway/msg/control_msgs/msg/*.msg)
    if [[ $distro == jazzy ]]; then
        files+=(gateway/msg/jazzy/control_msgs/action/*.action)
    else
        files+=(gateway/msg/control_msgs/action/*.action)
    fi
    "$venv/bin/python" gateway/tools/rosidl_hashes.py control_msgs "${files[@]}" \
        --json-dir "$venv/share/control_msgs" >/dev/null 2>&1
    for f in "${files[@]}"; do
        cp "$f" "$venv/share/control_msgs/$(basename "$(dirname "$f")")/"
    done
}
extra_done() {
    local idl rel
    for idl in tests/peers/interfaces/*/msg/*.idl; do
        rel=${idl#tests/peers/interfaces/}
        [[ -f $venv/share/${rel%.idl}.json ]] || return 1
    done
    [[ -f $venv/share/control_msgs/action/FollowJointTrajectory.json ]] &&
        cmp -s "$venv/share/control_msgs/action/FollowJointTrajectory.action" \
            "gateway/msg/$([[ $distro == jazzy ]] && echo jazzy/)control_msgs/action/FollowJointTrajectory.action"
}
if [[ -x $venv/bin/python ]] && "$venv/bin/python" -c "$probe" 2>/dev/null; then
    extra_done || extra_interfaces
    echo "$venv"; exit 0
fi
if [[ $distro == jazzy && -z $python ]]; then
    # PyPI has ros-jazzy-* wheels for CPython 3.12 only.
    if command -v python3.12 >/dev/null && python3.12 -c 'import venv' 2>/dev/null; then
        python=python3.12
    else
        root=$(pyenv root 2>/dev/null || echo "$HOME/.pyenv")
        found=$(ls -d "$root"/versions/3.12.* 2>/dev/null | sort -V | tail -n 1 || true)
        if [[ -n $found && -x $found/bin/python3.12 ]]; then
            python=$found/bin/python3.12
        fi
    fi
    if [[ -z $python ]]; then
        echo "install-ros2.sh: ROS 2 Jazzy's wheels need Python 3.12: none found (no python3.12" \
             "on PATH, no pyenv 3.12.x); install one or set ROS_JAZZY_PYTHON" >&2
        exit 1
    fi
fi
"$python" -m venv "$venv" >&2
"$venv/bin/pip" install -q "${names[@]/#/$prefix}" "${data[@]}" >&2
"$venv/bin/python" -c "$probe" >&2
extra_interfaces
echo "$venv"
