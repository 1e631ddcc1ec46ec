//! Inverse kinematics: damped least squares (Levenberg-Marquardt) on the
//! geometric Jacobian, with joint bounds enforced by projection and an
//! active set, and random restarts when a descent stalls.
//!
//! iKin solves the same problem with IPOPT; this solver needs no external
//! library and reaches the targets iKin's solver is used for (the 7-DOF arm,
//! or 10 DOF with the torso released) to sub-millimetre accuracy.

use nalgebra::{DMatrix, DVector, Matrix4, Vector3};

use crate::chain::Chain;
use crate::error::{KinError, Result};
use crate::pose::{self, Vector7};

/// What part of the target pose the solver matches.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum IkMode {
    /// Position only (3 constraints), as iKin's `xyz` control mode.
    Position,
    /// Position and orientation (6 constraints), as iKin's `full` pose mode.
    Pose,
}

/// Solver settings.
#[derive(Debug, Clone, PartialEq)]
pub struct IkConfig {
    /// Constraints to satisfy.
    pub mode: IkMode,
    /// Position tolerance \[m\].
    pub tol_pos: f64,
    /// Orientation tolerance \[rad\] (ignored in [`IkMode::Position`]).
    pub tol_rot: f64,
    /// Iteration budget for one descent.
    pub max_iter: usize,
    /// Descents restarted from random joint values when one stalls.
    pub max_restarts: usize,
    /// Metres that one radian of orientation error weighs in the cost.
    pub rot_weight: f64,
    /// Largest joint step of one iteration \[rad\] (keeps steps in the linear regime).
    pub max_step: f64,
    /// Seed of the restart generator (the solver is deterministic).
    pub seed: u64,
}

impl Default for IkConfig {
    fn default() -> Self {
        Self {
            mode: IkMode::Pose,
            tol_pos: 1e-4,
            tol_rot: 1e-3,
            max_iter: 200,
            max_restarts: 20,
            rot_weight: 0.2,
            max_step: 0.5,
            seed: 0x1cb_1c0b,
        }
    }
}

impl IkConfig {
    /// Default settings in position-only mode.
    pub fn position() -> Self {
        Self {
            mode: IkMode::Position,
            ..Self::default()
        }
    }

    fn validate(&self) -> Result<()> {
        let pos = |v: f64| v.is_finite() && v > 0.0;
        if !pos(self.tol_pos) || !pos(self.tol_rot) {
            return Err(KinError::InvalidConfig("tolerances must be positive"));
        }
        if !pos(self.rot_weight) || !pos(self.max_step) {
            return Err(KinError::InvalidConfig(
                "rot_weight and max_step must be positive",
            ));
        }
        if self.max_iter == 0 {
            return Err(KinError::InvalidConfig("max_iter must be at least 1"));
        }
        Ok(())
    }
}

/// Outcome of a solve: always the best configuration found, with its error.
#[derive(Debug, Clone, PartialEq)]
pub struct IkSolution {
    /// Released joint values \[rad\], within bounds.
    pub q: DVector<f64>,
    /// End-effector transform reached.
    pub h: Matrix4<f64>,
    /// Distance between reached and target position \[m\].
    pub pos_error: f64,
    /// Angle between reached and target orientation \[rad\].
    pub rot_error: f64,
    /// Iterations spent, all descents included.
    pub iterations: usize,
    /// Descents restarted.
    pub restarts: usize,
    /// Whether the tolerances were met.
    pub converged: bool,
}

/// Damped-least-squares IK solver for a [`Chain`].
#[derive(Debug, Clone, PartialEq, Default)]
pub struct IkSolver {
    config: IkConfig,
}

/// Damping bounds of the Levenberg-Marquardt loop.
const LAMBDA_INIT: f64 = 1e-2;
const LAMBDA_MIN: f64 = 1e-6;
const LAMBDA_MAX: f64 = 1e3;

struct Eval {
    h: Matrix4<f64>,
    e: DVector<f64>,
    pos_err: f64,
    rot_err: f64,
    cost: f64,
}

