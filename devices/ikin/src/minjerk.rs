//! The minimum-jerk controller icub-main's Cartesian controller drives a limb with:
//! iKin's `MultiRefMinJerkCtrl` on ctrlLib's `minJerkVelCtrlForIdealPlant` filters and
//! Tustin `Integrator`, in the same discrete-time form, so that a trajectory of time `T`
//! unfolds as C++'s does (90 % of the step at `T`, over by `1.5 T`).
//!
//! Each step blends two references: the joints the solver found (`qd`, through the joint
//! filter) and the pose it reached (`xd`, through the task filter, mapped through the
//! Jacobian with weights that vanish near the joint limits), then integrates the joint
//! velocity within the limits.

use nalgebra::{DMatrix, DVector, Matrix3, Matrix6, Vector4};

use crate::chain::Chain;
use crate::error::{KinError, Result};
use crate::pose::{axis2dcm, dcm2axis, rotation};

/// ctrlLib's `Filter` with the coefficients of `F(s) = -a / (s^2 - c s - b)`, the
/// velocity command of a minimum-jerk trajectory of time `T`, discretised with Tustin at
/// `Ts` (`minJerkVelCtrlForIdealPlant`).
#[derive(Debug, Clone)]
pub struct MinJerkVelFilter {
    ts: f64,
    t: f64,
    num: [f64; 3],
    den: [f64; 3],
    /// Past inputs and outputs, newest first.
    u_old: [DVector<f64>; 2],
    y_old: [DVector<f64>; 2],
}

impl MinJerkVelFilter {
    /// A filter of `dim` channels at sample time `ts`, for `T = 1` s until told otherwise.
    pub fn new(ts: f64, dim: usize) -> Self {
        let z = DVector::zeros(dim);
        let mut f = MinJerkVelFilter {
            ts,
            t: 1.0,
            num: [0.0; 3],
            den: [1.0, 0.0, 0.0],
            u_old: [z.clone(), z.clone()],
            y_old: [z.clone(), z],
        };
        f.coefficients();
        f
    }

    fn coefficients(&mut self) {
        let (t, two_on_ts) = (self.t, 2.0 / self.ts);
        // 90 % of the steady state at t = T, transient over for t >= 1.5 T
        let a = -150.765868956161 / (t * t * t);
        let b = -84.9812819469538 / (t * t);
        let c = -15.9669610709384 / t;
        let c1 = two_on_ts * (two_on_ts - c) - b;
        let c2 = -a / c1;
        self.num = [c2, 2.0 * c2, c2];
        self.den = [
            1.0,
            -2.0 * (two_on_ts * two_on_ts + b) / c1,
            (two_on_ts * (two_on_ts + c) - b) / c1,
        ];
    }

    /// One sample of input `u` for trajectory time `t` (a new `t` changes the
    /// coefficients and keeps the state, as `Filter::adjustCoeffs`).
    pub fn filt(&mut self, t: f64, u: &DVector<f64>) -> DVector<f64> {
        if t != self.t {
            self.t = t;
            self.coefficients();
        }
        let y = (u * self.num[0] + &self.u_old[0] * self.num[1] + &self.u_old[1] * self.num[2]
            - &self.y_old[0] * self.den[1]
            - &self.y_old[1] * self.den[2])
            / self.den[0];
        self.u_old.swap(0, 1);
        self.u_old[0] = u.clone();
        self.y_old.swap(0, 1);
        self.y_old[0] = y.clone();
        y
    }

    /// Zero state (`reset(zeros)`).
    pub fn reset(&mut self) {
        for v in self.u_old.iter_mut().chain(self.y_old.iter_mut()) {
            v.fill(0.0);
        }
    }
}

/// ctrlLib's `Integrator`: Tustin, saturated to `[lo, hi]`.
#[derive(Debug, Clone)]
pub struct Integrator {
    ts: f64,
    lo: DVector<f64>,
    hi: DVector<f64>,
    y: DVector<f64>,
    x_old: DVector<f64>,
}

impl Integrator {
    pub fn new(ts: f64, y0: DVector<f64>, lo: DVector<f64>, hi: DVector<f64>) -> Self {
        let x_old = DVector::zeros(y0.len());
        Integrator {
            ts,
            lo,
            hi,
            y: y0,
            x_old,
        }
    }

    pub fn integrate(&mut self, x: &DVector<f64>) -> &DVector<f64> {
        let y = &self.y + (x + &self.x_old) * (self.ts / 2.0);
        self.y = y.zip_zip_map(&self.lo, &self.hi, |v, lo, hi| v.clamp(lo, hi));
        self.x_old = x.clone();
        &self.y
    }

    /// Restarts from `y0` with no past input.
    pub fn reset(&mut self, y0: DVector<f64>) {
        self.y = y0;
        self.x_old.fill(0.0);
    }
}

/// The part of a pose the controller tracks (iKin's `IKINCTRL_POSE_*`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CtrlPose {
    /// Position and orientation.
    Full,
    /// Position only.
    Xyz,
}

