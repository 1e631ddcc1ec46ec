//! The cost of wholebodydynamics' estimation per cycle on the whole ergoCubSN001 (66
//! links, 57 joints of which 32 estimated, its 4 foot F/T sensors, 5 contacts): the
//! kinematics from the waist IMU, the contacts per submodel and the joint torques;
//! also the offset calibration's expected F/T readings. The robot runs it every 1 ms.

use criterion::{criterion_group, criterion_main, Criterion};
use robot_dynamics::estimation::{ContactKind, Estimator};
use robot_dynamics::kinematics::{BaseMotion, JointState};
use robot_dynamics::nalgebra::{DVector, Vector3};
use robot_dynamics::spatial::Wrench;
use robot_dynamics::urdf;

fn ergocub() -> Estimator {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../../shared/robot-models/ergoCub/robots/ergoCubSN001/model.urdf"
    );
    let axes = "torso_pitch,torso_roll,torso_yaw,neck_pitch,neck_roll,neck_yaw,l_shoulder_pitch,l_shoulder_roll,l_shoulder_yaw,l_elbow,l_wrist_roll,l_wrist_pitch,l_wrist_yaw,r_shoulder_pitch,r_shoulder_roll,r_shoulder_yaw,r_elbow,r_wrist_roll,r_wrist_pitch,r_wrist_yaw,l_hip_pitch,l_hip_roll,l_hip_yaw,l_knee,l_ankle_pitch,l_ankle_roll,r_hip_pitch,r_hip_roll,r_hip_yaw,r_knee,r_ankle_pitch,r_ankle_roll";
    let axes: Vec<&str> = axes.split(',').collect();
    let mut model = urdf::read_file(path)
        .unwrap()
        .with_dofs(&axes, &[])
        .unwrap();
    model
        .select_ft(&[
            "l_foot_front_ft",
            "l_foot_rear_ft",
            "r_foot_front_ft",
            "r_foot_rear_ft",
        ])
        .unwrap();
    Estimator::new(model, "root_link").unwrap()
}

fn bench(c: &mut Criterion) {
    let est = ergocub();
    let frames: Vec<(String, ContactKind)> = [
        "root_link",
        "l_foot_front",
        "l_foot_rear",
        "r_foot_front",
        "r_foot_rear",
    ]
    .iter()
    .map(|f| (f.to_string(), ContactKind::FullWrench))
    .collect();
    let (contacts, _) = est.choose_contacts(&frames).unwrap();
    let n = est.model.dof_count();
    let joints = JointState {
        q: DVector::from_fn(n, |i, _| 0.2 * (i as f64).sin()),
        dq: DVector::from_fn(n, |i, _| 0.1 * (i as f64).cos()),
        ddq: DVector::zeros(n),
    };
    let base = BaseMotion::Floating {
        frame: est.model.frame("waist_imu_0").unwrap(),
        proper_acc: Vector3::new(0.3, -0.2, 9.8),
        ang_vel: Vector3::new(0.01, 0.02, -0.01),
        ang_acc: Vector3::zeros(),
    };
    let ft = vec![Wrench::from_column_slice(&[1.0, 2.0, 60.0, 0.1, 0.2, 0.3]); 4];
    c.bench_function("ergocub_estimate_cycle", |b| {
        b.iter(|| est.estimate(&joints, &base, &ft, &contacts).unwrap())
    });
    let calib = [robot_dynamics::estimation::Contact::new(
        &est.model,
        "base_link",
        ContactKind::FullWrench,
    )
    .unwrap()];
    c.bench_function("ergocub_expected_ft", |b| {
        b.iter(|| est.expected_ft(&joints, &base, &calib).unwrap())
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
