#!/usr/bin/env bash
# The project's test command (README "Run the tests"; CI's .ci/run calls exactly this).
# Formatting, lints, then every unit, vector, property and integration test. Everything
# runs inside ../shared/netns-run: a private network namespace with only loopback.
set -euo pipefail
cd "$(dirname "$0")/.."

netns_run=${NETNS_RUN:-$(cd .. && pwd)/shared/netns-run}
if [[ ! -x $netns_run ]]; then
    echo "tests/run.sh: $netns_run not found (expected ../shared beside the repository)" >&2
    exit 2
fi
export YARP_VECTORS_DIR=${YARP_VECTORS_DIR:-$(cd .. && pwd)/shared/yarp-vectors}

echo "== cargo fmt --check"
cargo fmt --all --check
echo "== cargo clippy"
cargo clippy --workspace --all-targets --quiet -- -D warnings
echo "== fuzz targets (build + short smoke)"
if [[ -x fuzz/smoke.sh ]]; then fuzz/smoke.sh; fi
echo "== doc tests"
cargo test --workspace --doc --quiet
echo "== programs (yarp, yarpserver, yarpdev, yarprobotinterface, gateway, emulator, launcher)"
cargo build --workspace --bins --quiet
echo "== tests (under netns-run)"
status=0
"$netns_run" cargo nextest run --workspace --no-fail-fast || status=$?
echo "== prune the target directory to this build"
tests/prune-target.sh || true
exit $status
