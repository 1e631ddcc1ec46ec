//! Forward kinematics against poses derived independently from the DH tables
//! published in the iCub documentation ("iCub Forward Kinematics" pages of
//! icub-tech-iit), plus the construction rules of iKin's limbs.

mod common;

use std::f64::consts::{FRAC_PI_2, PI};

use common::{all_limbs, all_released, translation, Rng};
use icub_ikin::nalgebra::{Matrix4, Rotation3, Translation3, Vector3, Vector4};
use icub_ikin::{pose, Chain, KinError, Limb, LimbKind, Link, DEG2RAD};

/// Standard DH transform built from elementary motions (an implementation
/// independent of `Link::h`): Rz(θ) · Tz(d) · Tx(a) · Rx(α).
fn dh_ref(a: f64, d: f64, alpha: f64, theta: f64) -> Matrix4<f64> {
    Rotation3::from_axis_angle(&Vector3::z_axis(), theta).to_homogeneous()
        * Translation3::new(0.0, 0.0, d).to_homogeneous()
        * Translation3::new(a, 0.0, 0.0).to_homogeneous()
        * Rotation3::from_axis_angle(&Vector3::x_axis(), alpha).to_homogeneous()
}

/// A published table row: A \[mm\], d \[mm\], α \[rad\], θ offset \[deg\].
type Row = (f64, f64, f64, f64);

fn fk_ref(h0: Matrix4<f64>, rows: &[Row], hn: Matrix4<f64>, q_deg: &[f64]) -> Matrix4<f64> {
    let mut h = h0;
    for (r, q) in rows.iter().zip(q_deg) {
        h *= dh_ref(r.0 / 1000.0, r.1 / 1000.0, r.2, (r.3 + q) * DEG2RAD);
    }
    h * hn
}

fn m(rows: [[f64; 4]; 3], mm: bool) -> Matrix4<f64> {
    let s = if mm { 1e-3 } else { 1.0 };
    Matrix4::new(
        rows[0][0],
        rows[0][1],
        rows[0][2],
        rows[0][3] * s,
        rows[1][0],
        rows[1][1],
        rows[1][2],
        rows[1][3] * s,
        rows[2][0],
        rows[2][1],
        rows[2][2],
        rows[2][3] * s,
        0.0,
        0.0,
        0.0,
        1.0,
    )
}

const T_RO0: [[f64; 4]; 3] = [[0., -1., 0., 0.], [0., 0., -1., 0.], [1., 0., 0., 0.]];

const LEFT_ARM_V1: [Row; 10] = [
    (32.0, 0.0, FRAC_PI_2, 0.0),
    (0.0, -5.5, FRAC_PI_2, -90.0),
    (23.3647, -143.3, -FRAC_PI_2, 105.0),
    (0.0, 107.74, -FRAC_PI_2, 90.0),
    (0.0, 0.0, FRAC_PI_2, -90.0),
    (15.0, 152.28, -FRAC_PI_2, 75.0),
    (-15.0, 0.0, FRAC_PI_2, 0.0),
    (0.0, 137.3, FRAC_PI_2, -90.0),
    (0.0, 0.0, FRAC_PI_2, 90.0),
    (62.5, -16.0, 0.0, 0.0),
];

const LEFT_LEG_V1: [Row; 6] = [
    (0.0, 0.0, -FRAC_PI_2, 90.0),
    (0.0, 0.0, -FRAC_PI_2, 90.0),
    (0.0, -223.6, FRAC_PI_2, -90.0),
    (-213.0, 0.0, PI, 90.0),
    (0.0, 0.0, -FRAC_PI_2, 0.0),
    (-41.0, 0.0, 0.0, 0.0),
];

const IMU_V1: [Row; 6] = [
    (32.0, 0.0, FRAC_PI_2, 0.0),
    (0.0, -5.5, FRAC_PI_2, -90.0),
    (2.31, -193.3, -FRAC_PI_2, -90.0),
    (33.0, 0.0, FRAC_PI_2, 90.0),
    (0.0, 1.0, -FRAC_PI_2, -90.0),
    (22.5, 100.5, -FRAC_PI_2, 90.0),
];

