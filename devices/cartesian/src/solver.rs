//! The Cartesian solver of icub-main's `iKinCartesianSolver` module (iKin's
//! `CartesianSolver`), without its ports: a limb's chain fed by the robot's encoders, a
//! target taken from `/in`, a solve per period when the target is new (or, tracking, when
//! the uncontrolled joints drift by more than a degree), the result for `/out`, and the
//! `/rpc` commands. [`crate::solver_service`] is its tokio layer.
//!
//! The problem is iKin's — position first, then orientation (full pose), joints within
//! their bounds — solved with [`icub_ikin::IkSolver`] instead of IPOPT, seeded with the
//! current joints so that the arm moves no more than it must.

use icub_ikin::{IkConfig, IkMode, IkSolver, Limb, LimbKind, DEG2RAD, RAD2DEG};
use nalgebra::Vector4;
use std::time::Duration;
use yarp_proto::{Bottle, Value};

use crate::protocol::{self, ack, nack, word};

/// Uncontrolled joints' drift that makes a tracking solver solve again \[deg\]
/// (`CARTSLV_UNCTRLEDJNTS_THRES`).
const UNCONTROLLED_DRIFT_DEG: f64 = 1.0;

/// Why a solver cannot be configured.
#[derive(Debug, thiserror::Error)]
pub enum SolverConfigError {
    #[error("{0} is invalid: parts are left_arm, right_arm, left_leg and right_leg")]
    Part(String),
    #[error("unable to locate {0} definition")]
    NoGroup(String),
    #[error("the {0} group has no `name`")]
    NoName(String),
    #[error("type {0}: {1}")]
    Type(String, icub_ikin::KinError),
    #[error("{0}: custom kinematics (CustomKinFile) are not supported by this build")]
    Custom(String),
}

/// A solver's configuration: one group of `cartesianSolver.ini`, as
/// `CartesianSolver::open` reads it.
#[derive(Debug, Clone, PartialEq)]
pub struct SolverConfig {
    /// The group's name (`left_arm`, ...), which picks the limb.
    pub part: String,
    /// The port prefix (`name`, e.g. `cartesianSolver/left_arm`), without the `/`.
    pub name: String,
    pub robot: String,
    /// iKin limb type (`left_v2`, ...).
    pub limb_type: String,
    pub kind: LimbKind,
    pub period: Duration,
    /// Links released (1) or blocked (0), all of them; `None`: the limb's default.
    pub dof: Option<Vec<i32>>,
    pub rest_pos: Vec<f64>,
    pub rest_weights: Vec<f64>,
    pub full_pose: bool,
    pub tracking: bool,
    pub verbose: bool,
    pub tol: f64,
    pub constr_tol: f64,
    pub max_iter: i64,
    /// How long to wait for the robot's boards at start \[s\].
    pub ping_robot_tmo: f64,
}

impl SolverConfig {
    /// Reads group `part` of a `cartesianSolver.ini` (`--part`).
    pub fn from_ini(part: &str, ini: &yarp_proto::Property) -> Result<Self, SolverConfigError> {
        let kind = match part {
            "left_arm" | "right_arm" => LimbKind::Arm,
            "left_leg" | "right_leg" => LimbKind::Leg,
            _ => return Err(SolverConfigError::Part(part.into())),
        };
        let group = ini
            .find_group(part)
            .ok_or_else(|| SolverConfigError::NoGroup(part.into()))?;
        // C++ runs a CustomCartesianSolver for such a group, whatever its name
        if group.check("CustomKinFile") {
            return Err(SolverConfigError::Custom(part.into()));
        }
        let text = |k: &str| {
            group.find(k).and_then(|v| match v {
                Value::Vocab32(w) => Some(w.as_string()),
                _ => v.as_str().map(str::to_string),
            })
        };
        let num = |k: &str, d: f64| group.find(k).and_then(Value::as_f64).unwrap_or(d);
        let list = |k: &str| group.find(k).and_then(protocol::numbers);
        let name = text("name").ok_or_else(|| SolverConfigError::NoName(part.into()))?;
        // C++ keeps only `left`/`right` before the `_`; anything else is `right`
        let mut limb_type = text("type").unwrap_or_else(|| "right".into());
        let side = limb_type.split('_').next().unwrap_or("");
        if side != "left" && side != "right" {
            limb_type = "right".into();
        }
        Limb::new(kind, &limb_type).map_err(|e| SolverConfigError::Type(limb_type.clone(), e))?;
        Ok(SolverConfig {
            part: part.into(),
            name: name.trim_start_matches('/').into(),
            robot: text("robot").unwrap_or_else(|| "icub".into()),
            limb_type,
            kind,
            period: Duration::from_millis(num("period", 20.0).max(1.0) as u64),
            dof: list("dof").map(|d| d.iter().map(|v| *v as i32).collect()),
            rest_pos: list("rest_pos").unwrap_or_default(),
            // read as integers by C++ (0.5 is 0)
            rest_weights: list("rest_weights")
                .unwrap_or_default()
                .iter()
                .map(|w| w.trunc().max(0.0))
                .collect(),
            full_pose: text("pose").as_deref() != Some("xyz"),
            tracking: text("mode").as_deref() == Some("cont"),
            verbose: text("verbosity").as_deref() == Some("on"),
            tol: num("tol", 1e-4),
            constr_tol: num("constr_tol", 1e-6),
            max_iter: num("maxIter", 200.0) as i64,
            ping_robot_tmo: num("ping_robot_tmo", 0.0),
        })
    }

