//! The head's kinematics as `iKinGazeCtrl` uses them: the two eyes (iKin's `iCubEye`), the
//! head centre (`iCubHeadCenter`), the fixation point where the eyes' lines of sight meet,
//! the angles of a point in the head's absolute frame, and the joints that look at a point.
//!
//! Joints: torso in the chain's order (pitch, roll, yaw: the torso board's reversed below
//! version 3), head as the board orders them (neck pitch, roll, yaw, eyes tilt, version,
//! vergence), all in radians here.

use icub_ikin::{Chain, Limb, DEG2RAD};
use nalgebra::{Matrix3, Matrix4, Vector3};

/// The limits of the six head joints \[rad\].
pub type HeadLimits = [(f64, f64); 6];

/// The head's chains for a head version (`v2.5`, ...).
#[derive(Clone)]
pub struct Head {
    left: Chain,
    right: Chain,
    center: Chain,
    /// `iKinGazeCtrl`'s `eyeCAbsFrame`: the head centre with every joint at zero.
    abs_frame: Matrix4<f64>,
    /// The head IMU (`iCubInertialSensor`): 3 torso and 3 neck links.
    imu: Chain,
    /// Half the distance between the eyes \[m\].
    pub half_baseline: f64,
    /// The version's number (below 3 the torso's joints run backwards on the board).
    pub version: f64,
}

fn chain_of(limb: Limb) -> Chain {
    let mut c = limb.into_chain();
    // every joint set by us, torso included
    for i in 0..c.n() {
        let _ = c.release_link(i);
    }
    c.set_constrained(false);
    c
}

impl Head {
    pub fn new(version: &str) -> Result<Head, icub_ikin::KinError> {
        let left = Limb::eye(&format!("left_{version}"))?;
        let v = left.version();
        let left = chain_of(left);
        let right = chain_of(Limb::eye(&format!("right_{version}"))?);
        let center = chain_of(Limb::head_center(&format!("right_{version}"))?);
        let pl = left.h_at(&[0.0; 8])?;
        let pr = right.h_at(&[0.0; 8])?;
        let half_baseline =
            0.5 * (pl.fixed_view::<3, 1>(0, 3) - pr.fixed_view::<3, 1>(0, 3)).norm();
        let abs_frame = center.h_at(&[0.0; 8])?;
        // iKinGazeCtrl 2.11 builds its IMU chain from the bare version ("2.5"), which
        // iKin reads as 0.5: every head gets the v1 chain, as here
        let imu = chain_of(Limb::inertial_sensor("v1")?);
        Ok(Head {
            left,
            right,
            center,
            imu,
            abs_frame,
            half_baseline,
            version: v,
        })
    }

    /// The eight link angles of an eye (or, `pan` 0, of the head centre).
    fn links(torso: &[f64; 3], head: &[f64; 6], pan: f64) -> [f64; 8] {
        [
            torso[0], torso[1], torso[2], head[0], head[1], head[2], head[3], pan,
        ]
    }

    /// The frames of the left and right eye.
    pub fn eyes(&self, torso: &[f64; 3], head: &[f64; 6]) -> (Matrix4<f64>, Matrix4<f64>) {
        let (ver, verg) = (head[4], head[5]);
        let l = self
            .left
            .h_at(&Self::links(torso, head, ver + verg / 2.0))
            .unwrap_or_else(|_| Matrix4::identity());
        let r = self
            .right
            .h_at(&Self::links(torso, head, ver - verg / 2.0))
            .unwrap_or_else(|_| Matrix4::identity());
        (l, r)
    }

    /// The head centre's frame (its z axis: where the head looks).
    pub fn center(&self, torso: &[f64; 3], head: &[f64; 6]) -> Matrix4<f64> {
        let mut h = *head;
        h[3] = 0.0;
        self.center
            .h_at(&Self::links(torso, &h, 0.0))
            .unwrap_or_else(|_| Matrix4::identity())
    }

