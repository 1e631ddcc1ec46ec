//! Helpers shared by the integration tests.
#![allow(dead_code)]

use icub_ikin::nalgebra::{DVector, Matrix4};
use icub_ikin::{Chain, Limb};

/// Every limb/type pair the crate knows.
pub fn all_limbs() -> Vec<Limb> {
    use icub_ikin::LimbKind::*;
    let mut out = Vec::new();
    for kind in [
        Arm,
        Leg,
        Eye,
        EyeNeckRef,
        HeadCenter,
        InertialSensor,
        Torso,
        Finger,
    ] {
        for t in Limb::known_types(kind) {
            out.push(Limb::new(kind, &t).unwrap());
        }
    }
    out
}

/// A chain with every link released and no clamping, to evaluate any
/// configuration of all links.
pub fn all_released(chain: &Chain) -> Chain {
    let mut c = chain.clone();
    c.set_constrained(false);
    for i in 0..c.n() {
        c.release_link(i).unwrap();
    }
    c
}

/// Deterministic uniform generator for test configurations.
pub struct Rng(pub u64);

impl Rng {
    pub fn next_f64(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Released joints of `chain` drawn uniformly within bounds.
    pub fn config(&mut self, chain: &Chain) -> DVector<f64> {
        let (lo, hi) = chain.dof_limits();
        DVector::from_fn(lo.len(), |i, _| lo[i] + self.next_f64() * (hi[i] - lo[i]))
    }
}

pub fn translation(h: &Matrix4<f64>) -> [f64; 3] {
    [h[(0, 3)], h[(1, 3)], h[(2, 3)]]
}
