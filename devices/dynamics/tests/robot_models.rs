//! The robots' own URDFs: ergoCubSN001's (../shared/robot-models) read as
//! iDynTree reads it, its F/T sensors against the masses beyond them, and an
//! iCub's arms (PyPI's icub-models) against our iKin chains.

use std::path::{Path, PathBuf};

use icub_ikin::Limb;
use robot_dynamics::estimation::{Contact, ContactKind, Estimator};
use robot_dynamics::kinematics::{BaseMotion, JointState};
use robot_dynamics::nalgebra::Vector3;
use robot_dynamics::urdf;

const G: f64 = 9.81;

fn ergocub() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/robot-models/ergoCub/robots/ergoCubSN001/model.urdf")
}

#[test]
fn ergocub_is_read_as_idyntree_reads_it() {
    let model = urdf::read_file(ergocub()).unwrap();
    // 204 URDF links, 138 of them massless leaves on fixed joints (frames).
    assert_eq!(
        (model.links.len(), model.joints.len(), model.dof_count()),
        (66, 65, 57)
    );
    assert!((model.mass() - 56.651).abs() < 1e-3, "{}", model.mass());
    let ft: Vec<_> = model.sensors.ft.iter().map(|s| s.name.as_str()).collect();
    assert_eq!(
        ft,
        [
            "l_arm_ft",
            "l_foot_front_ft",
            "l_foot_rear_ft",
            "l_leg_ft",
            "r_arm_ft",
            "r_foot_front_ft",
            "r_foot_rear_ft",
            "r_leg_ft"
        ]
    );
    for (frame, link) in [
        ("l_sole", "l_foot_rear"),
        ("waist_imu_0", "torso_1"),
        ("base_link", "root_link"),
        ("l_hand_palm", "l_hand_palm"),
        ("l_leg_ft_imu", "l_hip_3"),
    ] {
        assert_eq!(
            model.frame(frame).unwrap().link,
            model.link(link).unwrap(),
            "{frame}"
        );
    }
    let est = Estimator::new(model, "root_link").unwrap();
    let s = &est.submodels;
    assert_eq!(s.count(), 9);
    let mass_of = |base: &str| {
        let sub = s.of_link[est.model.link(base).unwrap()];
        s.traversals[sub]
            .order
            .iter()
            .map(|&l| est.model.links[l].inertia.mass)
            .sum::<f64>()
    };
    assert_eq!(s.of_link[est.model.link("root_link").unwrap()], 0);
    for (base, mass) in [
        ("root_link", 26.632),
        ("l_hip_3", 10.590),
        ("r_hip_3", 10.585),
        ("l_foot_front", 0.2211),
        ("l_shoulder_3", 3.972),
        ("r_shoulder_3", 3.988),
    ] {
        assert!(
            (mass_of(base) - mass).abs() < 1e-3,
            "{base}: {}",
            mass_of(base)
        );
    }
}

/// Hanging from root_link at rest, each F/T sensor carries the weight of
/// what lies beyond it: a child-to-parent sensor reads that weight pushing
/// down in the world, a parent-to-child one (the feet's) the opposite.
#[test]
fn ergocub_hanging_sensors_read_the_weight_beyond_them() {
    let model = urdf::read_file(ergocub()).unwrap();
    let est = Estimator::new(model, "root_link").unwrap();
    let m = &est.model;
    let mut q = vec![0.0; m.dof_count()];
    for (name, v) in [
        ("l_knee", -0.6),
        ("r_hip_pitch", 0.4),
        ("l_elbow", 0.9),
        ("torso_pitch", 0.2),
    ] {
        q[m.dof_names().iter().position(|n| *n == name).unwrap()] = v;
    }
    let joints = JointState::at_rest(&q);
    let base = BaseMotion::Fixed {
        frame: m.frame("root_link").unwrap(),
        gravity: Vector3::new(0.0, 0.0, -G),
    };
    let contacts = [Contact::new(m, "root_link", ContactKind::FullWrench).unwrap()];
    let (expected, estimate) = est.expected_ft(&joints, &base, &contacts).unwrap();
    let beyond = |sensor: &str| -> f64 {
        // The mass on the child's side of the sensor's joint.
        let s = &m.sensors.ft[m.sensors.ft_index(sensor).unwrap()];
        let child = m.joints[s.joint].child;
        let t = robot_dynamics::Traversal::filtered(m, child, |j| j != s.joint);
        t.order.iter().map(|&l| m.links[l].inertia.mass).sum()
    };
    for (i, s) in m.sensors.ft.iter().enumerate() {
        let in_world = estimate.states.base_h_link[s.link].rotation
            * s.link_h_sensor.rotation
            * expected[i].fixed_rows::<3>(0).into_owned();
        let sign = if s.applied_on == m.joints[s.joint].parent {
            -1.0
        } else {
            1.0
        };
        let weight = Vector3::new(0.0, 0.0, sign * beyond(&s.name) * G);
        assert!(
            (in_world - weight).norm() < 1e-9,
            "{}: {in_world} vs {weight}",
            s.name
        );
    }
}

