//! Every file in `mappings/` and `mappings/launch/` loads and validates; the simulated
//! iCub's URDF names exactly the joints its robot files give its control boards.

use std::path::{Path, PathBuf};
use yarp_ros2_gateway::mapping::Mappings;

fn toml_files(dir: &Path) -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    files.sort();
    files
}

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..")
}

#[test]
fn every_shipped_mapping_file_loads() {
    let files = toml_files(&repo().join("mappings"));
    assert!(files.len() >= 5, "{files:?}");
    let launch = toml_files(&repo().join("mappings/launch"));
    assert!(launch.len() >= 5, "{launch:?}");
    for f in files.iter().chain(&launch) {
        if let Err(e) = Mappings::load(std::slice::from_ref(f)) {
            panic!("{e}");
        }
    }
}

/// The simulated iCub's mappings, as `launch-configs/icub-sim.toml` loads them: every part
/// merged into `/joint_states`, the URDF, a CameraInfo beside the camera.
#[test]
fn icub_sim_mappings_give_the_whole_robot() {
    let m = Mappings::load(&[
        repo().join("mappings/launch/icub-sim.toml"),
        repo().join("mappings/launch/icub-sim-camera.toml"),
    ])
    .unwrap_or_else(|e| panic!("{e}"));
    let robot = &m.robots[0];
    let parts = &robot.joint_states.as_ref().unwrap().parts;
    let joint_entries: Vec<&str> = m
        .topics
        .iter()
        .filter(|t| t.ros_type == "sensor_msgs/msg/JointState" && t.joint_names.is_some())
        .map(|t| t.name.as_str())
        .collect();
    assert_eq!(parts, &joint_entries, "every part's JointState is merged");
    let urdf = robot.robot_description.as_ref().unwrap();
    // The robot files' axis names (motorControl/*.xml `AxisName`), without the unused
    // fourth torso axis "none" (the torso's remapper exposes joints 0..2).
    let hw = repo().join("launch-configs/icub-sim/robot/hardware/motorControl");
    let mut axes = Vec::new();
    for f in std::fs::read_dir(&hw).unwrap() {
        let text = std::fs::read_to_string(f.unwrap().path()).unwrap();
        let Some(start) = text.find("name=\"AxisName\">") else {
            continue;
        };
        let rest = &text[start + "name=\"AxisName\">".len()..];
        let list = &rest[..rest.find('<').unwrap()];
        axes.extend(
            list.split('"')
                .skip(1)
                .step_by(2)
                .filter(|n| *n != "none")
                .map(str::to_string),
        );
    }
    axes.sort();
    let mut joints = urdf.joints.clone();
    joints.sort();
    assert_eq!(axes.len(), 53);
    assert_eq!(joints, axes);
    let camera = m.topics.iter().find(|t| t.name == "left_camera").unwrap();
    let ci = camera
        .camera_info
        .as_ref()
        .unwrap()
        .intrinsics
        .as_ref()
        .unwrap();
    assert_eq!(ci.size, Some((320, 240)));
}
