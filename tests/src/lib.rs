//! Shared helpers for the integration tests: locating and loading the recorded C++ YARP
//! vectors in `../shared/yarp-vectors/`.

use std::path::PathBuf;

/// Directory of the recorded vectors: `$YARP_VECTORS_DIR`, else `../shared/yarp-vectors`
/// beside the repository. Panics with a clear message if missing: these tests must never
/// be skipped silently.
pub fn vectors_dir() -> PathBuf {
    let dir = std::env::var_os("YARP_VECTORS_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| {
            PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../shared/yarp-vectors")
        });
    assert!(
        dir.join("README.md").is_file(),
        "YARP vectors not found at {} (set YARP_VECTORS_DIR)",
        dir.display()
    );
    dir
}

/// Loads every record of one `.jsonl` file.
pub fn load_records(file: &str) -> Vec<serde_json::Value> {
    let path = vectors_dir().join(file);
    let text = std::fs::read_to_string(&path)
        .unwrap_or_else(|e| panic!("cannot read {}: {e}", path.display()));
    text.lines()
        .filter(|l| !l.trim().is_empty())
        .enumerate()
        .map(|(i, l)| {
            serde_json::from_str(l)
                .unwrap_or_else(|e| panic!("{}:{}: bad JSON: {e}", path.display(), i + 1))
        })
        .collect()
}

/// Decodes a lowercase hex field.
pub fn hex_field(rec: &serde_json::Value, key: &str) -> Vec<u8> {
    let s = rec[key]
        .as_str()
        .unwrap_or_else(|| panic!("{}: field {key} missing", rec["id"]));
    hex::decode(s).unwrap_or_else(|e| panic!("{}: field {key}: {e}", rec["id"]))
}

/// A record's `id`, for messages.
pub fn id(rec: &serde_json::Value) -> &str {
    rec["id"].as_str().unwrap_or("?")
}