/// The ROS venv's icub-models (installed by tests/peers/install-ros2.sh).
fn icub_models() -> Option<PathBuf> {
    let venv = std::env::var_os("ROS_VENV").map(PathBuf::from);
    match venv
        .map(|v| v.join("share/iCub/robots"))
        .filter(|p| p.is_dir())
    {
        Some(p) => Some(p),
        None if std::env::var("CI").as_deref() == Ok("true") => panic!(
            "ROS_VENV has no share/iCub/robots (icub-models): run tests/peers/install-ros2.sh"
        ),
        None => {
            eprintln!("SKIPPED: ROS_VENV with icub-models not set");
            None
        }
    }
}

#[test]
fn icub_arms_are_ikins_chains() {
    let Some(dir) = icub_models() else { return };
    let robot = "iCubGenova02";
    let model = urdf::read_file(dir.join(robot).join("model.urdf")).unwrap();
    let est = Estimator::new(model, "root_link").unwrap();
    let m = &est.model;
    let base = BaseMotion::Fixed {
        frame: m.frame("root_link").unwrap(),
        gravity: Vector3::new(0.0, 0.0, -G),
    };
    for (side, ty) in [("l", "left_v2"), ("r", "right_v2")] {
        let mut arm = Limb::arm(ty).unwrap();
        let arm_joints = [
            "shoulder_pitch",
            "shoulder_roll",
            "shoulder_yaw",
            "elbow",
            "wrist_prosup",
            "wrist_pitch",
            "wrist_yaw",
        ];
        for (torso, part) in [
            ([0.0; 3], [0.0, 10.0, 0.0, 15.0, 0.0, 0.0, 0.0]),
            (
                [10.0, -5.0, 15.0],
                [-60.0, 45.0, 20.0, 80.0, -30.0, 10.0, 5.0],
            ),
            (
                [-20.0, 10.0, 30.0],
                [-10.0, 90.0, -30.0, 100.0, 45.0, -20.0, -10.0],
            ),
        ] {
            let mut q = vec![0.0; m.dof_count()];
            let names = m.dof_names();
            let mut set = |name: String, deg: f64| {
                q[names.iter().position(|n| *n == name).unwrap()] = deg.to_radians()
            };
            for (n, v) in ["torso_yaw", "torso_roll", "torso_pitch"].iter().zip(torso) {
                set(n.to_string(), v);
            }
            for (n, v) in arm_joints.iter().zip(part) {
                set(format!("{side}_{n}"), v);
            }
            let states = est.kinematics(&JointState::at_rest(&q), &base).unwrap();
            let hand = m.frame(&format!("{side}_hand_dh_frame")).unwrap();
            let ours = (states.base_h_link[hand.link] * hand.link_h_frame).to_homogeneous();
            arm.set_from_encoders(&torso, &part).unwrap();
            let ikin = arm.chain().h();
            let dp = (ours.fixed_view::<3, 1>(0, 3) - ikin.fixed_view::<3, 1>(0, 3)).norm();
            let r = ours.fixed_view::<3, 3>(0, 0).transpose() * ikin.fixed_view::<3, 3>(0, 0);
            let angle = ((r.trace() - 1.0) / 2.0)
                .clamp(-1.0, 1.0)
                .acos()
                .to_degrees();
            // The URDF is the CAD, iKin the nominal DH: millimetres apart, same axes.
            assert!(
                dp < 0.010 && angle < 0.05,
                "{robot} {ty} {torso:?} {part:?}: {:.2} mm, {angle:.3} deg",
                dp * 1e3
            );
        }
    }
}

/// Kinematics from the waist IMU (on torso_1, reached against the URDF's
/// joints) gives what kinematics from the fixed root gives when the IMU reads
/// the gravity of that posture: the same F/T readings and torques.
#[test]
fn ergocub_from_its_imu_is_ergocub_from_its_root() {
    let model = urdf::read_file(ergocub()).unwrap();
    let est = Estimator::new(model, "root_link").unwrap();
    let m = &est.model;
    let q: Vec<f64> = (0..m.dof_count())
        .map(|i| 0.3 * ((i as f64) * 1.7).sin())
        .collect();
    let still = JointState::at_rest(&q);
    let g = Vector3::new(0.0, 0.0, -G);
    let fixed = BaseMotion::Fixed {
        frame: m.frame("root_link").unwrap(),
        gravity: g,
    };
    let states = est.kinematics(&still, &fixed).unwrap();
    let imu = m.frame("waist_imu_0").unwrap();
    let root_h_imu = states.relative(est.traversal.base, imu.link) * imu.link_h_frame;
    let floating = BaseMotion::Floating {
        frame: imu,
        proper_acc: root_h_imu.rotation.inverse() * -g,
        ang_vel: Vector3::zeros(),
        ang_acc: Vector3::zeros(),
    };
    let contacts = [Contact::new(m, "root_link", ContactKind::FullWrench).unwrap()];
    let (ft_fixed, a) = est.expected_ft(&still, &fixed, &contacts).unwrap();
    let (ft_floating, b) = est.expected_ft(&still, &floating, &contacts).unwrap();
    for (x, y) in ft_fixed.iter().zip(&ft_floating) {
        assert!((x - y).norm() < 1e-9, "{x} vs {y}");
    }
    assert!((a.torques - b.torques).norm() < 1e-9);
}