    /// The robot's parts the solver reads, in chain order: `(part, reversed)` — the
    /// torso reversed before version 3 (its pitch comes first in the chain).
    pub fn parts(&self) -> Vec<(String, bool)> {
        let version = Limb::new(self.kind, &self.limb_type)
            .map(|l| l.version())
            .unwrap_or(1.0);
        match self.kind {
            LimbKind::Arm => vec![("torso".into(), version < 3.0), (self.part.clone(), false)],
            _ => vec![(self.part.clone(), false)],
        }
    }
}

/// What one solve produced.
#[derive(Debug, Clone, PartialEq)]
pub struct Solution {
    /// The pose reached (7: position, unit axis, angle).
    pub x: [f64; 7],
    /// The released joints \[deg\].
    pub q: Vec<f64>,
}

/// The solver's state.
pub struct SolverCore {
    cfg: SolverConfig,
    limb: Limb,
    /// Hardware (robot) and software (`[set] [lim]`) bounds \[deg\], all links.
    hw_limits: Vec<(f64, f64)>,
    sw_limits: Vec<(f64, f64)>,
    rest_pos: Vec<f64>,
    rest_weights: Vec<f64>,
    full_pose: bool,
    position_first: bool,
    tracking: bool,
    verbose: bool,
    tol: f64,
    constr_tol: f64,
    max_iter: i64,
    task2: (i32, [f64; 3], [f64; 3]),
    /// The target (always 7; a shorter one keeps the rest).
    xd: [f64; 7],
    /// A target (or a pose mode) arrived since the last solve.
    new_input: bool,
    /// The token of the latest target, if it had one.
    token: Option<f64>,
    uncontrolled_old: Vec<f64>,
    tracking_old: bool,
    suspended: bool,
}

impl SolverCore {
    /// A solver over `limits` \[deg\] of every link, read from the robot (`alignJointsBounds`).
    pub fn new(cfg: SolverConfig, limits: &[(f64, f64)]) -> Result<Self, SolverConfigError> {
        let mut limb = Limb::new(cfg.kind, &cfg.limb_type)
            .map_err(|e| SolverConfigError::Type(cfg.limb_type.clone(), e))?;
        let n = limb.chain().n();
        let chain = limb.chain_mut();
        for (i, &(lo, hi)) in limits.iter().enumerate().take(n) {
            let _ = chain.set_limits(i, lo * DEG2RAD, hi * DEG2RAD);
        }
        let hw: Vec<(f64, f64)> = (0..n)
            .map(|i| {
                let l = &chain.links()[i];
                (l.min * RAD2DEG, l.max * RAD2DEG)
            })
            .collect();
        let mut core = SolverCore {
            limb,
            hw_limits: hw.clone(),
            sw_limits: hw,
            rest_pos: vec![0.0; n],
            rest_weights: vec![0.0; n],
            full_pose: cfg.full_pose,
            position_first: true,
            tracking: cfg.tracking,
            verbose: cfg.verbose,
            tol: cfg.tol,
            constr_tol: cfg.constr_tol,
            max_iter: cfg.max_iter,
            task2: match cfg.kind {
                LimbKind::Arm => (6, [0.0, 0.0, -1.0], [0.0, 0.0, 1.0]),
                _ => (0, [0.0; 3], [0.0; 3]),
            },
            xd: [0.0; 7],
            new_input: false,
            token: None,
            uncontrolled_old: Vec::new(),
            tracking_old: false,
            suspended: false,
            cfg,
        };
        let (rp, rw) = (core.cfg.rest_pos.clone(), core.cfg.rest_weights.clone());
        core.set_rest_pos(&rp);
        core.set_rest_weights(&rw);
        if let Some(dof) = core.cfg.dof.clone() {
            core.set_dof(&dof);
        }
        Ok(core)
    }