impl IkSolver {
    /// A solver with `config` (validated).
    pub fn new(config: IkConfig) -> Result<Self> {
        config.validate()?;
        Ok(Self { config })
    }

    /// The settings in use.
    pub fn config(&self) -> &IkConfig {
        &self.config
    }

    /// Solves for the released joints of `chain` reaching `target` (root
    /// frame), starting from `q0` or the chain's current angles. The chain is
    /// not modified: apply `solution.q` with [`Chain::set_ang`].
    pub fn solve(
        &self,
        chain: &Chain,
        target: &Matrix4<f64>,
        q0: Option<&[f64]>,
    ) -> Result<IkSolution> {
        if chain.dof() == 0 {
            return Err(KinError::NoDof);
        }
        if !target.iter().all(|v| v.is_finite()) {
            return Err(KinError::NonFinite("IK target"));
        }
        let (lo, hi) = chain.dof_limits();
        let start = match q0 {
            Some(q) => {
                // Validate through the chain (length and finiteness).
                chain.h_at(q)?;
                DVector::from_column_slice(q)
            }
            None => chain.ang(),
        };
        let mut rng = XorShift(self.config.seed | 1);
        let mut best: Option<IkSolution> = None;
        let mut iterations = 0;
        let mut restarts = 0;
        for attempt in 0..=self.config.max_restarts {
            restarts = attempt;
            let seed = if attempt == 0 {
                clamp(&start, &lo, &hi)
            } else {
                DVector::from_fn(lo.len(), |i, _| lo[i] + rng.next_f64() * (hi[i] - lo[i]))
            };
            let (sol, iters) = self.descend(chain, target, seed, &lo, &hi)?;
            iterations += iters;
            let better = match &best {
                None => true,
                Some(b) => {
                    self.weighted(sol.pos_error, sol.rot_error)
                        < self.weighted(b.pos_error, b.rot_error)
                }
            };
            if better {
                best = Some(sol);
            }
            if best.as_ref().is_some_and(|b| b.converged) {
                break;
            }
        }
        let mut best = best.ok_or(KinError::NoDof)?;
        best.iterations = iterations;
        best.restarts = restarts;
        Ok(best)
    }

    /// Position-only convenience: solves for `xyz` whatever the configured mode.
    pub fn solve_position(
        &self,
        chain: &Chain,
        xyz: &Vector3<f64>,
        q0: Option<&[f64]>,
    ) -> Result<IkSolution> {
        let mut target = Matrix4::identity();
        target.fixed_view_mut::<3, 1>(0, 3).copy_from(xyz);
        let solver = IkSolver {
            config: IkConfig {
                mode: IkMode::Position,
                ..self.config.clone()
            },
        };
        solver.solve(chain, &target, q0)
    }

    /// Solves for an iKin 7-vector pose `x y z ax ay az θ`.
    pub fn solve_pose7(
        &self,
        chain: &Chain,
        pose7: &Vector7<f64>,
        q0: Option<&[f64]>,
    ) -> Result<IkSolution> {
        if !pose7.iter().all(|v| v.is_finite()) {
            return Err(KinError::NonFinite("IK target"));
        }
        self.solve(chain, &pose::h_from_pose7(pose7), q0)
    }

    fn weighted(&self, pos: f64, rot: f64) -> f64 {
        match self.config.mode {
            IkMode::Position => pos,
            IkMode::Pose => pos + self.config.rot_weight * rot,
        }
    }

    fn evaluate(&self, chain: &Chain, target: &Matrix4<f64>, q: &DVector<f64>) -> Result<Eval> {
        let h = chain.h_at(q.as_slice())?;
        let dp = pose::translation(target) - pose::translation(&h);
        // Orientation error as the rotation vector of R_d · Rᵀ (root frame),
        // which matches the angular rows of the geometric Jacobian.
        let dr = pose::rotation_vector(&(pose::rotation(target) * pose::rotation(&h).transpose()));
        let e = match self.config.mode {
            IkMode::Position => DVector::from_column_slice(dp.as_slice()),
            IkMode::Pose => {
                let w = self.config.rot_weight;
                DVector::from_column_slice(&[dp.x, dp.y, dp.z, w * dr.x, w * dr.y, w * dr.z])
            }
        };
        let cost = e.norm_squared();
        Ok(Eval {
            h,
            e,
            pos_err: dp.norm(),
            rot_err: dr.norm(),
            cost,
        })
    }