    /// The fixation point: the middle of the shortest segment between the two lines of
    /// sight (`computeFixationPointData`); `None` when they are parallel.
    pub fn fixation_point(&self, torso: &[f64; 3], head: &[f64; 6]) -> Option<Vector3<f64>> {
        let (l, r) = self.eyes(torso, head);
        let (p1, z1) = (
            l.fixed_view::<3, 1>(0, 3).into_owned(),
            l.fixed_view::<3, 1>(0, 2).into_owned(),
        );
        let (p2, z2) = (
            r.fixed_view::<3, 1>(0, 3).into_owned(),
            r.fixed_view::<3, 1>(0, 2).into_owned(),
        );
        let w = p1 - p2;
        let (a, b, c) = (z1.dot(&z1), z1.dot(&z2), z2.dot(&z2));
        let (d, e) = (z1.dot(&w), z2.dot(&w));
        let den = a * c - b * b;
        if den.abs() < 1e-12 {
            return None;
        }
        let t1 = (b * e - c * d) / den;
        let t2 = (a * e - b * d) / den;
        Some(((p1 + z1 * t1) + (p2 + z2 * t2)) / 2.0)
    }

    /// The head IMU's frame (as iKinGazeCtrl's `iCubInertialSensor` computes it).
    pub fn imu_frame(&self, torso: &[f64; 3], head: &[f64; 6]) -> Matrix4<f64> {
        let q = [torso[0], torso[1], torso[2], head[0], head[1], head[2]];
        self.imu.h_at(&q).unwrap_or_else(|_| Matrix4::identity())
    }

    /// How the fixation point moves with the eyes' tilt, version and vergence: its 3x3
    /// Jacobian (`computeFixationPointData`'s), by central differences.
    pub fn fixation_jacobian(&self, torso: &[f64; 3], head: &[f64; 6]) -> Option<Matrix3<f64>> {
        let eps = 1e-6;
        let mut j = Matrix3::zeros();
        for k in 0..3 {
            let (mut plus, mut minus) = (*head, *head);
            plus[3 + k] += eps;
            minus[3 + k] -= eps;
            let d = self.fixation_point(torso, &plus)? - self.fixation_point(torso, &minus)?;
            j.set_column(k, &(d / (2.0 * eps)));
        }
        Some(j)
    }

    /// The velocity of the point `x`, carried by the head, when the neck turns at
    /// `neck_vel` \[rad/s\] (the linear rows of the head centre's Jacobian with the
    /// point as its end).
    pub fn point_velocity_of_neck(
        &self,
        torso: &[f64; 3],
        head: &[f64; 6],
        x: &Vector3<f64>,
        neck_vel: &Vector3<f64>,
    ) -> Vector3<f64> {
        let j = self.neck_jacobian(torso, head);
        let w = j.fixed_view::<3, 3>(3, 0) * neck_vel;
        let h = self.center(torso, head);
        let p = h.fixed_view::<3, 1>(0, 3).into_owned();
        // a rigid point: v = v_end + w x (x - p_end)
        j.fixed_view::<3, 3>(0, 0) * neck_vel + w.cross(&(x - p))
    }

    /// The head centre's geometric Jacobian over the three neck joints (rows: linear
    /// velocity of the centre, then angular velocity).
    pub fn neck_jacobian(&self, torso: &[f64; 3], head: &[f64; 6]) -> nalgebra::Matrix6x3<f64> {
        let mut h = *head;
        h[3] = 0.0;
        let q = Self::links(torso, &h, 0.0);
        let j = self
            .center
            .geo_jacobian_at(&q)
            .unwrap_or_else(|_| nalgebra::Matrix6xX::zeros(8));
        j.fixed_view::<6, 3>(0, 3).into_owned()
    }

    /// Azimuth, elevation and vergence of `x` in the absolute head frame \[rad\]
    /// (`getAbsAngles`: right and up positive).
    pub fn abs_angles(&self, x: &Vector3<f64>) -> [f64; 3] {
        let inv = self
            .abs_frame
            .try_inverse()
            .unwrap_or_else(Matrix4::identity);
        let f = inv * x.push(1.0);
        let azi = f[0].atan2(f[2]);
        let ele = -f[1].atan2(f[2].abs());
        let ver = 2.0 * self.half_baseline.atan2(f.xyz().norm());
        [azi, ele, ver]
    }