    pub fn config(&self) -> &SolverConfig {
        &self.cfg
    }

    /// Number of links of the chain.
    pub fn links(&self) -> usize {
        self.limb.chain().n()
    }

    /// The encoders of the parts (`parts()` order, degrees) set the chain (`getFeedback`).
    pub fn set_feedback(&mut self, parts: &[Vec<f64>]) -> Result<(), icub_ikin::KinError> {
        match (self.cfg.kind, parts) {
            (LimbKind::Arm, [torso, arm]) => self.limb.set_from_encoders(torso, arm),
            (_, [leg]) => self.limb.set_from_encoders(&[], leg),
            _ => Err(icub_ikin::KinError::DimensionMismatch {
                expected: self.cfg.parts().len(),
                got: parts.len(),
            }),
        }
    }

    /// Takes the current pose as the target (`initPos`), once the feedback is in.
    pub fn init_target(&mut self) {
        let x = self.limb.chain().end_eff_pose();
        self.xd.copy_from_slice(x.as_slice());
        self.uncontrolled_old = self.uncontrolled();
    }

    fn uncontrolled(&self) -> Vec<f64> {
        let c = self.limb.chain();
        (0..c.n())
            .filter(|&i| c.is_blocked(i).unwrap_or(false))
            .map(|i| c.all_angles()[i])
            .collect()
    }

    /// A bottle from `/in` (`InputPort::onRead`): mode, dof, pose, rest, then the target.
    pub fn on_input(&mut self, b: &Bottle) {
        let has_xd = b.check(word::XD);
        if has_xd {
            self.token = protocol::find_number(b, word::TOKEN);
        }
        match protocol::find_word(b, word::MODE).as_deref() {
            Some(word::TRACK) => self.tracking = true,
            Some(word::SINGLE) => self.tracking = false,
            Some(_) => tracing::warn!("{}: got incomplete mode command", self.cfg.name),
            None => {}
        }
        if let Some(dof) = protocol::find_vector(b, word::DOF) {
            self.set_dof(&dof.iter().map(|v| *v as i32).collect::<Vec<_>>());
        }
        if let Some(p) = protocol::find_word(b, word::POSE) {
            let full = p != word::XYZ;
            if p == word::FULL || p == word::XYZ {
                self.new_input |= full != self.full_pose;
                self.full_pose = full;
            }
        }
        // C++'s `||` short-circuits: a rest position hides rest weights in one message
        if let Some(rp) = protocol::find_vector(b, word::REST_POS) {
            self.set_rest_pos(&rp);
        } else if let Some(rw) = protocol::find_vector(b, word::REST_WEIGHTS) {
            self.set_rest_weights(&rw);
        }
        match protocol::find_vector(b, word::XD) {
            Some(xd) => {
                for (d, v) in self.xd.iter_mut().zip(xd) {
                    *d = v;
                }
                self.new_input = true;
            }
            None => tracing::warn!("{}: missing xd data; it shall be present", self.cfg.name),
        }
    }

    /// One period of the solver's thread (after [`SolverCore::set_feedback`]): the
    /// `/out` bottle when it solved.
    pub fn tick(&mut self) -> Option<Bottle> {
        if self.suspended {
            return None;
        }
        let mut solve = false;
        let unctrl = self.uncontrolled();
        if !unctrl.is_empty() {
            if self.tracking && !self.tracking_old {
                self.uncontrolled_old = unctrl.clone();
            }
            let drift: f64 = unctrl
                .iter()
                .zip(&self.uncontrolled_old)
                .map(|(a, b)| (a - b) * (a - b))
                .sum::<f64>()
                .sqrt();
            solve |= self.tracking && drift * RAD2DEG > UNCONTROLLED_DRIFT_DEG;
        }
        solve |= std::mem::take(&mut self.new_input);
        self.tracking_old = self.tracking;
        if !solve {
            return None;
        }
        let xd = self.xd;
        let sol = self.solve(&xd, None);
        self.uncontrolled_old = unctrl;
        let mut out = Bottle::new()
            .with(protocol::vector_option(word::XD, &xd))
            .with(protocol::vector_option(word::X, &sol.x))
            .with(protocol::vector_option(word::Q, &sol.q));
        if let Some(t) = self.token {
            out.push(protocol::token_option(t));
        }
        Some(out)
    }

