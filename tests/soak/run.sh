#!/usr/bin/env bash
# tests/soak/run.sh [--minutes 30] [--config icub-sim] [--out DIR]
# The soak run (see tests/soak/README.md): release binaries from
# $CARGO_TARGET_DIR/release (default /root/.cache/yarp-rs/target), matplotlib in a venv of
# its own (~/.cache/yarp-rs/venv-soak), the whole run in a private network namespace.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
netns="$root/../shared/netns-run"
if [[ ${NETNS_RUN_INSIDE:-} != 1 ]]; then
  [[ -x $netns ]] || { echo "run.sh: no $netns" >&2; exit 2; }
  exec "$netns" "$0" "$@"
fi
export CARGO_TARGET_DIR=${CARGO_TARGET_DIR:-/root/.cache/yarp-rs/target}
export ROS_VENV=${ROS_VENV:-/root/.cache/yarp-rs/venv-ros}
for b in yarp yarp-launch yarpserver yarprobotinterface yarpdev icub-board-emulator yarp-ros2-gateway; do
  if [[ ! -x $CARGO_TARGET_DIR/release/$b ]]; then
    (cd "$root" && cargo build --release --workspace --bins)
    break
  fi
done
venv=${SOAK_VENV:-$HOME/.cache/yarp-rs/venv-soak}
if ! "$venv/bin/python" -c 'import matplotlib' 2>/dev/null; then
  python3 -m venv "$venv"
  "$venv/bin/pip" install -q matplotlib
fi
exec "$venv/bin/python" -u "$here/soak.py" "$@"