const RIGHT_EYE_V1: [Row; 8] = [
    (32.0, 0.0, FRAC_PI_2, 0.0),
    (0.0, -5.5, FRAC_PI_2, -90.0),
    (2.31, -193.3, -FRAC_PI_2, -90.0),
    (33.0, 0.0, FRAC_PI_2, 90.0),
    (0.0, 1.0, -FRAC_PI_2, -90.0),
    (-54.0, 82.5, -FRAC_PI_2, 90.0),
    (0.0, 34.0, -FRAC_PI_2, 0.0),
    (0.0, 0.0, FRAC_PI_2, -90.0),
];

fn assert_close(a: &Matrix4<f64>, b: &Matrix4<f64>, tol: f64) {
    let d = (a - b).amax();
    assert!(d < tol, "matrices differ by {d}:\n{a}\n{b}");
}

/// Compares the limb with the published table at zero and at random joints.
fn check_against_table(limb: &Limb, h0: Matrix4<f64>, rows: &[Row], hn: Matrix4<f64>) {
    let chain = all_released(limb.chain());
    assert_eq!(chain.n(), rows.len());
    let mut rng = Rng(0x5eed ^ rows.len() as u64);
    let mut q_deg = vec![0.0; rows.len()];
    for trial in 0..20 {
        if trial > 0 {
            q_deg = (0..rows.len())
                .map(|_| -90.0 + 180.0 * rng.next_f64())
                .collect();
        }
        let q: Vec<f64> = q_deg.iter().map(|v| v * DEG2RAD).collect();
        assert_close(
            &chain.h_at(&q).unwrap(),
            &fk_ref(h0, rows, hn, &q_deg),
            1e-12,
        );
    }
}

#[test]
fn link_transform_is_standard_dh() {
    let mut rng = Rng(7);
    for _ in 0..100 {
        let mut r = || rng.next_f64() * 2.0 - 1.0;
        let (a, d, alpha, offset, q) = (r(), r(), r() * PI, r() * PI, r() * PI);
        let l = Link::new(a, d, alpha, offset, -PI, PI);
        assert_close(&l.h(q), &dh_ref(a, d, alpha, q + offset), 1e-14);
    }
}

#[test]
fn left_arm_v1_matches_published_table() {
    check_against_table(
        &Limb::arm("left_v1").unwrap(),
        m(T_RO0, false),
        &LEFT_ARM_V1,
        Matrix4::identity(),
    );
}

#[test]
fn left_leg_v1_matches_published_table() {
    let h0 = m(
        [[1., 0., 0., 0.], [0., 0., 1., -68.1], [0., -1., 0., -119.9]],
        true,
    );
    check_against_table(
        &Limb::leg("left").unwrap(),
        h0,
        &LEFT_LEG_V1,
        Matrix4::identity(),
    );
}

#[test]
fn inertial_v1_matches_published_table() {
    let t_nis = m(
        [[1., 0., 0., 0.], [0., 0., -1., 0.], [0., 1., 0., 6.6]],
        true,
    );
    check_against_table(
        &Limb::inertial_sensor("v1").unwrap(),
        m(T_RO0, false),
        &IMU_V1,
        t_nis,
    );
}

#[test]
fn right_eye_v1_matches_published_table() {
    check_against_table(
        &Limb::eye("right").unwrap(),
        m(T_RO0, false),
        &RIGHT_EYE_V1,
        Matrix4::identity(),
    );
}

/// With all joints at zero a leg is straight: the foot lies below the hip by
/// the sum of the link lengths (0.1199 + 0.2236 + 0.213 + 0.041 m for v1).
#[test]
fn straight_leg_at_zero_joints() {
    for (t, y) in [("left", -0.0681), ("right_v1", 0.0681)] {
        let leg = Limb::leg(t).unwrap();
        let h = leg.chain().h_at(&[0.0; 6]).unwrap();
        let p = translation(&h);
        let expected = [0.0, y, -(0.1199 + 0.2236 + 0.213 + 0.041)];
        for k in 0..3 {
            assert!((p[k] - expected[k]).abs() < 1e-12, "{t}: {p:?}");
        }
        // Foot frame: z points forward (-x of the root), x points up.
        let r = pose::rotation(&h);
        assert!((r[(2, 0)] - 1.0).abs() < 1e-12 && (r[(0, 2)] + 1.0).abs() < 1e-12);
    }
    // v2.5: 0.1199 + 0.234545 + 0.2005 + 0.06805 down, a of link 2 and d of
    // the last link forward.
    let h = Limb::leg("right_v2.5")
        .unwrap()
        .chain()
        .h_at(&[0.0; 6])
        .unwrap();
    let p = translation(&h);
    assert!((p[2] + (0.1199 + 0.234545 + 0.2005 + 0.06805)).abs() < 1e-12);
    assert!((p[1] - 0.0681).abs() < 1e-12);
    assert!((p[0] - (0.0009175 + 0.0035)).abs() < 1e-12);
}

