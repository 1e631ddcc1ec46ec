#!/usr/bin/env bash
# The main job: builds every program, then runs a launch config with yarp-launch.
#
#   launch-configs/run.sh                 # the simulated iCub served to ROS 2 (icub-sim)
#   launch-configs/run.sh fake-devices    # fake devices only: up in about a second
#   launch-configs/run.sh demo            # name server, writer, reader
#   launch-configs/run.sh FILE.toml|FILE.xml [yarp-launch options...]
#
# Ctrl-C stops every module in reverse order. The dashboard is on http://127.0.0.1:8080/.
set -euo pipefail
cd "$(dirname "$0")/.."
config=${1:-icub-sim}
shift || true
case $config in
    *.toml | *.xml) file=$config ;;
    *) file=launch-configs/$config.toml ;;
esac
if [[ ! -f $file ]]; then
    echo "run.sh: no launch config $file (try icub-sim, fake-devices, demo)" >&2
    exit 2
fi
echo "building the programs (first time: several minutes)..." >&2
cargo build --quiet --workspace --bins
bin=${CARGO_TARGET_DIR:-target}/debug
exec "$bin/yarp-launch" "$file" "$@"