    /// The point at absolute angles `[azi, ele, ver]` \[rad\] (`get3DPoint` "abs").
    pub fn point_from_abs_angles(&self, ang: &[f64; 3]) -> Option<Vector3<f64>> {
        let head = [0.0, 0.0, 0.0, 0.0, 0.0, ang[2].max(1e-3)];
        let fp = self.fixation_point(&[0.0; 3], &head)?;
        let r: Matrix3<f64> =
            icub_ikin::pose::axis2dcm(&nalgebra::Vector4::new(0.0, 1.0, 0.0, ang[0]))
                * icub_ikin::pose::axis2dcm(&nalgebra::Vector4::new(1.0, 0.0, 0.0, ang[1]));
        let mut rot = Matrix4::identity();
        rot.fixed_view_mut::<3, 3>(0, 0).copy_from(&r);
        let frame = self.abs_frame;
        let inv = frame.try_inverse()?;
        let x = frame * rot * inv * fp.push(1.0);
        Some(x.xyz())
    }

    /// Neck joints (pitch, roll, yaw) whose head centre looks at `x`, from `neck0`,
    /// within `limits` (roll held where it is: the rest posture).
    pub fn solve_neck(
        &self,
        torso: &[f64; 3],
        neck0: [f64; 3],
        x: &Vector3<f64>,
        limits: &HeadLimits,
    ) -> [f64; 3] {
        // the target's direction in the head-centre frame: x and y to zero
        let err = |n: &[f64; 3]| -> nalgebra::Vector2<f64> {
            let h = self.center(torso, &[n[0], n[1], n[2], 0.0, 0.0, 0.0]);
            let inv = h.try_inverse().unwrap_or_else(Matrix4::identity);
            let d = (inv * x.push(1.0)).xyz();
            let d = d / d.norm().max(1e-9);
            nalgebra::Vector2::new(d[0], d[1])
        };
        let mut n = neck0;
        for _ in 0..30 {
            let e = err(&n);
            if e.norm() < 1e-9 {
                break;
            }
            let eps = 1e-6;
            let mut j = nalgebra::Matrix2::zeros();
            for (col, k) in [(0, 0), (1, 2)] {
                let mut m = n;
                m[k] += eps;
                let d = (err(&m) - e) / eps;
                j.set_column(col, &d);
            }
            let Some(step) = j.try_inverse().map(|ji| -(ji * e)) else {
                break;
            };
            n[0] = (n[0] + step[0].clamp(-0.3, 0.3)).clamp(limits[0].0, limits[0].1);
            n[2] = (n[2] + step[1].clamp(-0.3, 0.3)).clamp(limits[2].0, limits[2].1);
        }
        n
    }

    /// Eye joints (tilt, version, vergence) that fixate `x` with the neck at `neck`,
    /// within `limits` (vergence at least `min_vergence`).
    pub fn solve_eyes(
        &self,
        torso: &[f64; 3],
        neck: [f64; 3],
        x: &Vector3<f64>,
        limits: &HeadLimits,
        min_vergence: f64,
    ) -> [f64; 3] {
        // a first guess from the head centre (the saccade's geometry), then Newton
        let h = self.center(torso, &[neck[0], neck[1], neck[2], 0.0, 0.0, 0.0]);
        let f = (h.try_inverse().unwrap_or_else(Matrix4::identity) * x.push(1.0)).xyz();
        let mut e = [
            -f[1].atan2(f[2].abs()),
            f[0].atan2(f[2]),
            2.0 * self.half_baseline.atan2(f.norm()),
        ];
        let clamp = |e: &mut [f64; 3]| {
            e[0] = e[0].clamp(limits[3].0, limits[3].1);
            e[1] = e[1].clamp(limits[4].0, limits[4].1);
            e[2] = e[2].clamp(min_vergence.max(limits[5].0), limits[5].1);
        };
        clamp(&mut e);
        let fix = |e: &[f64; 3]| {
            self.fixation_point(torso, &[neck[0], neck[1], neck[2], e[0], e[1], e[2]])
        };
        for _ in 0..30 {
            let Some(p) = fix(&e) else { break };
            let r = p - x;
            if r.norm() < 1e-6 {
                break;
            }
            let eps = 1e-6;
            let mut j = Matrix3::zeros();
            for k in 0..3 {
                let mut m = e;
                m[k] += eps;
                let Some(pm) = fix(&m) else { return e };
                j.set_column(k, &((pm - p) / eps));
            }
            let Some(ji) = j.try_inverse() else { break };
            let step = -(ji * r);
            for k in 0..3 {
                e[k] += step[k].clamp(-0.2, 0.2);
            }
            clamp(&mut e);
        }
        e
    }
}