/// Reference end-effector positions at zero joints (all links, torso
/// included), computed once from the DH tables; left and right mirror in y.
#[test]
fn zero_joint_hand_positions_mirror() {
    for (left, right) in [
        ("left", "right"),
        ("left_v1.7", "right_v1.7"),
        ("left_v2", "right_v2"),
        ("left_v3", "right_v3"),
    ] {
        let l = all_released(Limb::arm(left).unwrap().chain())
            .h_at(&[0.0; 10])
            .unwrap();
        let r = all_released(Limb::arm(right).unwrap().chain())
            .h_at(&[0.0; 10])
            .unwrap();
        let (pl, pr) = (translation(&l), translation(&r));
        assert!((pl[0] - pr[0]).abs() < 1e-9 && (pl[1] + pr[1]).abs() < 1e-9);
        assert!((pl[2] - pr[2]).abs() < 1e-9);
        // The hanging hand is below the waist and beside the body.
        assert!(pr[2] < -0.1 && pr[1] > 0.05, "{right}: {pr:?}");
    }
    let r = all_released(Limb::arm("right").unwrap().chain())
        .h_at(&[0.0; 10])
        .unwrap();
    let p = translation(&r);
    let expected = [-0.010_8, 0.094_1, -0.176_8];
    for k in 0..3 {
        assert!((p[k] - expected[k]).abs() < 1e-4, "{p:?}");
    }
}

#[test]
fn arm_versions_change_the_right_links() {
    let d = |t: &str, i: usize| Limb::arm(t).unwrap().chain().link(i).unwrap().d;
    assert_eq!(d("right", 7), -0.1373);
    assert_eq!(d("right_v1.5", 7), -0.1373);
    assert_eq!(d("right_v1.7", 7), -0.1413);
    assert_eq!(d("right_v1.7", 9), 0.016);
    assert_eq!(d("right_v2", 9), 0.02598);
    assert_eq!(d("left_v2.7", 9), -0.02598);
    assert_eq!(d("left_v3", 3), 0.163978);
    let v3 = Limb::arm("right_v3").unwrap();
    assert_eq!(v3.version(), 3.0);
    assert_eq!(v3.chain().h0()[(0, 2)], 1.0);
}

#[test]
fn every_known_type_builds_with_ikin_shapes() {
    let limbs = all_limbs();
    assert!(limbs.len() > 100);
    for limb in &limbs {
        let (n, dof) = (limb.chain().n(), limb.chain().dof());
        let expected = match limb.kind() {
            LimbKind::Arm => (10, 7),
            LimbKind::Leg => (6, 6),
            LimbKind::Eye => (8, 5),
            LimbKind::EyeNeckRef => (5, 5),
            LimbKind::HeadCenter => (8, 3),
            LimbKind::InertialSensor => (6, 6),
            LimbKind::Torso => (3, 3),
            LimbKind::Finger => match limb.type_name().split('_').nth(1).unwrap() {
                "thumb" => (5, 4),
                "middle" => (3, 3),
                _ => (4, 4),
            },
        };
        assert_eq!((n, dof), expected, "{}", limb.type_name());
        let h = limb.chain().h();
        let r = pose::rotation(&h);
        let err = (r * r.transpose() - icub_ikin::nalgebra::Matrix3::identity()).amax();
        // Finger base frames are published rounded (the thumb's to ~7e-3);
        // iKin mirrors the left thumb without negating H0(2,0), which leaves
        // version "a" (H0(2,0) = 0.256) non-orthonormal: kept for parity.
        if !limb.type_name().starts_with("left_thumb_a") {
            assert!(err < 1e-2, "{} {err}", limb.type_name());
        }
    }
}

