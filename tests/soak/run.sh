#!/usr/bin/env bash
# tests/soak/run.sh [--minutes 30] [--config icub-sim] [--out DIR]
# The soak run (see tests/soak/README.md): release binaries from
# $CARGO_TARGET_DIR/release (default ~/.cache/yarp-rs/target), rclpy from $ROS_VENV,
# matplotlib in a venv of its own (~/.cache/yarp-rs/venv-soak), the whole run in a private
# network namespace. Everything that needs the network (cargo's registry, PyPI) happens
# first, outside the namespace, which has only loopback; each is done once and cached.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
# --help needs none of the installs below.
case ${1:-} in -h | --help) exec python3 "$here/soak.py" --help ;; esac
netns="$root/../shared/netns-run"
export CARGO_TARGET_DIR=${CARGO_TARGET_DIR:-$HOME/.cache/yarp-rs/target}
venv=${SOAK_VENV:-$HOME/.cache/yarp-rs/venv-soak}

if [[ ${NETNS_RUN_INSIDE:-} != 1 ]]; then
  [[ -x $netns ]] || { echo "run.sh: no $netns (../shared beside the repository)" >&2; exit 2; }
  for b in yarp yarp-launch yarpserver yarprobotinterface yarpdev icub-board-emulator yarp-ros2-gateway; do
    if [[ ! -x $CARGO_TARGET_DIR/release/$b ]]; then
      (cd "$root" && cargo build --release --workspace --bins)
      break
    fi
  done
  # rclpy (idempotent: returns at once when the venv has it)
  export ROS_VENV=${ROS_VENV:-$HOME/.cache/yarp-rs/venv-ros}
  ROS_VENV=$("$root/tests/peers/install-ros2.sh" kilted)
  if ! "$venv/bin/python" -c 'import matplotlib' 2>/dev/null; then
    python3 -m venv "$venv"
    "$venv/bin/pip" install -q matplotlib || {
      echo "run.sh: cannot install matplotlib into $venv (pip needs PyPI)" >&2
      exit 2
    }
  fi
  exec "$netns" "$0" "$@"
fi

# Inside the namespace: no network beyond loopback, so nothing is installed here.
[[ -x ${ROS_VENV:-}/bin/python ]] || { echo "run.sh: ROS_VENV is not set to an rclpy venv" >&2; exit 2; }
"$venv/bin/python" -c 'import matplotlib' 2>/dev/null || { echo "run.sh: no matplotlib in $venv" >&2; exit 2; }
exec "$venv/bin/python" -u "$here/soak.py" "$@"
