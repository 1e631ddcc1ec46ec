//! Pose representations used by iKin: the 7-vector `x y z ax ay az θ`
//! (position plus axis-angle, yarp's `dcm2axis`) and the XYZ Euler angles of
//! `iKinChain::RotAng`, with their conversions.

use nalgebra::{Matrix3, Matrix4, SVector, Vector3, Vector4, Vector6};

/// A 7-vector, the shape of iKin's axis-angle pose.
pub type Vector7<T> = SVector<T, 7>;

/// Rotation part of a homogeneous transform.
pub fn rotation(h: &Matrix4<f64>) -> Matrix3<f64> {
    h.fixed_view::<3, 3>(0, 0).into_owned()
}

/// Translation part of a homogeneous transform.
pub fn translation(h: &Matrix4<f64>) -> Vector3<f64> {
    h.fixed_view::<3, 1>(0, 3).into_owned()
}

/// Axis-angle `(ax, ay, az, θ)` of a rotation matrix, as yarp's `dcm2axis`:
/// unit axis and `θ ∈ [0, π]`. The identity gives axis `z` and `θ = 0`.
pub fn dcm2axis(r: &Matrix3<f64>) -> Vector4<f64> {
    let v = Vector3::new(
        r[(2, 1)] - r[(1, 2)],
        r[(0, 2)] - r[(2, 0)],
        r[(1, 0)] - r[(0, 1)],
    );
    let n = v.norm();
    let theta = (0.5 * n).atan2(0.5 * (r.trace() - 1.0));
    if n > 1e-9 {
        let a = v / n;
        return Vector4::new(a.x, a.y, a.z, theta);
    }
    // Symmetric R: the angle is 0 or π. For π, R = 2aaᵀ - I, so any non-zero
    // column of R + I is parallel to the axis.
    if theta.abs() < 1e-6 {
        return Vector4::new(0.0, 0.0, 1.0, 0.0);
    }
    let m = r + Matrix3::identity();
    let col = (0..3)
        .map(|c| m.column(c).into_owned())
        .max_by(|x, y| x.norm().total_cmp(&y.norm()))
        .unwrap_or_else(Vector3::z);
    let a = col.normalize();
    Vector4::new(a.x, a.y, a.z, theta)
}

/// Rotation matrix of an axis-angle `(ax, ay, az, θ)` (yarp's `axis2dcm`, the
/// rotation block only). The axis need not be normalised; a zero axis gives the identity.
pub fn axis2dcm(v: &Vector4<f64>) -> Matrix3<f64> {
    let axis = Vector3::new(v.x, v.y, v.z);
    let n = axis.norm();
    if n < 1e-12 {
        return Matrix3::identity();
    }
    let k = axis / n;
    let (s, c) = v.w.sin_cos();
    let kx = k.cross_matrix();
    Matrix3::identity() + kx * s + kx * kx * (1.0 - c)
}

/// Rotation vector `θ·axis` of a rotation matrix (the SO(3) logarithm).
pub fn rotation_vector(r: &Matrix3<f64>) -> Vector3<f64> {
    let aa = dcm2axis(r);
    Vector3::new(aa.x, aa.y, aa.z) * aa.w
}

/// iKin's 7-vector pose `x y z ax ay az θ` of a homogeneous transform.
pub fn pose7(h: &Matrix4<f64>) -> Vector7<f64> {
    let aa = dcm2axis(&rotation(h));
    Vector7::from_column_slice(&[h[(0, 3)], h[(1, 3)], h[(2, 3)], aa.x, aa.y, aa.z, aa.w])
}

/// Homogeneous transform of an iKin 7-vector pose.
pub fn h_from_pose7(p: &Vector7<f64>) -> Matrix4<f64> {
    let r = axis2dcm(&Vector4::new(p[3], p[4], p[5], p[6]));
    let mut h = Matrix4::identity();
    h.fixed_view_mut::<3, 3>(0, 0).copy_from(&r);
    h[(0, 3)] = p[0];
    h[(1, 3)] = p[1];
    h[(2, 3)] = p[2];
    h
}

/// iKin's 6-vector pose `x y z` plus XYZ Euler angles ([`rot_ang`]).
pub fn pose6(h: &Matrix4<f64>) -> Vector6<f64> {
    let e = rot_ang(&rotation(h));
    Vector6::new(h[(0, 3)], h[(1, 3)], h[(2, 3)], e.x, e.y, e.z)
}

/// XYZ Euler angles of a rotation matrix, as `iKinChain::RotAng`.
pub fn rot_ang(r: &Matrix3<f64>) -> Vector3<f64> {
    Vector3::new(
        (-r[(2, 1)]).atan2(r[(2, 2)]),
        r[(2, 0)].clamp(-1.0, 1.0).asin(),
        (-r[(1, 0)]).atan2(r[(0, 0)]),
    )
}

/// Time derivative of [`rot_ang`] given `dR`, as `iKinChain::dRotAng`.
pub fn d_rot_ang(r: &Matrix3<f64>, dr: &Matrix3<f64>) -> Vector3<f64> {
    Vector3::new(
        (r[(2, 1)] * dr[(2, 2)] - r[(2, 2)] * dr[(2, 1)])
            / (r[(2, 1)] * r[(2, 1)] + r[(2, 2)] * r[(2, 2)]),
        dr[(2, 0)] / (1.0 - r[(2, 0)] * r[(2, 0)]).abs().sqrt(),
        (r[(1, 0)] * dr[(0, 0)] - r[(0, 0)] * dr[(1, 0)])
            / (r[(1, 0)] * r[(1, 0)] + r[(0, 0)] * r[(0, 0)]),
    )
}
