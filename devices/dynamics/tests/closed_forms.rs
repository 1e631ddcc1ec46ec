//! The dynamics against closed forms: a pendulum, a planar two-link arm, and
//! the estimation of a known contact from an F/T sensor between two links.

use robot_dynamics::dynamics::{gravity_torques, inverse_dynamics};
use robot_dynamics::estimation::{Contact, ContactKind, Estimator};
use robot_dynamics::kinematics::{kinematics, BaseMotion, JointState, Traversal};
use robot_dynamics::nalgebra::{DVector, Vector3};
use robot_dynamics::spatial::{six, wrench_to, Wrench};
use robot_dynamics::{urdf, Model};

const G: f64 = 9.81;

fn link(name: &str, mass: f64, com: [f64; 3], izz: f64) -> String {
    format!(
        r#"<link name="{name}"><inertial><origin xyz="{} {} {}" rpy="0 0 0"/><mass value="{mass}"/>
        <inertia ixx="{izz}" ixy="0" ixz="0" iyy="{izz}" iyz="0" izz="{izz}"/></inertial></link>"#,
        com[0], com[1], com[2]
    )
}

fn joint(name: &str, kind: &str, parent: &str, child: &str, xyz: [f64; 3], axis: &str) -> String {
    format!(
        r#"<joint name="{name}" type="{kind}"><origin xyz="{} {} {}" rpy="0 0 0"/><parent link="{parent}"/><child link="{child}"/>
        <axis xyz="{axis}"/><limit lower="-3" upper="3" effort="10" velocity="10"/></joint>"#,
        xyz[0], xyz[1], xyz[2]
    )
}

