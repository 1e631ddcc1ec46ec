//! One revolute link described by standard Denavit-Hartenberg parameters.

use nalgebra::Matrix4;

/// Degrees to radians, as iKin's `CTRL_DEG2RAD`.
pub const DEG2RAD: f64 = std::f64::consts::PI / 180.0;
/// Radians to degrees, as iKin's `CTRL_RAD2DEG`.
pub const RAD2DEG: f64 = 180.0 / std::f64::consts::PI;

/// A link with standard DH parameters, as iKin's `iKinLink`.
///
/// The homogeneous transform from frame `i-1` to frame `i` is
/// `Rz(θ) · Tz(d) · Tx(a) · Rx(α)` with `θ = q + offset`, exactly the matrix
/// `iKinLink::getH` fills in. Lengths are in metres, angles in radians.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Link {
    /// Link length `a` \[m\].
    pub a: f64,
    /// Link offset `d` \[m\].
    pub d: f64,
    /// Link twist `α` \[rad\].
    pub alpha: f64,
    /// Joint angle offset added to the joint value \[rad\].
    pub offset: f64,
    /// Lower joint bound \[rad\].
    pub min: f64,
    /// Upper joint bound \[rad\].
    pub max: f64,
}

impl Link {
    /// A link from DH parameters in SI units (radians), in iKin's argument order.
    pub const fn new(a: f64, d: f64, alpha: f64, offset: f64, min: f64, max: f64) -> Self {
        Self {
            a,
            d,
            alpha,
            offset,
            min,
            max,
        }
    }

    /// A link whose angles (`alpha`, `offset`, `min`, `max`) are in degrees,
    /// as in iKin's link property files.
    pub fn from_deg(a: f64, d: f64, alpha: f64, offset: f64, min: f64, max: f64) -> Self {
        Self::new(
            a,
            d,
            alpha * DEG2RAD,
            offset * DEG2RAD,
            min * DEG2RAD,
            max * DEG2RAD,
        )
    }

    /// `q` clamped into `[min, max]`.
    pub fn clamp(&self, q: f64) -> f64 {
        q.max(self.min).min(self.max)
    }

    /// Transform from the previous frame to this link's frame at joint value `q`.
    pub fn h(&self, q: f64) -> Matrix4<f64> {
        let (st, ct) = (q + self.offset).sin_cos();
        let (sa, ca) = self.alpha.sin_cos();
        Matrix4::new(
            ct,
            -st * ca,
            st * sa,
            ct * self.a,
            st,
            ct * ca,
            -ct * sa,
            st * self.a,
            0.0,
            sa,
            ca,
            self.d,
            0.0,
            0.0,
            0.0,
            1.0,
        )
    }

    /// Derivative of [`Link::h`] with respect to `q` (iKin's `getDnH(1)`).
    pub fn dh(&self, q: f64) -> Matrix4<f64> {
        let (st, ct) = (q + self.offset).sin_cos();
        let (sa, ca) = self.alpha.sin_cos();
        Matrix4::new(
            -st,
            -ct * ca,
            ct * sa,
            -st * self.a,
            ct,
            -st * ca,
            st * sa,
            ct * self.a,
            0.0,
            0.0,
            0.0,
            0.0,
            0.0,
            0.0,
            0.0,
            0.0,
        )
    }
}
