//! Jacobians against numerical differentiation of forward kinematics, over
//! random joint configurations within bounds (proptest).

mod common;

use common::all_released;
use icub_ikin::nalgebra::{DVector, Vector3};
use icub_ikin::{pose, Chain, Limb};
use proptest::prelude::*;

const STEP: f64 = 1e-6;
const TOL: f64 = 1e-6;

/// Chains under test: 10-DOF arm (torso released), 7-DOF arms, leg, eye,
/// inertial sensor, a finger.
fn chains() -> Vec<Chain> {
    let mut out = vec![
        all_released(Limb::arm("right_v2").unwrap().chain()),
        Limb::arm("left_v3").unwrap().into_chain(),
        Limb::arm("right").unwrap().into_chain(),
        Limb::leg("left_v2.5").unwrap().into_chain(),
        Limb::eye("right_v2").unwrap().into_chain(),
        Limb::inertial_sensor("v2.6").unwrap().into_chain(),
        // The middle finger has an exactly orthonormal base (others are rounded).
        Limb::finger("left_middle").unwrap().into_chain(),
    ];
    for c in &mut out {
        c.set_constrained(true);
    }
    out
}

/// Maps unit-interval samples onto the released joints' bounds.
fn config(chain: &Chain, u: &[f64]) -> DVector<f64> {
    let (lo, hi) = chain.dof_limits();
    DVector::from_fn(lo.len(), |i, _| lo[i] + u[i] * (hi[i] - lo[i]))
}

fn perturbed(q: &DVector<f64>, i: usize, h: f64) -> Vec<f64> {
    let mut v = q.clone();
    v[i] += h;
    v.as_slice().to_vec()
}

fn wrap(a: f64) -> f64 {
    (a + std::f64::consts::PI).rem_euclid(2.0 * std::f64::consts::PI) - std::f64::consts::PI
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    #[test]
    fn geometric_jacobian_matches_finite_differences(
        which in 0usize..7,
        u in proptest::collection::vec(0.0f64..1.0, 10),
    ) {
        let chain = &chains()[which];
        let q = config(chain, &u);
        let j = chain.geo_jacobian_at(q.as_slice()).unwrap();
        for i in 0..chain.dof() {
            let hp = chain.h_at(&perturbed(&q, i, STEP)).unwrap();
            let hm = chain.h_at(&perturbed(&q, i, -STEP)).unwrap();
            let v = (pose::translation(&hp) - pose::translation(&hm)) / (2.0 * STEP);
            let w = pose::rotation_vector(&(pose::rotation(&hp) * pose::rotation(&hm).transpose()))
                / (2.0 * STEP);
            let col = j.column(i);
            let jv = Vector3::new(col[0], col[1], col[2]);
            let jw = Vector3::new(col[3], col[4], col[5]);
            prop_assert!((jv - v).amax() < TOL, "linear col {}: {} vs {}", i, jv, v);
            prop_assert!((jw - w).amax() < TOL, "angular col {}: {} vs {}", i, jw, w);
        }
        // The stateful variant agrees with the pure one.
        let mut c = chain.clone();
        c.set_ang(q.as_slice()).unwrap();
        prop_assert!((c.geo_jacobian() - &j).amax() < 1e-15);
    }

    #[test]
    fn analytical_jacobian_matches_finite_differences(
        which in 0usize..7,
        u in proptest::collection::vec(0.0f64..1.0, 10),
    ) {
        let chain = &chains()[which];
        let q = config(chain, &u);
        let h = chain.h_at(q.as_slice()).unwrap();
        // Euler angles are singular where cos(pitch) -> 0.
        prop_assume!(h[(2, 0)].abs() < 0.95);
        let j = chain.ana_jacobian_at(q.as_slice()).unwrap();
        for i in 0..chain.dof() {
            let pp = pose::pose6(&chain.h_at(&perturbed(&q, i, STEP)).unwrap());
            let pm = pose::pose6(&chain.h_at(&perturbed(&q, i, -STEP)).unwrap());
            for r in 0..6 {
                let d = if r < 3 { pp[r] - pm[r] } else { wrap(pp[r] - pm[r]) };
                let num = d / (2.0 * STEP);
                prop_assert!((j[(r, i)] - num).abs() < 1e-5,
                    "row {} col {}: {} vs {}", r, i, j[(r, i)], num);
            }
        }
    }
}

#[test]
fn link_jacobian_of_last_link_is_the_full_one() {
    let c = all_released(Limb::arm("left_v2").unwrap().chain());
    let mut c = c;
    c.set_ang(&[0.1; 10]).unwrap();
    let full = c.geo_jacobian();
    let last = c.link_geo_jacobian(9).unwrap();
    assert!((full - last).amax() < 1e-15);
    let deg = c.geo_jacobian_deg();
    assert!((deg[(0, 0)] - c.geo_jacobian()[(0, 0)] * icub_ikin::DEG2RAD).abs() < 1e-15);
}
