//! wholebodydynamics on ergoCubSN001, live from the robot's own files: our
//! `yarprobotinterface` on `ergocub.xml` against `icub-robot-emulator` with the robot's
//! URDF as its body, hanging at its root (as on the crane): the F/T sensors and the
//! waist MTi read the body's statics. After `calib` on `<prefix>/rpc` (offsets: the
//! emulated sensors have none), in three poses, the torques the boards report (which
//! wholebodydynamics sends them as their virtual torque sensors) are the body's joint
//! torques, within 0.05 N·m or 2 %.

mod common;

use common::*;
use std::time::Duration;

fn ergocub() -> RobotSpec {
    RobotSpec {
        name: "ergoCubSN001",
        urdf: shared().join("robot-models/ergoCub/robots/ergoCubSN001/model.urdf"),
        data_dir: shared().join("robot-models/ergoCub"),
        config: None,
        prefix: "/ergocub",
        wbd_rpc: "/wholeBodyDynamics/rpc",
    }
}

/// Three poses: the boards' torques (wholebodydynamics' estimates, through the boards'
/// virtual torque sensors) are the body's; a compliant joint gets its gravity torque as
/// impedance offset.
#[test]
fn ergocub_hanging_torques_are_the_bodys() {
    let work = tempfile::tempdir().unwrap();
    let dir = work.path().join("ergoCubSN001");
    copy_dir(&shared().join("robots-configuration/ergoCubSN001"), &dir);
    let mut r = start(&ergocub(), &dir, "fixed-root");
    let poses: [&[(&str, f64)]; 3] = [
        &[],
        &[
            ("l_shoulder_pitch", -40.0),
            ("l_shoulder_roll", 30.0),
            ("l_elbow", 50.0),
            ("r_shoulder_pitch", -20.0),
            ("r_elbow", 70.0),
            ("torso_pitch", 10.0),
            ("l_hip_pitch", 30.0),
            ("l_knee", -40.0),
            ("r_hip_roll", 15.0),
            ("r_knee", -20.0),
            ("neck_pitch", 10.0),
        ],
        &[
            ("l_shoulder_roll", 60.0),
            ("l_shoulder_yaw", 20.0),
            ("l_wrist_yaw", 20.0),
            ("r_shoulder_roll", 45.0),
            ("r_wrist_pitch", 20.0),
            ("torso_roll", 5.0),
            ("torso_yaw", 15.0),
            ("l_hip_pitch", -10.0),
            ("l_ankle_pitch", 20.0),
            ("r_hip_pitch", 45.0),
            ("r_knee", -60.0),
            ("r_ankle_roll", 10.0),
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
    // Gravity compensation: l_hip_pitch, compliant in position control, gets its gravity
    // torque as impedance offset.
    let j = r.names["left_leg"]
        .iter()
        .position(|n| n == "l_hip_pitch")
        .unwrap();
    let leg = "/ergocub/left_leg/rpc:i";
    let reply = r
        .robot
        .rpc(leg, &format!("[set] [intm] [mode] {j} [comp]\n"));
    assert!(!reply.contains("[fail]"), "{reply}");
    std::thread::sleep(Duration::from_secs(1));
    let offset = numbers(&r.robot.net.rpc(leg, &format!("[get] [iimp] [iof] {j}\n")));
    let gravity = body_torques(&mut r.emulator)["l_hip_pitch"];
    let got = *offset.last().expect("an impedance offset");
    assert!(
        (got - gravity).abs() <= (0.02 * gravity.abs()).max(0.05),
        "impedance offset {got:.4} N·m, gravity torque {gravity:.4} N·m ({offset:?})"
    );
    eprintln!(
        "l_hip_pitch compliant: impedance offset {got:.4} N·m, gravity torque {gravity:.4} N·m"
    );
}

/// A user's wholebodydynamics.xml for manipulation: the left arm's F/T sensor among the
/// estimation's and a contact at the left palm. The emulator pushes the palm down with
/// 10 N: the palm's wrench port shows it, and the arm's torques follow the body's (its
/// change is the Jacobian-transposed push).
#[test]
fn ergocub_push_on_the_palm_is_estimated() {
    let work = tempfile::tempdir().unwrap();
    let dir = work.path().join("ergoCubSN001");
    copy_dir(&shared().join("robots-configuration/ergoCubSN001"), &dir);
    let file = dir.join("estimators/wholebodydynamics.xml");
    let text = std::fs::read_to_string(&file)
        .unwrap()
        .replace(
            "(l_foot_front_ft, l_foot_rear_ft,",
            "(l_arm_ft, l_foot_front_ft, l_foot_rear_ft,",
        )
        .replace(
            "(root_link,l_foot_front,",
            "(root_link,l_hand_palm,l_foot_front,",
        );
    assert!(text.contains("(l_arm_ft,") && text.contains("l_hand_palm,l_foot_front"));
    std::fs::write(&file, text).unwrap();
    let mut r = start(&ergocub(), &dir, "fixed-root");
    pose(
        &r.robot,
        &r.names,
        &[
            ("l_shoulder_pitch", -30.0),
            ("l_shoulder_roll", 40.0),
            ("l_elbow", 60.0),
        ],
    );
    let arm: Vec<String> = [
        "l_shoulder_pitch",
        "l_shoulder_roll",
        "l_shoulder_yaw",
        "l_elbow",
        "l_wrist_yaw",
        "l_wrist_roll",
        "l_wrist_pitch",
    ]
    .map(String::from)
    .to_vec();
    check_torques(&mut r, &arm, "before the push");
    let before = board_torques(&r.robot, &r.names);
    let truth_before = body_torques(&mut r.emulator);
    push_down(&mut r, "l_hand_palm");
    let worst = check_torques(&mut r, &arm, "pushed");
    let after = board_torques(&r.robot, &r.names);
    let truth_after = body_torques(&mut r.emulator);
    for axis in &arm {
        let (d_est, d_true) = (
            after[axis] - before[axis],
            truth_after[axis] - truth_before[axis],
        );
        eprintln!("{axis}: the push changed the estimate by {d_est:.4} N·m, the body's torque by {d_true:.4} N·m");
    }
    eprintln!("worst difference {:.4} N·m ({})", worst.0, worst.1);
    // The palm's wrench port: (l_hand_palm, l_hand_palm, root_link), the root's axes
    // (the world's: the robot hangs upright), about the palm.
    let line = read_wrench(
        &r,
        "/wholeBodyDynamics/left_arm/cartesianEndEffectorWrench:o",
    );
    let force = (line[0], line[1], line[2]);
    assert!(
        force.0.abs() < 0.5 && force.1.abs() < 0.5 && (force.2 + 10.0).abs() < 0.5,
        "the palm's external wrench {line:?}, pushed with (0, 0, -10) N"
    );
    eprintln!("the palm's wrench port: {line:?}");
}

/// Standing on its four foot plates (the body shares its weight among them): each foot
/// F/T sensor carries its plate's share, and the torques of every estimated joint, legs
/// included, are the body's in two poses.
#[test]
fn ergocub_standing_torques_are_the_bodys() {
    let work = tempfile::tempdir().unwrap();
    let dir = work.path().join("ergoCubSN001");
    copy_dir(&shared().join("robots-configuration/ergoCubSN001"), &dir);
    let mut r = start(
        &ergocub(),
        &dir,
        "standing:l_foot_front,l_foot_rear,r_foot_front,r_foot_rear",
    );
    let axes = r.estimated.clone();
    let mut worst = check_torques(&mut r, &axes, "standing");
    pose(
        &r.robot,
        &r.names,
        &[
            ("l_shoulder_pitch", -30.0),
            ("r_elbow", 60.0),
            ("torso_pitch", 15.0),
            ("l_hip_roll", 5.0),
            ("neck_pitch", -10.0),
        ],
    );
    let w = check_torques(&mut r, &axes, "standing, leaning");
    if w.0 > worst.0 {
        worst = w;
    }
    eprintln!("worst difference {:.4} N·m ({})", worst.0, worst.1);
}