/// iKin's `MultiRefMinJerkCtrl` on a chain (its released links are the controlled ones).
#[derive(Debug, Clone)]
pub struct MinJerkController {
    chain: Chain,
    pose: CtrlPose,
    exec_time: f64,
    ts: f64,
    in_target_tol: f64,
    /// Straightness of the Cartesian path (weight of the task term).
    gamma: f64,
    guard: Guard,
    joint: MinJerkVelFilter,
    task: MinJerkVelFilter,
    integrator: Integrator,
    q: DVector<f64>,
    qdot: DVector<f64>,
    e: DVector<f64>,
    in_target: bool,
}

/// The joint-limit guards of `computeGuard` (guard ratio 0.1).
#[derive(Debug, Clone)]
struct Guard {
    width: DVector<f64>,
    min_ext: DVector<f64>,
    min_int: DVector<f64>,
    max_ext: DVector<f64>,
    max_int: DVector<f64>,
}

impl Guard {
    fn new(lo: &DVector<f64>, hi: &DVector<f64>) -> Self {
        const GUARD_RATIO: f64 = 0.1;
        let width = (hi - lo) * (0.25 * GUARD_RATIO);
        let min_ext = lo + &width;
        let min_int = &min_ext + &width;
        let max_ext = hi - &width;
        let max_int = &max_ext - &width;
        Guard {
            width,
            min_ext,
            min_int,
            max_ext,
            max_int,
        }
    }

    /// `computeWeight`: `gamma` inside, 0 past the outer guard, a tanh between.
    fn weight(&self, i: usize, q: f64, gamma: f64) -> f64 {
        if q >= self.min_int[i] && q <= self.max_int[i] {
            gamma
        } else if q <= self.min_ext[i] || q >= self.max_ext[i] {
            0.0
        } else if q < self.min_int[i] {
            let cog = 0.5 * (self.min_ext[i] + self.min_int[i]);
            0.5 * gamma * (1.0 + (10.0 * (q - cog) / self.width[i]).tanh())
        } else {
            let cog = 0.5 * (self.max_ext[i] + self.max_int[i]);
            0.5 * gamma * (1.0 + (-10.0 * (q - cog) / self.width[i]).tanh())
        }
    }
}

impl MinJerkController {
    /// A controller of `chain`'s released joints at sample time `ts` \[s\].
    pub fn new(chain: Chain, pose: CtrlPose, ts: f64) -> Result<Self> {
        if !(ts.is_finite() && ts > 0.0) {
            return Err(KinError::InvalidConfig("the sample time must be positive"));
        }
        let dim = chain.dof();
        let (lo, hi) = chain.dof_limits();
        let q = chain.ang();
        Ok(MinJerkController {
            guard: Guard::new(&lo, &hi),
            integrator: Integrator::new(ts, q.clone(), lo, hi),
            joint: MinJerkVelFilter::new(ts, dim),
            task: MinJerkVelFilter::new(ts, 6),
            chain,
            pose,
            exec_time: 1.0,
            ts,
            in_target_tol: 1e-2,
            gamma: 0.05,
            q,
            qdot: DVector::zeros(dim),
            e: DVector::zeros(6),
            in_target: false,
        })
    }

    /// The trajectory time, bounded below by ten samples as C++ bounds it; returns
    /// the time in force.
    pub fn set_exec_time(&mut self, t: f64) -> f64 {
        let lower = 10.0 * self.ts;
        self.exec_time = if t > lower { t } else { lower };
        self.exec_time
    }

    pub fn exec_time(&self) -> f64 {
        self.exec_time
    }

    pub fn set_in_target_tol(&mut self, tol: f64) {
        self.in_target_tol = tol;
    }

    pub fn in_target_tol(&self) -> f64 {
        self.in_target_tol
    }

    pub fn set_gamma(&mut self, gamma: f64) {
        self.gamma = gamma;
    }

    pub fn gamma(&self) -> f64 {
        self.gamma
    }

    pub fn set_pose(&mut self, pose: CtrlPose) {
        self.pose = pose;
    }

    /// The controller's chain (its joints are the integrated references).
    pub fn chain(&self) -> &Chain {
        &self.chain
    }

    /// The integrated joint references \[rad\].
    pub fn q(&self) -> &DVector<f64> {
        &self.q
    }

    /// The last joint velocity command \[rad/s\].
    pub fn qdot(&self) -> &DVector<f64> {
        &self.qdot
    }

    /// Whether the task error fell under the in-target tolerance.
    pub fn is_in_target(&self) -> bool {
        self.in_target
    }

    /// Restarts from joints `q0` (`restart`): filters at rest, integrator at `q0`.
    pub fn restart(&mut self, q0: &[f64]) -> Result<()> {
        self.set_q(q0)?;
        self.qdot.fill(0.0);
        self.joint.reset();
        self.task.reset();
        self.in_target = false;
        Ok(())
    }

    /// Moves the chain and the integrator to `q0` (`set_q`).
    pub fn set_q(&mut self, q0: &[f64]) -> Result<()> {
        self.q = self.chain.set_ang(q0)?;
        self.integrator.reset(self.q.clone());
        Ok(())
    }