#[test]
fn unknown_types_list_the_known_ones() {
    // a number is a version, as iKin reads it: a side or a version it cannot read is not
    assert!(Limb::arm("left_v9").is_ok() && Limb::leg("right_v2.7").is_ok());
    let err = Limb::arm("middle_v2").unwrap_err();
    match &err {
        KinError::UnknownType { limb, given, known } => {
            assert_eq!(*limb, "iCubArm");
            assert_eq!(given, "middle_v2");
            for k in ["left", "right_v1.7", "left_v2.6", "right_v2.7", "left_v3"] {
                assert!(known.iter().any(|s| s == k), "{k} missing");
            }
        }
        other => panic!("unexpected {other:?}"),
    }
    let msg = err.to_string();
    assert!(
        msg.contains("middle_v2") && msg.contains("right_v2.5"),
        "{msg}"
    );
    for (kind, bad) in [
        (LimbKind::Leg, "left_vtwo"),
        (LimbKind::Leg, "middle_v1"),
        (LimbKind::Eye, "right_v"),
        (LimbKind::HeadCenter, "up"),
        (LimbKind::InertialSensor, "left_v2"),
        (LimbKind::Torso, "v4"),
        (LimbKind::Finger, "right_toe"),
        (LimbKind::Finger, "right_thumb_c"),
        (LimbKind::Arm, ""),
    ] {
        let e = Limb::new(kind, bad).unwrap_err();
        assert!(matches!(e, KinError::UnknownType { .. }), "{bad}");
        assert!(e.to_string().contains("known types"));
    }
}

#[test]
fn inertial_sensor_end_transforms() {
    let hn = |t: &str| *Limb::inertial_sensor(t).unwrap().chain().hn();
    // T_nls of the wiki, then the v2.5 IMU offset expressed in the T_nls frame.
    assert_eq!(translation(&hn("v1")), [0.0, 0.0, 0.0066]);
    let p = translation(&hn("v2.5"));
    for (a, b) in p.iter().zip([0.0087, 0.0105, 0.0066 + 0.01795]) {
        assert!((a - b).abs() < 1e-15, "{p:?}");
    }
    assert_eq!(hn("v3"), hn("v2.5"));
    assert_ne!(hn("v2.6"), hn("v2.5"));
    let r = pose::rotation(&hn("v2.6"));
    assert!((r * r.transpose() - icub_ikin::nalgebra::Matrix3::identity()).amax() < 1e-15);
}

#[test]
fn head_center_and_neck_ref_derive_from_eye() {
    let eye = Limb::eye("left_v2").unwrap();
    let hc = Limb::head_center("left_v2").unwrap();
    assert_eq!(hc.chain().link(6).unwrap().d, 0.0);
    assert!(hc.chain().is_blocked(6).unwrap() && hc.chain().is_blocked(7).unwrap());
    let nr = Limb::eye_neck_ref("left_v2").unwrap();
    assert_eq!(nr.chain().links(), &eye.chain().links()[3..]);
    assert_eq!(nr.chain().h0(), eye.chain().h0());
}

#[test]
fn blocking_and_limits_follow_ikin() {
    let mut arm = Limb::arm("right_v2").unwrap();
    let c = arm.chain_mut();
    // Released links start at their lower bound, as iKinLink does.
    assert_eq!(c.link_ang(3).unwrap(), -95.5 * DEG2RAD);
    assert_eq!(c.link_ang(0).unwrap(), 0.0);
    // Clamping.
    let q = c
        .set_ang_deg(&[-200.0, 0.0, 0.0, 200.0, 0.0, 0.0, 0.0])
        .unwrap();
    assert!((q[0] + 95.5).abs() < 1e-9 && (q[3] - 106.0).abs() < 1e-9);
    assert!(q[1].abs() < 1e-9);
    // Blocking values.
    assert_eq!(c.set_blocking_value(3, 0.1), Err(KinError::NotBlocked(3)));
    assert!((c.set_blocking_value(0, 1.0).unwrap() - 1.0).abs() < 1e-12);
    assert!((c.set_blocking_value(1, 2.0).unwrap() - 39.0 * DEG2RAD).abs() < 1e-12);
    c.release_link(1).unwrap();
    assert_eq!(c.dof(), 8);
    assert_eq!(c.dof_links(), &[1, 3, 4, 5, 6, 7, 8, 9]);
    assert!(matches!(
        c.set_ang(&[0.0; 7]),
        Err(KinError::DimensionMismatch {
            expected: 8,
            got: 7
        })
    ));
    assert!(matches!(
        c.block_link(10, 0.0),
        Err(KinError::LinkIndex { .. })
    ));
    assert!(matches!(
        c.set_ang(&[f64::NAN; 8]),
        Err(KinError::NonFinite(_))
    ));
    assert!(matches!(
        c.set_limits(3, 1.0, 0.0),
        Err(KinError::InvalidBounds { .. })
    ));
    // Unconstrained chains keep out-of-range values.
    c.set_constrained(false);
    let q = c.set_ang(&[3.0; 8]).unwrap();
    assert_eq!(q[0], 3.0);
    // An empty chain has no DOF.
    let mut empty = Chain::new();
    assert_eq!(empty.set_ang(&[]), Err(KinError::NoDof));
}

