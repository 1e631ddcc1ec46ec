#!/usr/bin/env bash
# Keeps the shared target directory to what the test command builds. Cargo never removes
# an artifact: every change of a profile, a feature set or a dependency leaves a new hash of
# every crate above it beside the old ones, and warm runs (CI's and sessions') once filled
# the disk that way (76 GB). This asks cargo which artifacts the test command's builds use
# (`--message-format json` lists fresh ones too) and deletes every other file in `deps/`;
# cargo rebuilds anything it still wants, so a file deleted wrongly costs time, never a
# wrong build.
#
# Usage: tests/prune-target.sh   (tests/run.sh calls it after the tests)
set -euo pipefail
cd "$(dirname "$0")/.."

target=${CARGO_TARGET_DIR:-$PWD/target}
[[ -d $target ]] || exit 0
before=$(du -sm "$target" | cut -f1)

python3 - "$target" <<'EOF'
import json, os, subprocess, sys

deps = os.path.join(sys.argv[1], "debug", "deps")
# The same invocations as tests/run.sh, so that everything is fresh and nothing rebuilds.
builds = [
    ["cargo", "clippy", "--workspace", "--all-targets", "--quiet", "--message-format", "json",
     "--", "-D", "warnings"],
    ["cargo", "build", "--workspace", "--bins", "--quiet", "--message-format", "json"],
    ["cargo", "nextest", "list", "--workspace", "--cargo-quiet", "--cargo-message-format",
     "json", "--message-format", "json"],
]
live = set()  # artifact stems: `libfoo-0123abcd` of `.../deps/libfoo-0123abcd.rlib`
for cmd in builds:
    run = subprocess.run(cmd, capture_output=True, text=True)
    if run.returncode != 0:
        sys.exit("prune-target: the build does not pass; nothing pruned")
    for line in run.stdout.splitlines():
        try:
            msg = json.loads(line)
        except ValueError:
            continue
        if msg.get("reason") == "compiler-artifact":
            for path in msg.get("filenames", []) + [msg.get("executable") or ""]:
                if path:
                    live.add(os.path.basename(path).split(".", 1)[0])
    # A program is named by its uplifted copy (debug/yarp), a hard link of deps/yarp-hash
    # that each of these builds re-points at its own variant: note them build by build.
    for name in os.listdir(deps):
        if os.stat(os.path.join(deps, name)).st_nlink > 1:
            live.add(name.split(".", 1)[0])
live |= {stem[3:] for stem in live if stem.startswith("lib")}  # rustc's `foo-hash.d`
for name in os.listdir(deps):
    path = os.path.join(deps, name)
    if os.path.isfile(path) and name.split(".", 1)[0] not in live:
        os.remove(path)
EOF

# The fuzz targets (their own workspace) and the benches (built by hand, release) grow
# the same way; a cold build of either takes a few minutes, so they are cleared past 8 GB.
for dir in "$target/x86_64-unknown-linux-gnu" "$target/release"; do
    if [[ -d $dir ]] && (($(du -sm "$dir" | cut -f1) > 8000)); then
        rm -rf "$dir"
    fi
done
echo "prune-target: $target from ${before} MB to $(du -sm "$target" | cut -f1) MB" >&2
