//! Every robot's `cartesianSolver.ini` (robots-configuration, in service and retired),
//! read as `iKinCartesianSolver --part <group>` reads it, unmodified.

use icub_cartesian::solver::{SolverConfig, SolverConfigError};
use std::path::{Path, PathBuf};

fn solver_files() -> Vec<PathBuf> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/robots-configuration");
    let mut out = Vec::new();
    for dir in [root.clone(), root.join("robots-icebox")] {
        let Ok(entries) = std::fs::read_dir(&dir) else {
            continue;
        };
        for e in entries.flatten() {
            let f = e.path().join("cartesianSolver.ini");
            if f.is_file() {
                out.push(f);
            }
        }
    }
    out.sort();
    out
}

#[test]
fn every_robots_solver_groups_read() {
    let files = solver_files();
    assert!(
        files.len() >= 30,
        "robots-configuration has {} solver files",
        files.len()
    );
    let (mut groups, mut custom) = (0, 0);
    for f in &files {
        let text = std::fs::read_to_string(f).unwrap();
        let ini = yarp_proto::Property::from_config_text(&text)
            .unwrap_or_else(|e| panic!("{}: {e}", f.display()));
        for part in ["left_arm", "right_arm", "left_leg", "right_leg"] {
            if ini.find_group(part).is_none() {
                continue;
            }
            match SolverConfig::from_ini(part, &ini) {
                Ok(cfg) => {
                    groups += 1;
                    assert_eq!(
                        cfg.name,
                        format!("cartesianSolver/{part}"),
                        "{}",
                        f.display()
                    );
                    assert_eq!(cfg.period.as_millis(), 20, "{}", f.display());
                    assert!(!cfg.tracking && cfg.full_pose, "{}", f.display());
                    let released = cfg
                        .dof
                        .as_ref()
                        .map(|d| d.iter().filter(|v| **v != 0).count());
                    let want = if part.ends_with("arm") { 7 } else { 6 };
                    assert_eq!(released, Some(want), "{} [{part}]", f.display());
                }
                // iCubChemnitz01's arm: a chain of its own file
                Err(SolverConfigError::Custom(_)) => custom += 1,
                Err(e) => panic!("{} [{part}]: {e}", f.display()),
            }
        }
    }
    eprintln!(
        "{} files, {groups} groups read, {custom} custom",
        files.len()
    );
    assert!(groups >= 100, "{groups} groups");
    assert_eq!(custom, 1);
}

/// Every robot's `iKinGazeCtrl.ini`, read as the module reads it: the head version snapped
/// to the ones iKinGazeCtrl knows, and its eyes built from it.
#[test]
fn every_robots_gaze_file_reads() {
    use icub_cartesian::gaze::core::GazeConfig;
    use icub_cartesian::gaze::kinematics::Head;
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/robots-configuration");
    let mut seen = std::collections::BTreeMap::new();
    for dir in [root.clone(), root.join("robots-icebox")] {
        for e in std::fs::read_dir(&dir).into_iter().flatten().flatten() {
            let f = e.path().join("iKinGazeCtrl.ini");
            if !f.is_file() {
                continue;
            }
            let text = std::fs::read_to_string(&f).unwrap();
            let p = yarp_proto::Property::from_config_text(&text)
                .unwrap_or_else(|err| panic!("{}: {err}", f.display()));
            let cfg = GazeConfig::from_property(&p);
            Head::new(&cfg.head_version)
                .unwrap_or_else(|err| panic!("{}: {}: {err}", f.display(), cfg.head_version));
            let robot = e.file_name().to_string_lossy().into_owned();
            seen.insert(robot, cfg.head_version.clone());
        }
    }
    assert!(seen.len() >= 30, "{seen:?}");
    // C++'s snapping: 2.8 kept, 3.1 to 3.0, no version 1.0
    assert_eq!(seen.get("iCubGenova02").map(String::as_str), Some("v2.8"));
    assert_eq!(seen.get("iCubGenova09").map(String::as_str), Some("v3.0"));
    assert_eq!(seen.get("iCubLausanne01").map(String::as_str), Some("v1.0"));
}
