#!/usr/bin/env bash
# CI smoke test for the fuzz targets: builds every target, then runs each one briefly on
# its committed seeds (fuzz/seeds/<target>) plus any local corpus (fuzz/corpus/<target>,
# git-ignored). Exits non-zero if a build fails or any target finds a crash.
#
# Usage: fuzz/smoke.sh [seconds-per-target] [target...]
#   default: 7 s for each target (~45 s of fuzzing)
#
# Needs cargo-fuzz (`cargo install cargo-fuzz`). The toolchain may be stable:
# RUSTC_BOOTSTRAP=1 lets it accept the -Z sanitizer flags cargo-fuzz passes.
set -euo pipefail

cd "$(dirname "$0")"
secs="${1:-7}"
shift || true
targets=("$@")
if [ ${#targets[@]} -eq 0 ]; then
    targets=(bottle_decode text_parse ini_parse wire_decode nameserver datagram can_decode xsens_decode eth_decode shmem_ring ros_msg_decode mjpeg_monitor rplidar_decode cartesian_rpc)
fi

if ! cargo fuzz --help >/dev/null 2>&1; then
    echo "smoke.sh: cargo-fuzz is not installed (cargo install cargo-fuzz)" >&2
    exit 2
fi
export RUSTC_BOOTSTRAP=1

for t in "${targets[@]}"; do
    echo "== build $t"
    cargo fuzz build "$t"
done

failed=()
for t in "${targets[@]}"; do
    mkdir -p "corpus/$t"
    seeds=()
    [ -d "seeds/$t" ] && seeds=("seeds/$t")
    echo "== run $t for ${secs}s"
    log="$(mktemp)"
    if cargo fuzz run "$t" "corpus/$t" "${seeds[@]}" -- \
        -max_total_time="$secs" -print_final_stats=1 >"$log" 2>&1; then
        grep -E '^Done|stat::number_of_executed_units|stat::average_exec_per_sec|stat::new_units_added' "$log" || true
    else
        echo "!! $t FAILED (crash or error); log follows" >&2
        grep -vE '^\s+([0-9]+: |at )' "$log" | tail -60 >&2
        failed+=("$t")
    fi
    rm -f "$log"
done

if [ ${#failed[@]} -ne 0 ]; then
    echo "fuzz smoke: failures in: ${failed[*]} (inputs in fuzz/artifacts/)" >&2
    exit 1
fi
echo "fuzz smoke: ${#targets[@]} passed, 0 failed"