    /// Solves for `xd` (3 or 7 values) from the chain's joints (or `q0`, degrees of the
    /// released joints) and leaves the chain at the solution.
    pub fn solve(&mut self, xd: &[f64], q0: Option<&[f64]>) -> Solution {
        let chain = self.limb.chain();
        let mut seed: Vec<f64> = chain.ang().iter().copied().collect();
        if let Some(q0) = q0 {
            for (s, q) in seed.iter_mut().zip(q0) {
                *s = q * DEG2RAD;
            }
        }
        let full = self.full_pose && xd.len() >= 7;
        let mut target = nalgebra::Matrix4::identity();
        if xd.len() >= 7 {
            let r = icub_ikin::pose::axis2dcm(&Vector4::new(xd[3], xd[4], xd[5], xd[6]));
            target.fixed_view_mut::<3, 3>(0, 0).copy_from(&r);
        }
        for k in 0..3.min(xd.len()) {
            target[(k, 3)] = xd[k];
        }
        // position first: a pose out of reach ends at the closest position, its
        // orientation as near as that position allows (iKin's constraint and cost)
        let config = IkConfig {
            mode: if full { IkMode::Pose } else { IkMode::Position },
            rot_weight: if self.position_first { 0.02 } else { 0.5 },
            ..IkConfig::default()
        };
        let solved = IkSolver::new(config)
            .and_then(|s| s.solve(chain, &target, Some(&seed)))
            .map(|s| s.q);
        let q = match solved {
            Ok(q) => q,
            Err(e) => {
                tracing::warn!("{}: solve failed: {e}", self.cfg.name);
                chain.ang()
            }
        };
        let chain = self.limb.chain_mut();
        let _ = chain.set_ang(q.as_slice());
        let x = chain.end_eff_pose();
        Solution {
            x: [x[0], x[1], x[2], x[3], x[4], x[5], x[6]],
            q: chain.ang().iter().map(|v| v * RAD2DEG).collect(),
        }
    }

    fn dof_vector(&self) -> Vec<i32> {
        let c = self.limb.chain();
        (0..c.n())
            .map(|i| i32::from(!c.is_blocked(i).unwrap_or(true)))
            .collect()
    }

    /// `decodeDOF`: 0 blocks a link where it stands, 1 releases it, more leaves it; an
    /// arm's three shoulder joints go together.
    pub fn set_dof(&mut self, dof: &[i32]) -> Vec<i32> {
        let old = self.dof_vector();
        let mut new = old.clone();
        for (n, d) in new.iter_mut().zip(dof) {
            if *d <= 1 {
                *n = i32::from(*d != 0);
            }
        }
        if self.cfg.kind == LimbKind::Arm && new.len() >= 6 {
            let sh = &new[3..6];
            if !(sh.iter().all(|&v| v != 0) || sh.iter().all(|&v| v == 0)) {
                tracing::warn!(
                    "{}: attempt to set one shoulder's joint differently from others",
                    self.cfg.name
                );
                for v in &mut new[3..6] {
                    *v = old[3];
                }
            }
        }
        let chain = self.limb.chain_mut();
        for (i, &d) in new.iter().enumerate() {
            let blocked = chain.is_blocked(i).unwrap_or(false);
            if d == 0 && !blocked {
                let q = chain.all_angles()[i];
                let _ = chain.block_link(i, q);
            } else if d != 0 && blocked {
                let _ = chain.release_link(i);
            }
        }
        self.uncontrolled_old = self.uncontrolled();
        self.dof_vector()
    }

    fn set_rest_pos(&mut self, v: &[f64]) {
        for (i, (r, x)) in self.rest_pos.iter_mut().zip(v).enumerate() {
            let (lo, hi) = self.sw_limits[i];
            *r = x.clamp(lo, hi);
        }
    }

