//! Every file in `mappings/` loads and validates.

use std::path::PathBuf;
use yarp_ros2_gateway::mapping::Mappings;

#[test]
fn every_shipped_mapping_file_loads() {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../mappings");
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    files.sort();
    assert!(files.len() >= 5, "{files:?}");
    for f in &files {
        if let Err(e) = Mappings::load(std::slice::from_ref(f)) {
            panic!("{e}");
        }
    }
}
