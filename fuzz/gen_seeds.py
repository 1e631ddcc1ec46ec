#!/usr/bin/env python3
"""Writes the seeds under fuzz/seeds/ that come from the recorded C++ YARP vectors
(shared/yarp-vectors/bottles.jsonl): its `binary` fields seed bottle_decode and its
`text_in` fields seed text_parse (`<vector id>.bin`/`.txt`, rewritten in place). The other
seeds are kept: those `long.sh` merged in (named by their hash) and the hand-written
ini_parse ones.

Usage: python3 fuzz/gen_seeds.py [path/to/bottles.jsonl]
"""
import json
import pathlib
import sys

here = pathlib.Path(__file__).resolve().parent
src = pathlib.Path(sys.argv[1]) if len(sys.argv) > 1 else (
    here.parent.parent / "shared" / "yarp-vectors" / "bottles.jsonl")
if not src.exists():
    src = pathlib.Path("/work/shared/yarp-vectors/bottles.jsonl")

binary = here / "seeds" / "bottle_decode"
text = here / "seeds" / "text_parse"
for d in (binary, text):
    d.mkdir(parents=True, exist_ok=True)

# A handful of diverse vectors (every type, compaction, dicts, odd tags, quirky text).
BINARY_IDS = {
    "bottle-001", "bottle-010", "bottle-025", "bottle-055", "bottle-063", "bottle-064",
    "bottle-080", "bottle-082", "bottle-086", "bottle-088", "bottle-091", "bottle-094",
    "bottle-097", "bottle-100", "bottle-101", "bottle-103", "bottle-106", "bottle-109",
    "bottle-111",
}
TEXT_IDS = {
    "bottle-001", "bottle-013", "bottle-019", "bottle-023", "bottle-028", "bottle-032",
    "bottle-033", "bottle-041", "bottle-043", "bottle-046", "bottle-047", "bottle-053",
    "bottle-057", "bottle-062", "bottle-063", "bottle-068", "bottle-071", "bottle-076",
    "bottle-078", "bottle-079",
}

n_bin = n_txt = 0
for line in src.read_text().splitlines():
    if not line.strip():
        continue
    v = json.loads(line)
    if v.get("binary") and v["id"] in BINARY_IDS:
        (binary / f"{v['id']}.bin").write_bytes(bytes.fromhex(v["binary"]))
        n_bin += 1
    if v.get("text_in") is not None and v["id"] in TEXT_IDS:
        (text / f"{v['id']}.txt").write_bytes(v["text_in"].encode())
        n_txt += 1
print(f"{n_bin} bottle_decode seeds, {n_txt} text_parse seeds from {src}")
