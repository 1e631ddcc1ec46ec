#!/usr/bin/env bash
# The current "main job" demo (until the simulated iCub launcher lands): starts a YARP name
# server, a reader and a writer with the Rust `yarp` tools in a private config directory,
# sends a few Bottles, shows the port table, and shuts everything down.
# Usage: launch-configs/network-demo.sh   (from the repository root)
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build -q -p yarp-cli -p yarp-net
bin=${CARGO_TARGET_DIR:-target}/debug
export YARP_CONFIG_HOME=$(mktemp -d)
port=${YARP_DEMO_PORT:-10000}
pids=()
cleanup() {
    for p in "${pids[@]}"; do kill -TERM "$p" 2>/dev/null || true; done
    wait 2>/dev/null || true
    rm -rf "$YARP_CONFIG_HOME"
}
trap cleanup EXIT INT TERM

"$bin/yarp" conf 127.0.0.1 "$port" >/dev/null
"$bin/yarpserver" --ip 127.0.0.1 --socket "$port" --read --silent &
pids+=($!)
"$bin/yarp" wait /root
"$bin/yarp" read /demo/reader &
pids+=($!)
"$bin/yarp" wait /demo/reader
echo "== name server table:"
"$bin/yarp" name list
echo "== writing three bottles to /demo/reader (printed by the reader):"
{
    echo 'hello 42'
    echo '[set] [pos] 0 100.0'
    echo '(nested (list 1 2 3)) {1 2 255} "quoted string"'
    sleep 0.5
} | "$bin/yarp" write /demo/writer /demo/reader
sleep 0.3
echo "== a telnet-style text session would be: nc 127.0.0.1 <port of /demo/reader>, then"
echo "   CONNECT /me, d, 1 2 3  (see README)"
