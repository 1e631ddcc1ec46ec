#!/usr/bin/env bash
# The main job: builds every program, then runs a launch config with yarp-launch.
#
#   launch-configs/run.sh                 # the simulated iCub served to ROS 2 (icub-sim)
#   launch-configs/run.sh fake-devices    # fake devices only: up in about a second
#   launch-configs/run.sh demo            # name server, writer, reader
#   launch-configs/run.sh FILE.toml|FILE.xml [yarp-launch options...]
#
# Ctrl-C stops every module in reverse order. The dashboard is on http://127.0.0.1:8080/.
# Programs are built optimised (YARP_RS_PROFILE=debug: the debug build).
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
# Optimised programs: a main job runs for long and a debug build costs several times the
# CPU (the tests build and use debug programs of their own). YARP_RS_PROFILE=debug runs
# the debug build instead.
profile=${YARP_RS_PROFILE:-release}
case $profile in
    release) flags=(--release) ;;
    debug) flags=() ;;
    *) echo "run.sh: YARP_RS_PROFILE is release or debug, not $profile" >&2; exit 2 ;;
esac
echo "building the programs ($profile; first time: several minutes)..." >&2
cargo build --quiet "${flags[@]}" --workspace --bins
bin=${CARGO_TARGET_DIR:-target}/$profile
exec "$bin/yarp-launch" "$file" "$@"