fn robot(parts: &[String]) -> Model {
    urdf::read_str(&format!(r#"<robot name="r">{}</robot>"#, parts.concat()))
        .expect("test URDF reads")
}

fn fixed_base(model: &Model, frame: &str) -> BaseMotion {
    BaseMotion::Fixed {
        frame: model.frame(frame).unwrap(),
        gravity: Vector3::new(0.0, 0.0, -G),
    }
}

#[test]
fn pendulum_torque_is_inertia_times_acceleration_plus_gravity() {
    // A rod along x from a y axis; positive q lowers it (x turns to -z).
    let (m, l, ic) = (1.5, 0.4, 0.02);
    let model = robot(&[
        link("base", 1.0, [0.0; 3], 0.01),
        link("rod", m, [l, 0.0, 0.0], ic),
        joint("j", "revolute", "base", "rod", [0.0; 3], "0 1 0"),
    ]);
    let t = Traversal::new(&model, model.link("base").unwrap());
    for (q, dq, ddq) in [(0.0, 0.0, 0.0), (0.7, 1.3, -2.0), (-1.2, -0.4, 3.0)] {
        let joints = JointState {
            q: DVector::from_element(1, q),
            dq: DVector::from_element(1, dq),
            ddq: DVector::from_element(1, ddq),
        };
        let states = kinematics(&model, &t, &joints, &fixed_base(&model, "base")).unwrap();
        let tau =
            inverse_dynamics(&model, &t, &joints.q, &states, &[Wrench::zeros(); 2]).torques[0];
        let expected = (ic + m * l * l) * ddq - m * G * l * q.cos();
        assert!((tau - expected).abs() < 1e-12, "q {q}: {tau} vs {expected}");
    }
}

/// The textbook two-link arm in a vertical plane (joints about z, gravity
/// along -y), with its base link tipped so that gravity is -y.
#[test]
fn two_link_arm_matches_the_textbook_equations() {
    let (m1, m2, l1, lc1, lc2, i1, i2) = (2.0, 1.2, 0.5, 0.22, 0.17, 0.03, 0.015);
    let model = robot(&[
        link("base", 3.0, [0.0; 3], 0.1),
        link("upper", m1, [lc1, 0.0, 0.0], i1),
        link("fore", m2, [lc2, 0.0, 0.0], i2),
        joint("shoulder", "revolute", "base", "upper", [0.0; 3], "0 0 1"),
        joint(
            "elbow",
            "continuous",
            "upper",
            "fore",
            [l1, 0.0, 0.0],
            "0 0 1",
        ),
    ]);
    let t = Traversal::new(&model, model.link("base").unwrap());
    let base = BaseMotion::Fixed {
        frame: model.frame("base").unwrap(),
        gravity: Vector3::new(0.0, -G, 0.0),
    };
    for (q, dq, ddq) in [
        ([0.3, 0.9], [0.5, -1.1], [1.7, 0.4]),
        ([-1.0, 2.2], [0.0, 0.0], [0.0, 0.0]),
        ([2.5, -0.6], [-2.0, 1.0], [-0.5, 2.5]),
    ] {
        let joints = JointState {
            q: DVector::from_row_slice(&q),
            dq: DVector::from_row_slice(&dq),
            ddq: DVector::from_row_slice(&ddq),
        };
        let states = kinematics(&model, &t, &joints, &base).unwrap();
        let tau = inverse_dynamics(&model, &t, &joints.q, &states, &[Wrench::zeros(); 3]).torques;
        let (c1, c2, s2, c12) = (q[0].cos(), q[1].cos(), q[1].sin(), (q[0] + q[1]).cos());
        let m11 = m1 * lc1 * lc1 + i1 + m2 * (l1 * l1 + lc2 * lc2 + 2.0 * l1 * lc2 * c2) + i2;
        let m12 = m2 * (lc2 * lc2 + l1 * lc2 * c2) + i2;
        let m22 = m2 * lc2 * lc2 + i2;
        let h = m2 * l1 * lc2 * s2;
        let g1 = (m1 * lc1 + m2 * l1) * G * c1 + m2 * lc2 * G * c12;
        let g2 = m2 * lc2 * G * c12;
        let t1 = m11 * ddq[0] + m12 * ddq[1] - h * (2.0 * dq[0] * dq[1] + dq[1] * dq[1]) + g1;
        let t2 = m12 * ddq[0] + m22 * ddq[1] + h * dq[0] * dq[0] + g2;
        assert!(
            (tau[0] - t1).abs() < 1e-12 && (tau[1] - t2).abs() < 1e-12,
            "q {q:?}: {tau} vs [{t1}, {t2}]"
        );
        if dq == [0.0, 0.0] && ddq == [0.0, 0.0] {
            let g = gravity_torques(
                &model,
                model.frame("base").unwrap(),
                &q,
                Vector3::new(0.0, -G, 0.0),
            )
            .unwrap();
            assert!((g[0] - g1).abs() < 1e-12 && (g[1] - g2).abs() < 1e-12);
        }
    }
}

/// The two-link arm with an F/T sensor splitting its forearm, a massless tip
/// frame (a fake link, so an additional frame) and a push at the tip.
fn arm_with_sensor(direction: &str, frame: &str) -> Model {
    robot(&[
        link("base", 3.0, [0.0; 3], 0.1),
        link("upper", 2.0, [0.2, 0.01, 0.0], 0.03),
        link("fore_a", 0.6, [0.05, 0.0, 0.01], 0.004),
        link("fore_b", 0.7, [0.08, -0.01, 0.0], 0.006),
        r#"<link name="tip"/>"#.to_owned(),
        joint("shoulder", "revolute", "base", "upper", [0.0; 3], "0 1 0"),
        joint("elbow", "revolute", "upper", "fore_a", [0.5, 0.0, 0.0], "0 1 0"),
        r#"<joint name="ft_joint" type="fixed"><origin xyz="0.1 0 0" rpy="0.2 0 0.1"/><parent link="fore_a"/><child link="fore_b"/></joint>"#.to_owned(),
        r#"<joint name="tip_joint" type="fixed"><origin xyz="0.2 0 0" rpy="0 0 0"/><parent link="fore_b"/><child link="tip"/></joint>"#.to_owned(),
        format!(
            r#"<sensor name="ft" type="force_torque"><parent joint="ft_joint"/><force_torque><frame>{frame}</frame>
            <measure_direction>{direction}</measure_direction></force_torque><origin xyz="0.01 0 0" rpy="0 3.14159 0"/></sensor>"#
        ),
    ])
}

#[test]
fn fake_links_become_frames_and_sensors_name_frames() {
    let model = arm_with_sensor("child_to_parent", "sensor");
    assert_eq!(model.links.len(), 4);
    assert_eq!(model.joints.len(), 3);
    assert_eq!(model.dof_names(), ["shoulder", "elbow"]);
    assert_eq!(
        model.frame("tip").unwrap().link,
        model.link("fore_b").unwrap()
    );
    assert_eq!(
        model.frame("ft").unwrap().link,
        model.link("fore_b").unwrap()
    );
    assert_eq!(
        model.sensors.ft[0].applied_on,
        model.link("fore_a").unwrap()
    );
}

#[test]
fn an_f_t_sensor_measures_the_push_beyond_it_and_the_estimator_finds_the_push() {
    for direction in ["child_to_parent", "parent_to_child"] {
        for frame in ["child", "parent", "sensor"] {
            let model = arm_with_sensor(direction, frame);
            let est = Estimator::new(model.clone(), "base").unwrap();
            assert_eq!(est.submodels.count(), 2);
            let joints = JointState {
                q: DVector::from_row_slice(&[0.4, -0.9]),
                dq: DVector::from_row_slice(&[0.3, 0.5]),
                ddq: DVector::from_row_slice(&[-0.2, 0.8]),
            };
            let base = fixed_base(&model, "base");
            // The truth: a push at the tip, then what the sensor reads of it.
            let push = six(Vector3::new(1.0, -2.0, 10.0), Vector3::new(0.1, 0.3, -0.2));
            let tip = model.frame("tip").unwrap();
            let mut ext = vec![Wrench::zeros(); model.links.len()];
            ext[tip.link] = wrench_to(&tip.link_h_frame, &push);
            let t = Traversal::new(&model, model.link("base").unwrap());
            let states = kinematics(&model, &t, &joints, &base).unwrap();
            let truth = inverse_dynamics(&model, &t, &joints.q, &states, &ext);
            let sensor = &model.sensors.ft[0];
            let fore_b = model.link("fore_b").unwrap();
            let reading = sensor.measurement_from(&model, fore_b, &truth.joint_wrenches[fore_b]);
            // Static check of the reading against the subtree's balance: the
            // child's weight and the push, seen from the sensor.
            let contacts = [
                Contact::new(&model, "base", ContactKind::FullWrench).unwrap(),
                Contact::new(&model, "tip", ContactKind::FullWrench).unwrap(),
            ];
            let estimate = est.estimate(&joints, &base, &[reading], &contacts).unwrap();
            assert!(
                (estimate.contact_wrenches[1] - push).norm() < 1e-9,
                "{direction}/{frame}: {}",
                estimate.contact_wrenches[1]
            );
            assert!((estimate.torques.clone() - truth.torques.clone()).norm() < 1e-9);
            // Offsets: what the sensor should read when only the base holds
            // the arm is the forearm's own dynamics.
            let (expected, _) = est.expected_ft(&joints, &base, &contacts[..1]).unwrap();
            let no_push = inverse_dynamics(
                &model,
                &t,
                &joints.q,
                &states,
                &vec![Wrench::zeros(); model.links.len()],
            );
            let unpushed = sensor.measurement_from(&model, fore_b, &no_push.joint_wrenches[fore_b]);
            assert!((expected[0] - unpushed).norm() < 1e-9);
        }
    }
}

#[test]
fn a_static_sensor_reads_the_weight_beyond_it() {
    // Arm stretched along x at rest, sensor frame = child frame (no rotation
    // at q = 0 for `child` with this joint's rpy folded in below).
    let model = arm_with_sensor("child_to_parent", "child");
    let est = Estimator::new(model.clone(), "base").unwrap();
    let (expected, _) = est
        .expected_ft(
            &JointState::at_rest(&[0.0, 0.0]),
            &fixed_base(&model, "base"),
            &[Contact::new(&model, "base", ContactKind::FullWrench).unwrap()],
        )
        .unwrap();
    // child_to_parent: the force fore_b exerts on fore_a is its weight, down
    // in the world; in fore_b's frame (rolled 0.2 and yawed 0.1) that is
    // R^T (0, 0, -m g).
    let fore_b = model.link("fore_b").unwrap();
    let world_h_b = est
        .kinematics(
            &JointState::at_rest(&[0.0, 0.0]),
            &fixed_base(&model, "base"),
        )
        .unwrap()
        .base_h_link[fore_b];
    let weight = world_h_b.rotation.inverse() * Vector3::new(0.0, 0.0, -0.7 * G);
    assert!(
        (expected[0].fixed_rows::<3>(0) - weight).norm() < 1e-12,
        "{}",
        expected[0]
    );
}
