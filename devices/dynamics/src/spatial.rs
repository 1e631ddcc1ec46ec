//! Spatial (6D) algebra in iDynTree's conventions.
//!
//! A twist is `[v; ω]` (the velocity of a frame's origin, then the angular
//! velocity), a wrench `[f; τ]` (force, then torque about the frame's origin),
//! both expressed in one frame. Transforms are [`Iso`]: `a_H_b` maps
//! coordinates in `b` to coordinates in `a`.

use nalgebra::{Isometry3, Matrix3, Matrix6, Vector3, Vector6};

/// A rigid transform `a_H_b`.
pub type Iso = Isometry3<f64>;
/// A twist or spatial acceleration `[linear; angular]`.
pub type Motion = Vector6<f64>;
/// A wrench `[force; torque]`.
pub type Wrench = Vector6<f64>;

/// Linear part of a 6-vector.
pub fn lin(v: &Vector6<f64>) -> Vector3<f64> {
    v.fixed_rows::<3>(0).into_owned()
}

/// Angular part of a 6-vector.
pub fn ang(v: &Vector6<f64>) -> Vector3<f64> {
    v.fixed_rows::<3>(3).into_owned()
}

/// `[a; b]`.
pub fn six(a: Vector3<f64>, b: Vector3<f64>) -> Vector6<f64> {
    Vector6::new(a.x, a.y, a.z, b.x, b.y, b.z)
}

/// The skew-symmetric matrix of `v`: `skew(v) w = v × w`.
pub fn skew(v: &Vector3<f64>) -> Matrix3<f64> {
    Matrix3::new(0.0, -v.z, v.y, v.z, 0.0, -v.x, -v.y, v.x, 0.0)
}

/// A twist expressed in `b`, re-expressed in `a` (`a_H_b`).
pub fn motion_to(a_h_b: &Iso, m: &Motion) -> Motion {
    let r = a_h_b.rotation;
    let p = a_h_b.translation.vector;
    let w = r * ang(m);
    six(r * lin(m) + p.cross(&w), w)
}

/// A wrench expressed in `b`, re-expressed in `a` (`a_H_b`).
pub fn wrench_to(a_h_b: &Iso, f: &Wrench) -> Wrench {
    let r = a_h_b.rotation;
    let p = a_h_b.translation.vector;
    let force = r * lin(f);
    six(force, r * ang(f) + p.cross(&force))
}

/// The 6×6 matrix of [`wrench_to`] (`a_X*_b`).
pub fn wrench_matrix(a_h_b: &Iso) -> Matrix6<f64> {
    let r = a_h_b.rotation.to_rotation_matrix().into_inner();
    let p = skew(&a_h_b.translation.vector);
    let mut x = Matrix6::zeros();
    x.fixed_view_mut::<3, 3>(0, 0).copy_from(&r);
    x.fixed_view_mut::<3, 3>(3, 3).copy_from(&r);
    x.fixed_view_mut::<3, 3>(3, 0).copy_from(&(p * r));
    x
}

/// Spatial cross product of motions, `a × b`.
pub fn cross_motion(a: &Motion, b: &Motion) -> Motion {
    let (v, w) = (lin(a), ang(a));
    six(w.cross(&lin(b)) + v.cross(&ang(b)), w.cross(&ang(b)))
}

/// Spatial cross product of a motion and a wrench, `a ×* f`.
pub fn cross_force(a: &Motion, f: &Wrench) -> Wrench {
    let (v, w) = (lin(a), ang(a));
    six(w.cross(&lin(f)), w.cross(&ang(f)) + v.cross(&lin(f)))
}

/// A rigid body's inertia: mass, centre of mass and rotational inertia about
/// the centre of mass, all in the body's frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Inertia {
    pub mass: f64,
    pub com: Vector3<f64>,
    /// About the centre of mass, axes of the body's frame.
    pub rot_com: Matrix3<f64>,
}

impl Inertia {
    pub const ZERO: Inertia = Inertia {
        mass: 0.0,
        com: Vector3::new(0.0, 0.0, 0.0),
        rot_com: Matrix3::new(0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0),
    };

    /// The 6×6 spatial inertia about the frame's origin (`[f; τ] = M [a; α]`).
    pub fn matrix(&self) -> Matrix6<f64> {
        let m = self.mass;
        let c = skew(&self.com);
        let mut i = Matrix6::zeros();
        i.fixed_view_mut::<3, 3>(0, 0)
            .copy_from(&(Matrix3::identity() * m));
        i.fixed_view_mut::<3, 3>(0, 3).copy_from(&(-m * c));
        i.fixed_view_mut::<3, 3>(3, 0).copy_from(&(m * c));
        i.fixed_view_mut::<3, 3>(3, 3)
            .copy_from(&(self.rot_com - m * c * c));
        i
    }

    /// The same body seen from frame `a` (`a_H_b`, `self` in `b`).
    pub fn transformed(&self, a_h_b: &Iso) -> Inertia {
        let r = a_h_b.rotation.to_rotation_matrix().into_inner();
        Inertia {
            mass: self.mass,
            com: (a_h_b * nalgebra::Point3::from(self.com)).coords,
            rot_com: r * self.rot_com * r.transpose(),
        }
    }

    /// Two bodies rigidly joined, both expressed in the same frame.
    pub fn combined(&self, other: &Inertia) -> Inertia {
        let m = self.mass + other.mass;
        if m <= 0.0 {
            return Inertia::ZERO;
        }
        let com = (self.com * self.mass + other.com * other.mass) / m;
        let shift = |i: &Inertia| {
            let d = skew(&(i.com - com));
            i.rot_com - i.mass * d * d
        };
        Inertia {
            mass: m,
            com,
            rot_com: shift(self) + shift(other),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Translation3, UnitQuaternion};

    fn pose() -> Iso {
        Iso::from_parts(
            Translation3::new(0.3, -0.2, 0.5),
            UnitQuaternion::from_euler_angles(0.4, -0.7, 1.1),
        )
    }

    #[test]
    fn power_is_frame_independent() {
        let h = pose();
        let m = Motion::new(1.0, 2.0, 3.0, -0.5, 0.2, 0.9);
        let f = Wrench::new(-3.0, 0.5, 2.0, 0.1, -0.4, 0.7);
        assert!((m.dot(&f) - motion_to(&h, &m).dot(&wrench_to(&h, &f))).abs() < 1e-12);
        assert!((wrench_matrix(&h) * f - wrench_to(&h, &f)).norm() < 1e-12);
    }

    #[test]
    fn inertia_matrix_transforms_as_a_tensor() {
        let i = Inertia {
            mass: 2.0,
            com: Vector3::new(0.1, 0.0, -0.2),
            rot_com: Matrix3::from_diagonal(&Vector3::new(0.01, 0.02, 0.03)),
        };
        let h = pose();
        let m = Motion::new(0.3, 1.0, -2.0, 0.5, 0.1, -0.3);
        // Momentum computed in b then moved to a equals momentum computed in a.
        let in_b = wrench_to(&h, &(i.matrix() * m));
        let in_a = i.transformed(&h).matrix() * motion_to(&h, &m);
        assert!((in_a - in_b).norm() < 1e-12);
    }
}