    fn set_rest_weights(&mut self, v: &[f64]) {
        for (r, x) in self.rest_weights.iter_mut().zip(v) {
            *r = x.trunc().max(0.0);
        }
    }

    fn set_limits(&mut self, i: usize, min: f64, max: f64) -> bool {
        let Some(&(hw_lo, hw_hi)) = self.hw_limits.get(i) else {
            return false;
        };
        if min > max || min < hw_lo || max > hw_hi {
            return false;
        }
        if self
            .limb
            .chain_mut()
            .set_limits(i, min * DEG2RAD, max * DEG2RAD)
            .is_err()
        {
            return false;
        }
        self.sw_limits[i] = (min, max);
        true
    }

    fn set_tip(&mut self, v: &[f64]) -> bool {
        if v.len() < 7 {
            return false;
        }
        let mut hn = nalgebra::Matrix4::identity();
        let r = icub_ikin::pose::axis2dcm(&Vector4::new(v[3], v[4], v[5], v[6]));
        hn.fixed_view_mut::<3, 3>(0, 0).copy_from(&r);
        for k in 0..3 {
            hn[(k, 3)] = v[k];
        }
        self.limb.chain_mut().set_hn(hn).is_ok()
    }

    /// Whether the solver's thread is suspended (`[susp]`).
    pub fn is_suspended(&self) -> bool {
        self.suspended
    }

    /// The `/rpc` commands (`CartesianSolver::respond`). `[quit]` answers `[ack]`; the
    /// service closes after it.
    pub fn respond(&mut self, cmd: &Bottle) -> Bottle {
        let w = |i: usize| protocol::word_at(cmd, i).unwrap_or_default();
        match w(0).as_str() {
            word::GET if cmd.len() > 1 => self.respond_get(cmd, &w(1)),
            word::SET if cmd.len() > 2 => self.respond_set(cmd, &w(1)),
            word::ASK => self.respond_ask(cmd),
            word::SUSPEND => {
                self.suspended = true;
                ack()
            }
            word::RUN => {
                self.suspended = false;
                self.init_target();
                ack()
            }
            word::STATUS => ack().with(if self.suspended {
                "suspended"
            } else {
                "running"
            }),
            word::CFG => ack(),
            word::QUIT => ack(),
            word::HELP => {
                let mut b = Bottle::new().with(Value::vocab("many"));
                b.push("***** commands");
                for c in [
                    "get", "set", "ask", "susp", "run", "stat", "cfg", "help", "quit",
                ] {
                    b.push(Value::vocab(c));
                }
                b.push("***** options");
                for c in [
                    "mode", "pose", "dof", "lim", "verb", "tok", "resp", "resw", "tip", "tsk2",
                    "xd", "x", "q",
                ] {
                    b.push(Value::vocab(c));
                }
                b.push("***** values");
                for c in ["full", "xyz", "cont", "shot", "on", "off"] {
                    b.push(Value::vocab(c));
                }
                b
            }
            _ => nack(),
        }
    }

    fn respond_get(&mut self, cmd: &Bottle, opt: &str) -> Bottle {
        let word_reply = |w: &str| ack().with(Value::vocab(w));
        match opt {
            word::POSE => word_reply(if self.full_pose {
                word::FULL
            } else {
                word::XYZ
            }),
            word::PRIO => word_reply(if self.position_first {
                word::XYZ
            } else {
                word::ANG
            }),
            word::MODE => word_reply(if self.tracking {
                word::TRACK
            } else {
                word::SINGLE
            }),
            word::LIM => match cmd.get(2).and_then(Value::as_i64) {
                Some(i) if i >= 0 && (i as usize) < self.links() => {
                    let (lo, hi) = self.sw_limits[i as usize];
                    ack().with(lo).with(hi)
                }
                _ => nack(),
            },
            word::VERBOSITY => word_reply(if self.verbose { word::ON } else { word::OFF }),
            word::DOF => ack().with(protocol::i32_list(self.dof_vector())),
            word::REST_POS => ack().with(protocol::f64_list(&self.rest_pos)),
            word::REST_WEIGHTS => ack().with(protocol::f64_list(&self.rest_weights)),
            word::TASK2 => {
                let (n, x, w) = self.task2;
                ack().with(Value::List(
                    Bottle::new()
                        .with(n)
                        .with(protocol::f64_list(&x))
                        .with(protocol::f64_list(&w)),
                ))
            }
            word::CONVERGENCE => {
                let pair = |k: &str, v: Value| Value::List(Bottle::new().with(k).with(v));
                ack().with(Value::List(
                    Bottle::new()
                        .with(pair("tol", Value::Float64(self.tol)))
                        .with(pair("constr_tol", Value::Float64(self.constr_tol)))
                        .with(pair("max_iter", Value::Int32(self.max_iter as i32))),
                ))
            }
            _ => nack(),
        }
    }