#[test]
fn link_frames_and_pose_vectors() {
    let arm = Limb::arm("left_v2.5").unwrap();
    let c = arm.chain();
    assert_close(&c.link_h(9).unwrap(), &c.h(), 1e-15);
    let p7 = c.end_eff_pose();
    assert_close(&pose::h_from_pose7(&p7), &c.h(), 1e-12);
    let axis = Vector3::new(p7[3], p7[4], p7[5]);
    assert!((axis.norm() - 1.0).abs() < 1e-12 && p7[6] >= 0.0 && p7[6] <= PI);
    let p6 = c.end_eff_pose_euler();
    assert_eq!(p6[0], p7[0]);
    // dcm2axis corner cases: identity and half turns.
    let id = pose::dcm2axis(&icub_ikin::nalgebra::Matrix3::identity());
    assert_eq!(id, Vector4::new(0.0, 0.0, 1.0, 0.0));
    for axis in [
        Vector3::x(),
        Vector3::y(),
        Vector3::new(1.0, 1.0, 0.0).normalize(),
    ] {
        let r = Rotation3::from_axis_angle(&icub_ikin::nalgebra::Unit::new_normalize(axis), PI);
        let v = pose::dcm2axis(r.matrix());
        assert!((v[3] - PI).abs() < 1e-9);
        assert!((Vector3::new(v[0], v[1], v[2]).cross(&axis)).norm() < 1e-9);
    }
}

#[test]
fn encoders_map_onto_chains() {
    let torso = [10.0, -5.0, 20.0]; // yaw, roll, pitch
    let arm_enc = [-30.0, 30.0, 0.0, 45.0, 0.0, 0.0, 0.0, 0.0, 0.0];
    let mut arm = Limb::arm("left_v2").unwrap();
    arm.set_from_encoders(&torso, &arm_enc).unwrap();
    let a = arm.chain().all_angles();
    // Versions < 3 run the torso pitch -> roll -> yaw.
    assert!((a[0] - 20.0 * DEG2RAD).abs() < 1e-12 && (a[2] - 10.0 * DEG2RAD).abs() < 1e-12);
    assert!((a[3] + 30.0 * DEG2RAD).abs() < 1e-12 && (a[6] - 45.0 * DEG2RAD).abs() < 1e-12);
    let pose = arm.pose_from_encoders(&torso, &arm_enc).unwrap();
    assert_eq!(pose, arm.chain().end_eff_pose());
    let mut arm3 = Limb::arm("left_v3").unwrap();
    arm3.set_from_encoders(&torso, &arm_enc).unwrap();
    assert!((arm3.chain().all_angles()[0] - 10.0 * DEG2RAD).abs() < 1e-12);
    let mut eye = Limb::eye("right_v2").unwrap();
    eye.set_from_encoders(&torso, &[0.0, 0.0, 0.0, -10.0, 10.0, 20.0])
        .unwrap();
    assert!((eye.chain().all_angles()[7] - 0.0).abs() < 1e-12); // 10 - 20/2
    let mut index = Limb::finger("right_index").unwrap();
    index
        .set_from_encoders(&[], &[30.0, 0.0, 0.0, 0.0, 40.0, 60.0, 0.0, 0.0, 0.0])
        .unwrap();
    let q = index.chain().ang_deg();
    assert!((q[0] - 10.0).abs() < 1e-9 && (q[1] - 40.0).abs() < 1e-9 && (q[3] - 30.0).abs() < 1e-9);
    assert!(matches!(
        arm.set_from_encoders(&torso, &[0.0; 3]),
        Err(KinError::DimensionMismatch { .. })
    ));
    assert!(index.set_from_encoders(&[], &[0.0; 10]).is_err());
}