    fn converged(&self, ev: &Eval) -> bool {
        ev.pos_err < self.config.tol_pos
            && (self.config.mode == IkMode::Position || ev.rot_err < self.config.tol_rot)
    }

    fn jacobian(&self, chain: &Chain, q: &DVector<f64>) -> Result<DMatrix<f64>> {
        let j = chain.geo_jacobian_at(q.as_slice())?;
        let mut m = DMatrix::from_column_slice(6, j.ncols(), j.as_slice());
        Ok(match self.config.mode {
            IkMode::Position => m.rows(0, 3).into_owned(),
            IkMode::Pose => {
                m.rows_mut(3, 3).scale_mut(self.config.rot_weight);
                m
            }
        })
    }

    /// One Levenberg-Marquardt descent from `q`; returns the end point and iterations.
    fn descend(
        &self,
        chain: &Chain,
        target: &Matrix4<f64>,
        mut q: DVector<f64>,
        lo: &DVector<f64>,
        hi: &DVector<f64>,
    ) -> Result<(IkSolution, usize)> {
        let mut ev = self.evaluate(chain, target, &q)?;
        let mut lambda = LAMBDA_INIT;
        let mut iters = 0;
        while iters < self.config.max_iter && !self.converged(&ev) {
            iters += 1;
            let mut j = self.jacobian(chain, &q)?;
            // Active set: a joint on a bound whose descent direction points
            // outwards cannot move, so it must not take part in the step.
            let grad = j.transpose() * &ev.e;
            for i in 0..q.len() {
                let at_lo = q[i] <= lo[i] + 1e-9 && grad[i] < 0.0;
                let at_hi = q[i] >= hi[i] - 1e-9 && grad[i] > 0.0;
                if at_lo || at_hi {
                    j.column_mut(i).fill(0.0);
                }
            }
            let m = j.nrows();
            let jjt = &j * j.transpose() + DMatrix::identity(m, m) * (lambda * lambda);
            let Some(chol) = jjt.cholesky() else {
                lambda *= 10.0;
                continue;
            };
            let mut dq = j.transpose() * chol.solve(&ev.e);
            let step = dq.amax();
            if step > self.config.max_step {
                dq *= self.config.max_step / step;
            }
            let q_new = clamp(&(&q + dq), lo, hi);
            let ev_new = self.evaluate(chain, target, &q_new)?;
            if ev_new.cost < ev.cost {
                q = q_new;
                ev = ev_new;
                lambda = (lambda * 0.3).max(LAMBDA_MIN);
            } else {
                lambda *= 5.0;
                if lambda > LAMBDA_MAX {
                    break; // stalled: a local minimum or a bound we cannot leave
                }
            }
        }
        let converged = self.converged(&ev);
        Ok((
            IkSolution {
                q,
                h: ev.h,
                pos_error: ev.pos_err,
                rot_error: ev.rot_err,
                iterations: iters,
                restarts: 0,
                converged,
            },
            iters,
        ))
    }
}

fn clamp(q: &DVector<f64>, lo: &DVector<f64>, hi: &DVector<f64>) -> DVector<f64> {
    DVector::from_fn(q.len(), |i, _| q[i].max(lo[i]).min(hi[i]))
}

/// xorshift64*: a tiny deterministic generator for restart seeds.
struct XorShift(u64);

impl XorShift {
    fn next_f64(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        let v = self.0.wrapping_mul(0x2545_f491_4f6c_dd1d);
        (v >> 11) as f64 / (1u64 << 53) as f64
    }
}