    fn respond_set(&mut self, cmd: &Bottle, opt: &str) -> Bottle {
        let value = protocol::word_at(cmd, 2).unwrap_or_default();
        let list = cmd.get(2).and_then(protocol::numbers);
        let ok = |b: bool| if b { ack() } else { nack() };
        match opt {
            word::POSE if value == word::FULL || value == word::XYZ => {
                let full = value == word::FULL;
                self.new_input |= full != self.full_pose;
                self.full_pose = full;
                ack()
            }
            word::PRIO if value == word::XYZ || value == word::ANG => {
                self.position_first = value == word::XYZ;
                ack()
            }
            word::MODE if value == word::TRACK || value == word::SINGLE => {
                self.tracking = value == word::TRACK;
                ack()
            }
            word::LIM if cmd.len() > 4 => {
                let i = cmd.get(2).and_then(Value::as_i64).unwrap_or(-1);
                let (lo, hi) = (
                    cmd.get(3).and_then(Value::as_f64),
                    cmd.get(4).and_then(Value::as_f64),
                );
                ok(match (usize::try_from(i), lo, hi) {
                    (Ok(i), Some(lo), Some(hi)) => self.set_limits(i, lo, hi),
                    _ => false,
                })
            }
            word::VERBOSITY => match value.as_str() {
                word::ON => {
                    self.verbose = true;
                    ack()
                }
                // C++ answers [nack] having turned it off
                word::OFF => {
                    self.verbose = false;
                    nack()
                }
                _ => Bottle::new(),
            },
            word::DOF => match list {
                Some(d) => {
                    let d: Vec<i32> = d.iter().map(|v| *v as i32).collect();
                    ack().with(protocol::i32_list(self.set_dof(&d)))
                }
                None => nack(),
            },
            word::REST_POS => match list {
                Some(v) => {
                    self.set_rest_pos(&v);
                    ack().with(protocol::f64_list(&self.rest_pos))
                }
                None => nack(),
            },
            word::REST_WEIGHTS => match list {
                Some(v) => {
                    self.set_rest_weights(&v);
                    ack().with(protocol::f64_list(&self.rest_weights))
                }
                None => nack(),
            },
            word::TIP => ok(list.is_some_and(|v| self.set_tip(&v))),
            word::TASK2 => {
                let t = cmd.get(2).and_then(Value::as_list);
                let parsed = t.and_then(|t| {
                    let n = t.get(0)?.as_i64()? as i32;
                    let x = t.get(1).and_then(protocol::numbers)?;
                    let w = t.get(2).and_then(protocol::numbers)?;
                    (x.len() >= 3 && w.len() >= 3)
                        .then(|| (n, [x[0], x[1], x[2]], [w[0], w[1], w[2]]))
                });
                match parsed {
                    Some(t) => {
                        self.task2 = t;
                        ack()
                    }
                    None => nack(),
                }
            }
            word::CONVERGENCE => {
                let Some(opts) = cmd.get(2).and_then(Value::as_list) else {
                    return nack();
                };
                let mut any = false;
                if let Some(v) = opts.find("tol").and_then(Value::as_f64) {
                    self.tol = v;
                    any = true;
                }
                if let Some(v) = opts.find("constr_tol").and_then(Value::as_f64) {
                    self.constr_tol = v;
                    any = true;
                }
                if let Some(v) = opts.find("max_iter").and_then(Value::as_i64) {
                    self.max_iter = if v <= 0 { i64::from(i32::MAX) } else { v };
                    any = true;
                }
                ok(any)
            }
            _ => nack(),
        }
    }

