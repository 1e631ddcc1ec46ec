//! wholebodydynamics on an iCub: iCubGenova02 from its own files (`icub_all.xml`: every
//! part, its six strain F/T sensors; its `icub_wbd.xml` attaches wrappers to remappers it
//! does not open, so C++ cannot run it either), its URDF
//! from PyPI's icub-models as the emulated body, held at the root (on its pole). The
//! robot's `estimators/wholebodydynamics.xml` predates the groups whole-body-estimators
//! requires (C++ refuses it, as ours does in the census), so the test does what its
//! user would: the same file with `HW_USE_MAS_IMU`, the F/T sensors' names, the fixed
//! root as kinematic source and a wrench port for the left hand, included in
//! `icub_all.xml`. In three poses the
//! torques its boards report are the body's within 0.05 N·m or 2 %; a 10 N push on the
//! left hand shows on the hand's wrench port and in the arm's torques.

mod common;

use common::*;
use std::path::PathBuf;

/// The ROS venv's icub-models (tests/peers/install-ros2.sh installs it there).
fn icub_models() -> Option<PathBuf> {
    let dir = std::env::var_os("ROS_VENV")
        .map(|v| PathBuf::from(v).join("share/iCub"))
        .filter(|d| d.is_dir());
    if dir.is_none() {
        assert!(
            std::env::var("CI").as_deref() != Ok("true"),
            "ROS_VENV has no share/iCub (icub-models): run tests/peers/install-ros2.sh"
        );
        eprintln!("SKIPPED: no icub-models (set ROS_VENV)");
    }
    dir
}

/// The user's wholebodydynamics.xml: the robot's, with what whole-body-estimators needs.
fn users_file(robot_file: &str) -> String {
    let groups = r#"
        <param name="assume_fixed">root_link</param>
        <group name="HW_USE_MAS_IMU">
            <param name="accelerometer">head_imu_acc_1x1</param>
            <param name="gyroscope">head_imu_acc_1x1</param>
        </group>
        <group name="multipleAnalogSensorsNames">
            <param name="SixAxisForceTorqueSensorsNames">(l_arm_ft, r_arm_ft, l_leg_ft, r_leg_ft, l_foot_ft, r_foot_ft)</param>
        </group>
"#;
    let text = robot_file.replacen("<param name=\"modelFile\">", &format!("{groups}        <param name=\"modelFile\">"), 1).replacen(
        "<group name=\"WBD_OUTPUT_EXTERNAL_WRENCH_PORTS\">",
        "<group name=\"WBD_OUTPUT_EXTERNAL_WRENCH_PORTS\">\n            <param name=\"/icub02/wholeBodyDynamics/left_arm/cartesianEndEffectorWrench:o\">(l_hand,l_hand,root_link)</param>",
        1,
    );
    // the head's IMU is not opened by icub_all.xml (held at the root, none is needed)
    let text: String = text
        .lines()
        .filter(|l| !l.contains("<elem name=\"imu\">"))
        .map(|l| format!("{l}\n"))
        .collect();
    assert!(
        text.contains("HW_USE_MAS_IMU") && text.contains("left_arm/cartesianEndEffectorWrench")
    );
    text
}

#[test]
fn icub_on_its_pole_torques_and_a_push_are_the_bodys() {
    let Some(models) = icub_models() else { return };
    let spec = RobotSpec {
        name: "iCubGenova02",
        urdf: models.join("robots/iCubGenova02/model.urdf"),
        data_dir: models.clone(),
        config: None,
        prefix: "/icub",
        wbd_rpc: "/icub02/wholebodydynamics/rpc",
    };
    let work = tempfile::tempdir().unwrap();
    let dir = work.path().join("iCubGenova02");
    copy_dir(&shared().join("robots-configuration/iCubGenova02"), &dir);
    let file = dir.join("estimators/wholebodydynamics.xml");
    std::fs::write(&file, users_file(&std::fs::read_to_string(&file).unwrap())).unwrap();
    let top = dir.join("icub_all.xml");
    let text = std::fs::read_to_string(&top).unwrap().replacen(
        "</devices>",
        "    <xi:include href=\"estimators/wholebodydynamics.xml\" />\n    </devices>",
        1,
    );
    std::fs::write(&top, text).unwrap();
    let mut r = start(&spec, &dir, "fixed-root");
    let poses: [&[(&str, f64)]; 3] = [
        &[],
        &[
            ("l_shoulder_pitch", -40.0),
            ("l_shoulder_roll", 40.0),
            ("l_elbow", 50.0),
            ("r_shoulder_pitch", -20.0),
            ("r_elbow", 70.0),
            ("torso_pitch", 10.0),
            ("l_hip_pitch", 30.0),
            ("l_knee", -40.0),
            ("r_hip_roll", 15.0),
            ("r_knee", -20.0),
        ],
        &[
            ("l_shoulder_roll", 70.0),
            ("l_shoulder_yaw", 20.0),
            ("r_shoulder_roll", 45.0),
            ("r_shoulder_yaw", -20.0),
            ("torso_roll", 5.0),
            ("torso_yaw", 15.0),
            ("l_hip_pitch", -10.0),
            ("l_ankle_pitch", 20.0),
            ("r_hip_pitch", 45.0),
            ("r_knee", -60.0),
        ],
    ];
    let mut worst = (0.0f64, String::new());
    for (k, targets) in poses.iter().enumerate() {
        pose(&r.robot, &r.names, targets);
        let axes = r.estimated.clone();
        let w = check_torques(&mut r, &axes, &format!("pose {k}"));
        if w.0 > worst.0 {
            worst = w;
        }
    }
    eprintln!("worst difference {:.4} N·m ({})", worst.0, worst.1);
    // 10 N down on the left hand.
    push_down(&mut r, "l_hand");
    let arm: Vec<String> = [
        "l_shoulder_pitch",
        "l_shoulder_roll",
        "l_shoulder_yaw",
        "l_elbow",
    ]
    .map(String::from)
    .to_vec();
    let w = check_torques(&mut r, &arm, "pushed");
    eprintln!("pushed: worst difference {:.4} N·m ({})", w.0, w.1);
    let wrench = read_wrench(
        &r,
        "/icub02/wholeBodyDynamics/left_arm/cartesianEndEffectorWrench:o",
    );
    assert!(
        wrench[0].abs() < 0.5 && wrench[1].abs() < 0.5 && (wrench[2] + 10.0).abs() < 0.5,
        "the hand's external wrench {wrench:?}, pushed with (0, 0, -10) N"
    );
    eprintln!("the left hand's wrench port: {wrench:?}");
}