    /// The 6-D error of the chain's pose from `xd` (`calc_e`).
    fn task_error(&self, xd: &[f64]) -> DVector<f64> {
        let h = self.chain.h();
        let mut e = DVector::zeros(6);
        e[0] = xd[0] - h[(0, 3)];
        e[1] = xd[1] - h[(1, 3)];
        e[2] = xd[2] - h[(2, 3)];
        if self.pose == CtrlPose::Full && xd.len() >= 7 {
            let des = axis2dcm(&Vector4::new(xd[3], xd[4], xd[5], xd[6]));
            let r: Matrix3<f64> = rotation(&h);
            let ax = dcm2axis(&(des * r.transpose()));
            for k in 0..3 {
                e[3 + k] = ax[3] * ax[k];
            }
        }
        e
    }

    /// One step towards the solver's pose `xd` (7 values) and joints `qd` \[rad\]
    /// (`iterate`); `xdot_set` (7: linear velocity, axis, angular speed) replaces the
    /// task filter in task-velocity mode. `compensation` is added to the joint error
    /// once. Returns the new joint references.
    pub fn iterate(
        &mut self,
        xd: &[f64],
        qd: &DVector<f64>,
        xdot_set: Option<&[f64; 7]>,
    ) -> &DVector<f64> {
        self.e = self.task_error(xd);
        let qdot_j = self.joint.filt(self.exec_time, &(qd - &self.q));
        let xdot_t = match xdot_set {
            Some(v) => DVector::from_vec(vec![
                v[0],
                v[1],
                v[2],
                v[3] * v[6],
                v[4] * v[6],
                v[5] * v[6],
            ]),
            None => self.task.filt(self.exec_time, &self.e),
        };
        let j = self.chain.geo_jacobian();
        let j = DMatrix::from_iterator(6, j.ncols(), j.iter().copied());
        let dim = self.q.len();
        let w = DMatrix::from_diagonal(&DVector::from_iterator(
            dim,
            (0..dim).map(|i| self.guard.weight(i, self.q[i], self.gamma)),
        ));
        let jt = j.transpose();
        let m: Matrix6<f64> = Matrix6::identity() + {
            let jwjt = &j * &w * &jt;
            Matrix6::from_iterator(jwjt.iter().copied())
        };
        let pinv = m
            .pseudo_inverse(1e-12)
            .unwrap_or_else(|_| Matrix6::identity());
        let pinv = DMatrix::from_iterator(6, 6, pinv.iter().copied());
        self.qdot = &qdot_j + &w * (&jt * (pinv * (xdot_t - &j * &qdot_j)));
        let q = self.integrator.integrate(&self.qdot).clone();
        // the integrator bounds q to the limits: the chain takes it as it is
        self.q = self.chain.set_ang(q.as_slice()).unwrap_or(q);
        self.in_target = self.e.norm() < self.in_target_tol;
        &self.q
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::limbs::Limb;

    #[test]
    fn the_velocity_filter_integrates_to_a_minimum_jerk_step() {
        // the joint filter's output integrated: 90 % of a step at T, all of it by 1.5 T
        let (ts, t) = (0.01, 2.0);
        let mut f = MinJerkVelFilter::new(ts, 1);
        let mut q = 0.0;
        let mut q_at_t = 0.0;
        let mut prev = 0.0;
        for k in 1..=((2.0 * t / ts) as usize) {
            let v = f.filt(t, &DVector::from_element(1, 1.0 - q))[0];
            q += (v + prev) * ts / 2.0;
            prev = v;
            if k == (t / ts) as usize {
                q_at_t = q;
            }
        }
        assert!((q_at_t - 0.9).abs() < 0.03, "{q_at_t}");
        assert!((q - 1.0).abs() < 0.01, "{q}");
    }

    #[test]
    fn the_controller_reaches_the_solver_joints_in_about_the_trajectory_time() {
        let arm = Limb::arm("left_v2").unwrap();
        let mut chain = arm.into_chain();
        let q0 = [-0.5, 0.5, 0.0, 0.8, 0.0, 0.0, 0.0];
        chain.set_ang(&q0).unwrap();
        let mut target = chain.clone();
        let qd = DVector::from_vec(vec![-0.8, 0.6, 0.3, 1.0, 0.2, -0.1, 0.1]);
        target.set_ang(qd.as_slice()).unwrap();
        let xd = target.end_eff_pose();
        let mut c = MinJerkController::new(chain, CtrlPose::Full, 0.01).unwrap();
        c.set_exec_time(1.0);
        c.restart(&q0).unwrap();
        let mut steps = 0;
        while !c.is_in_target() && steps < 500 {
            c.iterate(xd.as_slice(), &qd, None);
            steps += 1;
        }
        // in target (1 cm of task error) within the transient's 1.5 T
        assert!(steps <= 150, "{steps} steps");
        assert!((c.q() - &qd).norm() < 0.05, "{}", c.q());
    }
}