/// A camera's intrinsics (`[CAMERA_CALIBRATION_LEFT]` of `icubEyes.ini`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Camera {
    pub w: i32,
    pub h: i32,
    pub fx: f64,
    pub fy: f64,
    pub cx: f64,
    pub cy: f64,
}

impl Camera {
    /// From a calibration group; `None` unless all six keys are there (as C++).
    pub fn from_group(g: &yarp_proto::Bottle) -> Option<Camera> {
        let n = |k: &str| g.find(k).and_then(yarp_proto::Value::as_f64);
        Some(Camera {
            w: n("w")? as i32,
            h: n("h")? as i32,
            fx: n("fx")?,
            fy: n("fy")?,
            cx: n("cx")?,
            cy: n("cy")?,
        })
    }

    /// The 3x4 projection, row-major (`Prj`).
    pub fn projection(&self) -> [f64; 12] {
        [
            self.fx, 0.0, self.cx, 0.0, 0.0, self.fy, self.cy, 0.0, 0.0, 0.0, 1.0, 0.0,
        ]
    }
}

impl Head {
    /// Pixel `(u, v)` of point `x` in an eye's camera (`projectPoint`).
    pub fn project(&self, eye: &Matrix4<f64>, cam: &Camera, x: &Vector3<f64>) -> Option<[f64; 2]> {
        let p = eye.try_inverse()? * x.push(1.0);
        (p[2].abs() > 1e-9).then(|| [cam.fx * p[0] / p[2] + cam.cx, cam.fy * p[1] / p[2] + cam.cy])
    }

    /// The point at depth `z` along pixel `(u, v)` of an eye's camera (`projectPoint`).
    pub fn unproject(
        &self,
        eye: &Matrix4<f64>,
        cam: &Camera,
        u: f64,
        v: f64,
        z: f64,
    ) -> Vector3<f64> {
        let p =
            nalgebra::Vector4::new((u - cam.cx) * z / cam.fx, (v - cam.cy) * z / cam.fy, z, 1.0);
        (eye * p).xyz()
    }

    /// The point seen at pixel `l` of the left camera and `r` of the right one, by linear
    /// triangulation (`triangulatePoint`).
    pub fn triangulate(
        &self,
        eyes: (&Matrix4<f64>, &Matrix4<f64>),
        cams: (&Camera, &Camera),
        l: [f64; 2],
        r: [f64; 2],
    ) -> Option<Vector3<f64>> {
        let mut a = nalgebra::Matrix4x3::zeros();
        let mut b = nalgebra::Vector4::zeros();
        for (k, (h, cam, px)) in [(eyes.0, cams.0, l), (eyes.1, cams.1, r)]
            .into_iter()
            .enumerate()
        {
            let prj = nalgebra::Matrix3x4::from_row_slice(&cam.projection());
            let p = prj * h.try_inverse()?;
            for (row, coord) in [(0, px[0]), (1, px[1])] {
                let line = p.row(row) - p.row(2) * coord;
                a.set_row(2 * k + row, &line.fixed_columns::<3>(0));
                b[2 * k + row] = -line[3];
            }
        }
        let x = a.pseudo_inverse(1e-12).ok()? * b;
        Some(x)
    }

    /// The distance at which the eyes verge by `ver` \[rad\] (`getDistFromVergence`).
    pub fn dist_from_vergence(&self, ver: f64) -> f64 {
        let t = (ver / 2.0).tan();
        self.half_baseline * (1.0 + 1.0 / (t * t)).sqrt()
    }
}

/// Degrees of an array of radians.
pub fn deg<const N: usize>(v: [f64; N]) -> [f64; N] {
    v.map(|x| x / DEG2RAD)
}
