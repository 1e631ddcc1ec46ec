#!/usr/bin/env bash
# tests/peers/run-cpp-host.sh ROBOT_DIR [XML] [-- EMULATOR_ARGS...]
# icub-main's C++ host (C++ yarprobotinterface, built by `install-cpp-peers.sh icub`) against
# our board emulator, on the robot's own 10.0.1.x addresses, in a private network namespace
# (../shared/netns-run): C++ yarpserver, `icub-eth-emulator ROBOT_DIR EMULATOR_ARGS...`,
# then C++ `yarprobotinterface --config XML` (default icub_all.xml) in ROBOT_DIR until Ctrl-C.
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
robot=$(cd "${1:?usage: $0 ROBOT_DIR [XML] [-- EMULATOR_ARGS...]}" && pwd)
shift
xml=icub_all.xml
if [[ $# -gt 0 && $1 != -- ]]; then xml=$1; shift; fi
[[ ${1:-} == -- ]] && shift

if [[ ${NETNS_RUN_INSIDE:-} != 1 ]]; then
  # Outside the namespace: the C++ peers are built (or found cached) first.
  CPP_BIN=$("$root/tests/peers/install-cpp-peers.sh" icub)
  export CPP_BIN
  exec "$root/../shared/netns-run" "$0" "$robot" "$xml" -- "$@"
fi
CPP_BIN=${CPP_BIN:-$("$root/tests/peers/install-cpp-peers.sh" icub)}
. "$(dirname "$CPP_BIN")/icubhost-env.sh"
export YARP_CONFIG_HOME=${TMPDIR:-/tmp}/cpp-host-yarp.$$
mkdir -p "$YARP_CONFIG_HOME"
emulator=${CARGO_TARGET_DIR:-$root/target}/debug/icub-eth-emulator

# The host's address (pc104.xml) and every board's, on loopback.
for a in $(grep -rhoE 'name="(PC104IpAddress|IpAddress)">[[:space:]]*[0-9.]+' "$robot/hardware" | grep -oE '[0-9.]+$' | sort -u); do
  ip addr add "$a/32" dev lo 2>/dev/null || true
done

pids=()
trap 'kill "${pids[@]}" 2>/dev/null || true; rm -rf "$YARP_CONFIG_HOME"' EXIT
yarp conf 127.0.0.1 10000 >/dev/null
# --read: with the robot's addresses on lo, C++ would otherwise prefer one of them to
# 127.0.0.1 and refuse to change yarp.conf.
# setsid: Ctrl-C reaches only yarprobotinterface, which parks the robot on the emulated
# boards before it ends; they are stopped after it.
setsid yarpserver --ip 127.0.0.1 --socket 10000 --read > "$YARP_CONFIG_HOME/yarpserver.log" 2>&1 & pids+=($!)
for _ in $(seq 100); do yarp exists /root >/dev/null 2>&1 && break; sleep 0.1; done
setsid "$emulator" "$robot" "$@" & pids+=($!)
cd "$robot"
yarprobotinterface --config "$robot/$xml"
