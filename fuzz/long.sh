#!/usr/bin/env bash
# Long fuzzing runs (by hand or a scheduled job, not CI): each target for SECONDS (default
# one hour) on its seeds plus a local corpus (fuzz/corpus/<target>, git-ignored, kept
# between runs), then one line of figures per target into fuzz/reports/<date>.md. The
# inputs of the corpus that reach code the seeds do not (edges, not hit counts, so the
# seeds stay small) are then merged into fuzz/seeds/<target>: commit them.
#
# Usage: fuzz/long.sh [seconds-per-target] [target...]
# A crash stops that target; its input is in fuzz/artifacts/<target>/. Minimise it
# (`cargo fuzz tmin`), fix the bug, add the input as a regression test and as a seed.
set -uo pipefail
cd "$(dirname "$0")"
secs="${1:-3600}"
shift || true
targets=("$@")
if [ ${#targets[@]} -eq 0 ]; then
    targets=($(sed -n 's/^    targets=(\(.*\))$/\1/p' smoke.sh))
fi
export RUSTC_BOOTSTRAP=1
mkdir -p reports
report="reports/$(date -u +%Y-%m-%d).md"
echo "| target | seconds | runs | coverage | corpus | crashes | seeds added |" >> "$report"
echo "|---|---:|---:|---:|---:|---:|---:|" >> "$report"
for t in "${targets[@]}"; do
    mkdir -p "corpus/$t"
    seeds=()
    [ -d "seeds/$t" ] && seeds=("seeds/$t")
    log=$(mktemp)
    cargo fuzz run "$t" "corpus/$t" "${seeds[@]}" -- -max_total_time="$secs" -rss_limit_mb=2048 >"$log" 2>&1
    rc=$?
    runs=$(grep -oE 'Done [0-9]+ runs' "$log" | grep -oE '[0-9]+' | tail -1)
    cov=$(grep -oE 'cov: [0-9]+' "$log" | tail -1 | grep -oE '[0-9]+')
    crashes=$([ $rc -eq 0 ] && echo 0 || echo "1 (rc $rc, see fuzz/artifacts/$t)")
    mkdir -p "seeds/$t"
    before=$(ls "seeds/$t" | wc -l)
    cargo fuzz run "$t" "seeds/$t" "corpus/$t" -- -merge=1 -use_counters=0 >"$log" 2>&1
    added=$(( $(ls "seeds/$t" | wc -l) - before ))
    echo "| $t | $secs | ${runs:-?} | ${cov:-?} | $(ls "corpus/$t" | wc -l) | $crashes | $added |" | tee -a "$report"
    rm -f "$log"
done