    /// `[ask] ([xd] (...)) [([q] (...))] [([pose] [full|xyz])]`: a solve on the spot;
    /// the reply's `q` covers every link.
    fn respond_ask(&mut self, cmd: &Bottle) -> Bottle {
        let Some(xd) = protocol::find_vector(cmd, word::XD).filter(|x| x.len() >= 3) else {
            return nack();
        };
        let q0 = protocol::find_vector(cmd, word::Q);
        let saved = self.full_pose;
        if let Some(p) = protocol::find_word(cmd, word::POSE) {
            self.full_pose = p != word::XYZ;
        }
        let sol = self.solve(&xd, q0.as_deref());
        self.full_pose = saved;
        let all: Vec<f64> = self
            .limb
            .chain()
            .all_angles()
            .iter()
            .map(|v| v * RAD2DEG)
            .collect();
        ack()
            .with(protocol::vector_option(word::X, &sol.x))
            .with(protocol::vector_option(word::Q, &all))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn genova02_left_arm() -> SolverCore {
        let ini = yarp_proto::Property::from_config_text(
            "[left_arm]\nrobot icub\nname cartesianSolver/left_arm\ntype left_v2\nperiod 20\n\
             dof (0 0 0 1 1 1 1 1 1 1)\nrest_pos (0 0 0 0 0 0 0 0 0 0)\n\
             rest_weights (1.0 1.0 1.0 0.0 0.0 0.0 0.0 0.0 0.0 0.0)\npose full\nmode shot\n",
        )
        .unwrap();
        let cfg = SolverConfig::from_ini("left_arm", &ini).unwrap();
        let limb = Limb::arm("left_v2").unwrap();
        let limits: Vec<(f64, f64)> = limb
            .chain()
            .links()
            .iter()
            .map(|l| (l.min * RAD2DEG, l.max * RAD2DEG))
            .collect();
        let mut core = SolverCore::new(cfg, &limits).unwrap();
        core.set_feedback(&[vec![0.0; 3], vec![-30.0, 30.0, 0.0, 45.0, 0.0, 0.0, 0.0]])
            .unwrap();
        core.init_target();
        core
    }

    #[test]
    fn a_reachable_pose_is_solved_within_a_millimetre() {
        let mut core = genova02_left_arm();
        let mut limb = Limb::arm("left_v2").unwrap();
        let want = limb
            .pose_from_encoders(&[0.0; 3], &[-50.0, 40.0, 20.0, 70.0, -20.0, -10.0, 10.0])
            .unwrap();
        let target = Bottle::new()
            .with(protocol::vector_option(word::XD, want.as_slice()))
            .with(protocol::token_option(7.0));
        core.on_input(&target);
        let out = core.tick().expect("a solve");
        let (x, q, tok) = crate::solver_service::parse_result(&out).unwrap();
        assert_eq!(tok, Some(7.0));
        assert_eq!(q.len(), 7);
        let d = (0..3).map(|k| (x[k] - want[k]).powi(2)).sum::<f64>().sqrt();
        assert!(d < 1e-3, "{d} m: {x:?} for {want:?}");
        assert!(core.tick().is_none(), "nothing new, no solve");
    }

    #[test]
    fn the_rpc_answers_as_cpp() {
        let mut core = genova02_left_arm();
        let r = core.respond(&Bottle::from_text("[get] [dof]"));
        assert_eq!(r.to_string(), "[ack] (0 0 0 1 1 1 1 1 1 1)");
        let r = core.respond(&Bottle::from_text("[set] [dof] (1 1 1 1 0 1 2 2 2 2)"));
        // the shoulder goes together: its joints stay released
        assert_eq!(r.to_string(), "[ack] (1 1 1 1 1 1 1 1 1 1)");
        assert_eq!(
            core.respond(&Bottle::from_text("[set] [verb] [off]"))
                .to_string(),
            "[nack]"
        );
        assert_eq!(
            core.respond(&Bottle::from_text("[get] [prio]")).to_string(),
            "[ack] [xyz]"
        );
        let r = core.respond(&Bottle::from_text("[set] [resw] (0.5 2.7 1 0 0 0 0 0 0 0)"));
        assert_eq!(
            r.to_string(),
            "[ack] (0.0 2.0 1.0 0.0 0.0 0.0 0.0 0.0 0.0 0.0)"
        );
        assert!(protocol::is_ack(
            &core.respond(&Bottle::from_text("[ask] ([xd] (-0.3 -0.1 0.1))"))
        ));
    }
}
