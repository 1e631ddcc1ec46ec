//! `cartesiancontrollerserver` (icub-main's `ServerCartesianController`), sans I/O: the
//! state of a limb's Cartesian controller — the measured chain, the min-jerk controller
//! that plans the joints, the solver's last answer, trajectory time, tolerance, modes,
//! contexts, events — and what each `rpc:i` command, each `command:i` message and each
//! control period does to it. [`crate::server_device`] gives it ports, boards and a thread.

use icub_ikin::minjerk::{CtrlPose, MinJerkController};
use icub_ikin::{Limb, LimbKind, DEG2RAD, RAD2DEG};
use nalgebra::DVector;
use std::collections::BTreeMap;
use std::time::Duration;
use yarp_devices::driver::Params;
use yarp_devices::error::{DevResult, DeviceError};
use yarp_proto::{Bottle, Property, Value};

use crate::protocol::{self, ack, nack, truth, word};

/// The C++ device name.
pub const NAME: &str = "cartesiancontrollerserver";
/// What `[get] [info]` says of the server (`CARTCTRL_SERVER_VER`).
pub const SERVER_VERSION: &str = "2.0";
/// Default trajectory time \[s\] and in-target tolerance.
const DEFAULT_TRAJ_TIME: f64 = 2.0;
const DEFAULT_TOL: f64 = 1e-2;

yarp_devices::device_params! {
    /// What `cartesiancontrollerserver` reads (icub-main's `ServerCartesianController`),
    /// besides the groups `DRIVER_<i>` (`Key`, `JointsOrder direct|reversed`,
    /// `MinAbsVels`) of each driver and `PLANT_MODEL`.
    pub struct CartesianControllerServerParams for "cartesiancontrollerserver" {
        /// Name of the controller's ports (`/<name>/...`)
        "GENERAL::ControllerName" controller_name: String = required,
        /// Period of the controller
        "GENERAL::ControllerPeriod" controller_period: i64 = 10; "ms"; in 1..=10000,
        /// Time after which the robot's encoders count as lost
        "GENERAL::RobotTimeout" robot_timeout: f64 = 1.0; "s"; check yarp_devices::params::positive,
        /// The solver module's port prefix (iKinCartesianSolver's `name`)
        "GENERAL::SolverNameToConnect" solver_name: String = required,
        /// The limb: arm or leg (custom chains are not supported)
        "GENERAL::KinematicPart" kinematic_part: String = required,
        /// The iKin limb type (e.g. right_v2)
        "GENERAL::KinematicType" kinematic_type: String = required,
        /// Number of the DRIVER_<i> groups
        "GENERAL::NumberOfDrivers" number_of_drivers: i64 = required; in 1..=8,
        /// Periods between two targets of the task-velocity mode
        "GENERAL::TaskRefVelPeriodFactor" task_ref_vel_period_factor: i64 = 4; in 1..=1000,
        /// Joints commanded in position direct (on) or velocity (off)
        "GENERAL::PositionControl" position_control: String = "on",
        /// One call per part (on) or per joint (off)
        "GENERAL::MultipleJointsControl" multiple_joints_control: String = "on",
    }
}

/// One `DRIVER_<i>` group: which attached device feeds which links.
#[derive(Debug, Clone, PartialEq)]
pub struct DriverDesc {
    /// The attach key (`networks` name) of the device.
    pub key: String,
    /// `JointsOrder reversed`: the device's joints fill the links last to first.
    pub reversed: bool,
    /// `MinAbsVels` \[deg/s\] (velocity control).
    pub min_abs_vels: Vec<f64>,
}

/// The configuration of a cartesian controller server.
#[derive(Debug, Clone, PartialEq)]
pub struct ServerConfig {
    /// `ControllerName`, without the leading `/`.
    pub name: String,
    /// `SolverNameToConnect`, without the leading `/`.
    pub solver: String,
    pub period: Duration,
    pub robot_timeout: Duration,
    pub kind: LimbKind,
    pub part: String,
    pub kinematic_type: String,
    pub drivers: Vec<DriverDesc>,
    pub position_control: bool,
    pub multiple_joints: bool,
    pub task_ref_vel_period_factor: u32,
}

impl ServerConfig {
    /// Reads the `GENERAL` and `DRIVER_<i>` groups of a device configuration.
    pub fn from_property(config: &Property) -> DevResult<Self> {
        let declared = CartesianControllerServerParams::read(config)?;
        let p = Params::new(NAME, config);
        let req = |key: &str| -> DevResult<String> { p.string(key)?.ok_or_else(|| p.missing(key)) };
        let bad = |param: &str, expected: &'static str, got: String| DeviceError::BadParam {
            device: NAME.into(),
            param: param.into(),
            expected,
            got,
        };
        let part = declared.kinematic_part;
        let kind = match part.as_str() {
            "arm" => LimbKind::Arm,
            "leg" => LimbKind::Leg,
            _ => {
                return Err(bad(
                    "GENERAL::KinematicPart",
                    "`arm` or `leg` (custom chains are not supported)",
                    part,
                ))
            }
        };
        let kinematic_type = declared.kinematic_type;
        Limb::new(kind, &kinematic_type).map_err(|e| {
            bad(
                "GENERAL::KinematicType",
                "an iKin limb type",
                format!("{kinematic_type} ({e})"),
            )
        })?;
        let mut drivers = Vec::new();
        for i in 0..declared.number_of_drivers {
            let key = req(&format!("DRIVER_{i}::Key"))?;
            let order_key = format!("DRIVER_{i}::JointsOrder");
            let reversed = match p.string(&order_key)?.as_deref() {
                None | Some("direct") => false,
                Some("reversed") => true,
                Some(other) => return Err(bad(&order_key, "`direct` or `reversed`", other.into())),
            };
            let min_abs_vels = config
                .find_group(format!("DRIVER_{i}"))
                .and_then(|g| g.find("MinAbsVels"))
                .and_then(protocol::numbers)
                .unwrap_or_default()
                .iter()
                .map(|v| v.abs())
                .collect();
            drivers.push(DriverDesc {
                key,
                reversed,
                min_abs_vels,
            });
        }
        Ok(ServerConfig {
            name: declared.controller_name.trim_start_matches('/').to_string(),
            solver: declared.solver_name.trim_start_matches('/').to_string(),
            period: Duration::from_millis(declared.controller_period as u64),
            robot_timeout: Duration::from_secs_f64(declared.robot_timeout),
            kind,
            part,
            kinematic_type,
            drivers,
            position_control: declared.position_control != "off",
            multiple_joints: declared.multiple_joints_control != "off",
            task_ref_vel_period_factor: declared.task_ref_vel_period_factor as u32,
        })
    }
}

/// What the server needs of its solver: its RPC and its target port.
pub trait SolverLink {
    /// A command on `/<ctrl>/<slv>/rpc`; `None` when the solver does not answer.
    fn rpc(&mut self, cmd: &Bottle) -> Option<Bottle>;
    /// A target on `/<ctrl>/<slv>/out` (written strictly).
    fn send(&mut self, target: &Bottle);
}

/// How an RPC is answered.
#[derive(Debug, Clone, PartialEq)]
pub enum Reply {
    Now(Bottle),
    /// `[ack]` once the solver answered the target of this token (a sync `[go]`).
    AfterToken(f64),
}

/// An event for `events:o`: its name, time and checkpoint (motion-ongoing only).
#[derive(Debug, Clone, PartialEq)]
pub struct Event {
    pub name: &'static str,
    pub time: f64,
    pub checkpoint: Option<f64>,
}

/// What a control period produced.
#[derive(Debug, Default)]
pub struct CycleOutput {
    /// Position-direct references of the released links \[deg\], in chain order.
    pub positions: Option<Vec<f64>>,
    /// Velocity commands \[deg/s\] of the released links (velocity mode).
    pub velocities: Option<Vec<f64>>,
    /// Stop the released joints (a stop in position direct).
    pub stop: bool,
    /// The pose for `state:o` (when connected).
    pub state: Option<[f64; 7]>,
    pub events: Vec<Event>,
    /// The token of a solver answer (a sync `[go]` waiting for it may reply).
    pub rx_token: Option<f64>,
}

/// A stored context (`[stor]`).
#[derive(Debug, Clone)]
struct Context {
    dof: Vec<i32>,
    rest_pos: Option<Bottle>,
    rest_weights: Option<Bottle>,
    tip: [f64; 7],
    limits: Vec<(f64, f64)>,
    traj_time: f64,
    tol: f64,
    tracking: bool,
    references: bool,
    gamma: f64,
    position_first: bool,
}

/// The controller's state.
pub struct ServerCore {
    cfg: ServerConfig,
    /// The measured limb.
    state: Limb,
    /// The planner (position direct: its own chain, restarted from the robot at onset).
    ctrl: MinJerkController,
    connected: bool,
    traj_time: f64,
    tol: f64,
    tracking: bool,
    references: bool,
    position_first: bool,
    /// The pose the last target asked for (full or position only).
    full_pose: bool,
    tip: [f64; 7],
    xdes: Vec<f64>,
    qdes: DVector<f64>,
    executing: bool,
    motion_done: bool,
    tx_token: f64,
    skip_solver: bool,
    tx_token_stop: f64,
    /// Feedback of the released joints at the motion's onset \[rad\].
    q0: DVector<f64>,
    path_perc: f64,
    checkpoints: Vec<f64>,
    pending_checkpoints: Vec<f64>,
    contexts: BTreeMap<i32, Context>,
    next_context: i32,
    vel_cmd: Vec<f64>,
    /// Task-velocity mode: `(v, axis, w)` and the virtual target integrated from it.
    task_vel: Option<([f64; 7], [f64; 7], u32)>,
    now: f64,
}

fn ctrl_pose(full: bool) -> CtrlPose {
    if full {
        CtrlPose::Full
    } else {
        CtrlPose::Xyz
    }
}

impl ServerCore {
    /// A controller over `limits` \[deg\] of every link, as the boards gave them.
    pub fn new(cfg: ServerConfig, limits: &[(f64, f64)]) -> DevResult<Self> {
        let mut state = Limb::new(cfg.kind, &cfg.kinematic_type)
            .map_err(|_| DeviceError::Unsupported("unknown KinematicType"))?;
        for (i, &(lo, hi)) in limits.iter().enumerate().take(state.chain().n()) {
            let _ = state.chain_mut().set_limits(i, lo * DEG2RAD, hi * DEG2RAD);
        }
        let ts = cfg.period.as_secs_f64();
        let mut ctrl = MinJerkController::new(state.chain().clone(), CtrlPose::Full, ts)
            .map_err(|_| DeviceError::Unsupported("no released joint in the chain"))?;
        let traj_time = ctrl.set_exec_time(DEFAULT_TRAJ_TIME);
        ctrl.set_in_target_tol(DEFAULT_TOL);
        let dof = state.chain().dof();
        let x = state.chain().end_eff_pose();
        Ok(ServerCore {
            cfg,
            ctrl,
            connected: false,
            traj_time,
            tol: DEFAULT_TOL,
            tracking: false,
            references: false,
            position_first: true,
            full_pose: true,
            tip: [0.0; 7],
            xdes: x.iter().copied().collect(),
            qdes: state.chain().ang(),
            executing: false,
            motion_done: true,
            tx_token: 0.0,
            skip_solver: false,
            tx_token_stop: 0.0,
            q0: DVector::zeros(dof),
            path_perc: 0.0,
            checkpoints: Vec::new(),
            pending_checkpoints: Vec::new(),
            contexts: BTreeMap::new(),
            next_context: 0,
            vel_cmd: vec![0.0; dof],
            task_vel: None,
            now: 0.0,
            state,
        })
    }

    pub fn config(&self) -> &ServerConfig {
        &self.cfg
    }

    pub fn is_connected(&self) -> bool {
        self.connected
    }

    /// Number of links.
    pub fn links(&self) -> usize {
        self.state.chain().n()
    }

    /// The released links' indices.
    pub fn released(&self) -> Vec<usize> {
        self.state.chain().dof_links().to_vec()
    }

    /// Joint `k` of part `d` (hardware index) for each link, in chain order:
    /// `(driver, axis)`.
    pub fn link_map(&self, axes: &[usize]) -> Vec<(usize, usize)> {
        let mut out = Vec::new();
        let n = self.links();
        for (d, (desc, &joints)) in self.cfg.drivers.iter().zip(axes).enumerate() {
            let joints = joints.min(n - out.len());
            for k in 0..joints {
                out.push((d, if desc.reversed { joints - k - 1 } else { k }));
            }
        }
        out
    }

    /// After the solver's ports are connected: its DOF, the tracking mode, the
    /// planner rebuilt and context 0 stored (`connectToSolver`).
    pub fn on_connected(&mut self, solver: &mut dyn SolverLink) -> bool {
        let Some(reply) = solver.rpc(
            &Bottle::new()
                .with(Value::vocab(word::GET))
                .with(Value::vocab(word::DOF)),
        ) else {
            return false;
        };
        if !protocol::is_ack(&reply) {
            return false;
        }
        if let Some(dof) = reply.get(1).and_then(protocol::numbers) {
            self.apply_dof(&dof);
        }
        self.connected = true;
        let mode = if self.tracking {
            word::TRACK
        } else {
            word::SINGLE
        };
        solver.rpc(&set_cmd(word::MODE).with(Value::vocab(mode)));
        self.rebuild_controller();
        if self.contexts.is_empty() {
            self.store_context(solver);
        }
        true
    }

    /// The solver is gone (its ports disconnected).
    pub fn on_disconnected(&mut self) {
        self.connected = false;
    }

    fn apply_dof(&mut self, dof: &[f64]) {
        let chain = self.state.chain_mut();
        for (i, d) in dof.iter().enumerate().take(chain.n()) {
            let blocked = chain.is_blocked(i).unwrap_or(false);
            if *d != 0.0 && blocked {
                let _ = chain.release_link(i);
            } else if *d == 0.0 && !blocked {
                let q = chain.all_angles()[i];
                let _ = chain.block_link(i, q);
            }
        }
    }

    /// A new planner on the measured chain (`createController`): any motion stops.
    fn rebuild_controller(&mut self) {
        let ts = self.cfg.period.as_secs_f64();
        if let Ok(mut c) = MinJerkController::new(self.state.chain().clone(), CtrlPose::Full, ts) {
            self.traj_time = c.set_exec_time(self.traj_time);
            c.set_in_target_tol(self.tol);
            c.set_gamma(self.ctrl.gamma());
            self.ctrl = c;
        }
        let dof = self.state.chain().dof();
        self.qdes = self.state.chain().ang();
        self.q0 = DVector::zeros(dof);
        self.vel_cmd = vec![0.0; dof];
        self.executing = false;
        self.motion_done = true;
    }

    /// Sends a target to the solver (`goTo`): `([xd] ..) ([pose] ..) ([mode] [cont]) ([tok] t)`.
    fn go_to(
        &mut self,
        full: bool,
        xd: &[f64],
        t: f64,
        solver: &mut dyn SolverLink,
    ) -> Option<f64> {
        if !self.connected || self.state.chain().dof() == 0 {
            return None;
        }
        self.motion_done = false;
        self.task_vel = None;
        self.ctrl.set_pose(ctrl_pose(full));
        self.full_pose = full;
        if t > 0.0 {
            self.traj_time = self.ctrl.set_exec_time(t);
        }
        // tokens are times, as C++'s; strictly increasing even within a clock tick
        let token = self.now.max(self.tx_token + 1e-6);
        self.tx_token = token;
        self.skip_solver = false;
        let b = Bottle::new()
            .with(protocol::vector_option(word::XD, xd))
            .with(protocol::vocab_option(
                word::POSE,
                if full { word::FULL } else { word::XYZ },
            ))
            .with(protocol::vocab_option(word::MODE, word::TRACK))
            .with(protocol::token_option(token));
        solver.send(&b);
        Some(token)
    }

    /// Stops a motion (`stopControlHelper`).
    fn stop_control(&mut self, out: &mut CycleOutput, solver: &mut dyn SolverLink) {
        if !(self.executing || self.task_vel.is_some()) {
            return;
        }
        self.executing = false;
        self.task_vel = None;
        self.motion_done = true;
        self.vel_cmd.iter_mut().for_each(|v| *v = 0.0);
        out.stop = true;
        self.tx_token_stop = self.tx_token;
        self.skip_solver = true;
        out.events.push(self.event("motion-done", None));
        if !self.tracking {
            solver.rpc(&set_cmd(word::MODE).with(Value::vocab(word::SINGLE)));
        }
    }

    fn event(&self, name: &'static str, checkpoint: Option<f64>) -> Event {
        Event {
            name,
            time: self.now,
            checkpoint,
        }
    }

    /// A message of `command:i`: `[go] [full|xyz] t (x..)` or `[tvel] (v.. axis.. w)`.
    pub fn on_command(&mut self, b: &Bottle, solver: &mut dyn SolverLink) -> CycleOutput {
        let mut out = CycleOutput::default();
        if protocol::is_word(b, 0, word::GO) && b.len() > 3 {
            let full = protocol::is_word(b, 1, word::FULL);
            let t = b.get(2).and_then(Value::as_f64).unwrap_or(0.0);
            if let Some(xd) = b.get(3).and_then(protocol::numbers) {
                if full || protocol::is_word(b, 1, word::XYZ) {
                    self.go_to(full, &xd, t, solver);
                }
            }
        } else if protocol::is_word(b, 0, word::TASKVEL) && b.len() > 1 {
            if let Some(v) = b
                .get(1)
                .and_then(protocol::numbers)
                .filter(|v| v.len() >= 7)
            {
                let mut xdot = [0.0; 7];
                xdot.copy_from_slice(&v[..7]);
                self.set_task_velocities(xdot, &mut out, solver);
            }
        }
        out
    }

    fn set_task_velocities(
        &mut self,
        xdot: [f64; 7],
        out: &mut CycleOutput,
        solver: &mut dyn SolverLink,
    ) {
        if xdot.iter().all(|v| *v == 0.0) {
            self.stop_control(out, solver);
            return;
        }
        let x = self.state.chain().end_eff_pose();
        let mut target = [0.0; 7];
        target.copy_from_slice(x.as_slice());
        let count = self.task_vel.map_or(0, |t| t.2);
        let target = self.task_vel.map_or(target, |t| t.1);
        self.task_vel = Some((xdot, target, count));
    }

    /// One control period with the measured joints of every link (`fb_deg`, chain
    /// order) and the solver's latest answer, if one came.
    pub fn cycle(
        &mut self,
        now: f64,
        fb_deg: &[f64],
        from_solver: Option<&Bottle>,
        healthy: bool,
        solver: &mut dyn SolverLink,
    ) -> CycleOutput {
        self.now = now;
        let mut out = CycleOutput::default();
        let chain = self.state.chain_mut();
        for (i, q) in fb_deg.iter().enumerate().take(chain.n()) {
            if chain.is_blocked(i).unwrap_or(false) {
                let _ = chain.set_blocking_value(i, q * DEG2RAD);
            } else {
                let _ = chain.set_link_ang(i, q * DEG2RAD);
            }
        }
        let fb = self.state.chain().ang();
        if !self.connected {
            return out;
        }
        if !healthy {
            self.stop_control(&mut out, solver);
        }
        // the task-velocity mode's virtual target, every TaskRefVelPeriodFactor periods
        if let Some((xdot, mut target, count)) = self.task_vel {
            let factor = self.cfg.task_ref_vel_period_factor;
            if count % factor == 0 {
                let dt = factor as f64 * self.cfg.period.as_secs_f64();
                for k in 0..3 {
                    target[k] += xdot[k] * dt;
                }
                let r = icub_ikin::pose::axis2dcm(&nalgebra::Vector4::new(
                    xdot[3],
                    xdot[4],
                    xdot[5],
                    xdot[6] * dt,
                )) * icub_ikin::pose::axis2dcm(&nalgebra::Vector4::new(
                    target[3], target[4], target[5], target[6],
                ));
                let ax = icub_ikin::pose::dcm2axis(&r);
                target[3..7].copy_from_slice(ax.as_slice());
                let saved = self.task_vel.take();
                self.go_to(true, &target, 0.0, solver);
                self.motion_done = false;
                self.task_vel = saved;
            }
            self.task_vel = Some((xdot, target, count + 1));
        }
        // the solver's answer
        let mut new_target = false;
        if let Some(b) = from_solver {
            let token = protocol::find_number(b, word::TOKEN);
            let stale = token.is_some_and(|t| t > self.tx_token)
                || (self.skip_solver
                    && !self.tracking
                    && token.is_some_and(|t| t <= self.tx_token_stop));
            if !stale {
                self.skip_solver = false;
                let x = protocol::find_vector(b, word::X).unwrap_or_default();
                let q: Vec<f64> = protocol::find_vector(b, word::Q)
                    .unwrap_or_default()
                    .iter()
                    .map(|v| v * DEG2RAD)
                    .collect();
                if q.len() == self.qdes.len() {
                    let q = DVector::from_vec(q);
                    if x != self.xdes || q != self.qdes {
                        new_target = true;
                        self.xdes = x;
                        self.qdes = q;
                    }
                    out.rx_token = token;
                }
            }
        }
        if new_target && healthy {
            if !self.executing {
                let _ = self.ctrl.restart(fb.as_slice());
            }
            self.executing = true;
            out.events.push(self.event("motion-onset", None));
            self.pending_checkpoints = self.checkpoints.clone();
            self.q0 = fb.clone();
        }
        // how far along the path
        let den = (&self.qdes - &self.q0).norm();
        self.path_perc = if den > 1e-6 {
            ((&fb - &self.q0).norm() / den).clamp(0.0, 1.0)
        } else {
            1.0
        };
        let mut done_now = false;
        if self.executing {
            let xd = self.xdes.clone();
            let qd = self.qdes.clone();
            let xdot = self.task_vel.map(|t| t.0);
            self.ctrl.iterate(&xd, &qd, xdot.as_ref());
            let mut in_target = self.ctrl.is_in_target();
            if self.cfg.position_control {
                in_target &= self.measured_in_target();
            }
            if in_target && self.task_vel.is_none() {
                self.executing = false;
                self.motion_done = true;
                self.vel_cmd.iter_mut().for_each(|v| *v = 0.0);
                done_now = true;
                if !self.tracking && out.rx_token.is_none_or(|t| t == self.tx_token) {
                    solver.rpc(&set_cmd(word::MODE).with(Value::vocab(word::SINGLE)));
                }
            } else if self.cfg.position_control {
                out.positions = Some(self.ctrl.q().iter().map(|v| v * RAD2DEG).collect());
                self.vel_cmd = self.ctrl.qdot().iter().map(|v| v * RAD2DEG).collect();
            } else {
                let v: Vec<f64> = self.ctrl.qdot().iter().map(|v| v * RAD2DEG).collect();
                self.vel_cmd = v.clone();
                out.velocities = Some(v);
            }
        }
        let x = self.state.chain().end_eff_pose();
        out.state = Some([x[0], x[1], x[2], x[3], x[4], x[5], x[6]]);
        // the ongoing checkpoints reached, the smallest first, one per period
        if let Some(&cp) = self.pending_checkpoints.first() {
            if self.path_perc >= cp {
                self.pending_checkpoints.remove(0);
                out.events.push(self.event("motion-ongoing", Some(cp)));
            }
        }
        if done_now {
            for cp in std::mem::take(&mut self.pending_checkpoints) {
                out.events.push(self.event("motion-ongoing", Some(cp)));
            }
            out.events.push(self.event("motion-done", None));
        }
        out
    }

    /// The measured pose within the tolerance of the solver's (`isInTargetHelper`).
    fn measured_in_target(&self) -> bool {
        if self.xdes.len() < 3 {
            return false;
        }
        let h = self.state.chain().h();
        let mut e = [0.0; 6];
        for k in 0..3 {
            e[k] = self.xdes[k] - h[(k, 3)];
        }
        if self.xdes.len() >= 7 && self.ctrl_is_full() {
            let des = icub_ikin::pose::axis2dcm(&nalgebra::Vector4::new(
                self.xdes[3],
                self.xdes[4],
                self.xdes[5],
                self.xdes[6],
            ));
            let r = icub_ikin::pose::rotation(&h);
            let ax = icub_ikin::pose::dcm2axis(&(des * r.transpose()));
            for k in 0..3 {
                e[3 + k] = ax[3] * ax[k];
            }
        }
        e.iter().map(|v| v * v).sum::<f64>().sqrt() < self.tol
    }

    fn ctrl_is_full(&self) -> bool {
        self.full_pose
    }
}

fn set_cmd(opt: &str) -> Bottle {
    Bottle::new()
        .with(Value::vocab(word::SET))
        .with(Value::vocab(opt))
}

fn get_cmd(opt: &str) -> Bottle {
    Bottle::new()
        .with(Value::vocab(word::GET))
        .with(Value::vocab(opt))
}

/// The `rpc:i` commands (`ServerCartesianController::respond`).
impl ServerCore {
    /// Answers one command; `out` collects what the command did to the motion (a stop).
    pub fn respond(
        &mut self,
        cmd: &Bottle,
        solver: &mut dyn SolverLink,
        out: &mut CycleOutput,
    ) -> Reply {
        let w = |i: usize| protocol::word_at(cmd, i).unwrap_or_default();
        let reply = match w(0).as_str() {
            word::STOP => {
                self.stop_control(out, solver);
                ack()
            }
            word::GO if cmd.len() > 3 => {
                let full = match w(1).as_str() {
                    word::FULL => Some(true),
                    word::XYZ => Some(false),
                    _ => None,
                };
                let t = cmd.get(2).and_then(Value::as_f64).unwrap_or(0.0);
                let xd = cmd.get(3).and_then(protocol::numbers);
                return match (full, xd) {
                    (Some(full), Some(xd)) => match self.go_to(full, &xd, t, solver) {
                        Some(token) => Reply::AfterToken(token),
                        None => Reply::Now(nack()),
                    },
                    _ => Reply::Now(nack()),
                };
            }
            // relayed to the solver as it is
            word::ASK => {
                let mut r = solver.rpc(cmd).unwrap_or_default();
                if r.is_empty() {
                    r.push(Value::vocab(word::NACK));
                }
                r
            }
            word::STORE => match self.store_context(solver) {
                Some(id) => ack().with(id),
                None => nack(),
            },
            // without an id C++ answers nothing at all
            word::RESTORE if cmd.len() > 1 => {
                let id = cmd.get(1).and_then(Value::as_i64).unwrap_or(-1);
                if self.restore_context(id as i32, solver) {
                    ack()
                } else {
                    nack()
                }
            }
            word::DELETE if cmd.len() > 1 => match cmd.get(1).and_then(Value::as_list) {
                Some(ids) => {
                    for id in ids.iter().filter_map(Value::as_i64) {
                        self.contexts.remove(&(id as i32));
                    }
                    ack()
                }
                None => nack(),
            },
            word::RESTORE | word::DELETE => Bottle::new(),
            word::GET if cmd.len() > 1 => self.respond_get(cmd, &w(1), solver),
            word::SET if cmd.len() > 2 => self.respond_set(cmd, &w(1), solver, out),
            word::EVENT if cmd.len() > 2 => self.respond_event(cmd, &w(1), &w(2)),
            _ => nack(),
        };
        Reply::Now(reply)
    }

    fn respond_get(&mut self, cmd: &Bottle, opt: &str, solver: &mut dyn SolverLink) -> Bottle {
        let attached = true;
        match opt {
            word::MODE => ack().with(Value::vocab(if self.tracking {
                word::TRACK
            } else {
                word::SINGLE
            })),
            word::REFERENCE => ack().with(truth(self.references)),
            word::PRIO => match self.priority(solver) {
                Some(p) => ack().with(p),
                None => nack(),
            },
            word::TIME if attached => ack().with(self.traj_time),
            word::TOL => ack().with(self.tol),
            word::DONE => ack().with(truth(self.motion_done)),
            word::IS_SOLVER_ON => ack().with(truth(self.connected)),
            word::LIM if cmd.len() > 2 && self.connected => {
                let axis = cmd.get(2).and_then(Value::as_i64).unwrap_or(-1);
                if axis < 0 || axis as usize >= self.links() {
                    return nack();
                }
                match solver.rpc(&get_cmd(word::LIM).with(Value::Int32(axis as i32))) {
                    Some(r) if protocol::is_ack(&r) && r.len() > 2 => {
                        let v = |i| r.get(i).and_then(Value::as_f64).unwrap_or(0.0);
                        ack().with(v(1)).with(v(2))
                    }
                    _ => nack(),
                }
            }
            word::DOF if self.connected => ack().with(protocol::i32_list(self.dof_vector())),
            word::REST_POS | word::REST_WEIGHTS if self.connected => {
                match solver.rpc(&get_cmd(opt)).and_then(|r| r.get(1).cloned()) {
                    Some(list) => ack().with(list),
                    None => nack(),
                }
            }
            word::DES => {
                let c = self.state.chain();
                let released = c.dof_links().to_vec();
                let q: Vec<f64> = (0..c.n())
                    .map(|i| match released.iter().position(|&l| l == i) {
                        Some(k) => self.qdes.get(k).copied().unwrap_or(0.0) * RAD2DEG,
                        None => c.all_angles()[i] * RAD2DEG,
                    })
                    .collect();
                ack()
                    .with(protocol::vector_option(word::X, &self.xdes))
                    .with(protocol::vector_option(word::Q, &q))
            }
            word::QDOT if self.connected => ack().with(protocol::f64_list(&self.vel_cmd)),
            word::XDOT if self.connected => ack().with(protocol::f64_list(&self.task_velocity())),
            word::POSE if cmd.len() > 2 => {
                let axis = cmd.get(2).and_then(Value::as_i64).unwrap_or(-1);
                if axis < 0 || axis as usize >= self.links() {
                    return nack();
                }
                match self.state.chain().link_h(axis as usize) {
                    Ok(h) => {
                        let x = icub_ikin::pose::pose7(&h);
                        ack()
                            .with(protocol::f64_list(x.as_slice()))
                            .with(Value::List(
                                Bottle::new().with(Value::Int32(0)).with(self.now),
                            ))
                    }
                    Err(_) => nack(),
                }
            }
            word::TIP => ack().with(protocol::f64_list(&self.tip)),
            word::INFO => ack().with(Value::List(self.info())),
            word::TWEAK => {
                let mut opts = Bottle::new();
                opts.push(Value::List(
                    Bottle::new().with("straightness").with(self.ctrl.gamma()),
                ));
                if let Some(r) = solver.rpc(&get_cmd(word::TASK2)).filter(protocol::is_ack) {
                    if let Some(v) = r.get(1) {
                        opts.push(Value::List(Bottle::new().with("task_2").with(v.clone())));
                    }
                }
                if let Some(r) = solver
                    .rpc(&get_cmd(word::CONVERGENCE))
                    .filter(protocol::is_ack)
                {
                    if let Some(l) = r.get(1).and_then(Value::as_list) {
                        for v in l.iter() {
                            opts.push(v.clone());
                        }
                    }
                }
                ack().with(Value::List(opts))
            }
            _ => nack(),
        }
    }

    fn respond_set(
        &mut self,
        cmd: &Bottle,
        opt: &str,
        solver: &mut dyn SolverLink,
        out: &mut CycleOutput,
    ) -> Bottle {
        let value = protocol::word_at(cmd, 2).unwrap_or_default();
        let ok = |b: bool| if b { ack() } else { nack() };
        match opt {
            word::MODE => ok(match value.as_str() {
                word::TRACK => self.set_tracking(true, solver),
                word::SINGLE => self.set_tracking(false, solver),
                _ => false,
            }),
            word::REFERENCE => ok(match value.as_str() {
                word::TRUE => {
                    self.references = true;
                    true
                }
                word::FALSE => {
                    self.references = false;
                    true
                }
                _ => false,
            }),
            word::PRIO => ok(match value.as_str() {
                "position" | "orientation" => self.set_priority(value == "position", solver),
                _ => false,
            }),
            word::TIME => match cmd.get(2).and_then(Value::as_f64) {
                Some(t) => {
                    self.traj_time = self.ctrl.set_exec_time(t);
                    ack()
                }
                None => nack(),
            },
            word::TOL => match cmd.get(2).and_then(Value::as_f64) {
                Some(t) => {
                    self.tol = t;
                    self.ctrl.set_in_target_tol(t);
                    ack()
                }
                None => nack(),
            },
            word::LIM if cmd.len() > 4 => {
                let r = solver.rpc(&cmd.clone());
                ok(r.as_ref().is_some_and(protocol::is_ack))
            }
            word::DOF if self.connected => {
                let Some(dof) = cmd.get(2).and_then(protocol::numbers) else {
                    return nack();
                };
                let ints = protocol::i32_list(dof.iter().map(|v| *v as i32));
                match solver.rpc(&set_cmd(word::DOF).with(ints)) {
                    Some(r) => {
                        let now = r.get(1).and_then(protocol::numbers).unwrap_or_default();
                        self.stop_control(out, solver);
                        self.apply_dof(&now);
                        self.rebuild_controller();
                        ack().with(protocol::i32_list(self.dof_vector()))
                    }
                    None => nack(),
                }
            }
            word::REST_POS | word::REST_WEIGHTS if self.connected => {
                let Some(list) = cmd.get(2).cloned() else {
                    return nack();
                };
                match solver
                    .rpc(&set_cmd(opt).with(list))
                    .and_then(|r| r.get(1).cloned())
                {
                    Some(v) => ack().with(v),
                    None => nack(),
                }
            }
            word::TIP => match cmd.get(2).and_then(protocol::numbers) {
                Some(v) if v.len() >= 7 && self.connected => {
                    let mut tip = [0.0; 7];
                    tip.copy_from_slice(&v[..7]);
                    ok(self.set_tip(tip, solver))
                }
                _ => nack(),
            },
            word::TWEAK => match cmd.get(2).and_then(Value::as_list) {
                Some(opts) => ok(self.tweak(opts, solver)),
                None => nack(),
            },
            _ => nack(),
        }
    }

    fn respond_event(&mut self, cmd: &Bottle, op: &str, kind: &str) -> Bottle {
        let cp = cmd.get(3).and_then(Value::as_f64);
        match (op, kind) {
            (word::REGISTER, word::ONGOING) => match cp {
                Some(cp) if (0.0..=1.0).contains(&cp) => {
                    let at = self.checkpoints.partition_point(|&c| c <= cp);
                    self.checkpoints.insert(at, cp);
                    ack()
                }
                _ => nack(),
            },
            (word::UNREGISTER, word::ONGOING) => {
                match cp.and_then(|cp| self.checkpoints.iter().position(|&c| c == cp)) {
                    Some(i) => {
                        self.checkpoints.remove(i);
                        ack()
                    }
                    None => nack(),
                }
            }
            (word::LIST, word::ONGOING) => ack().with(protocol::f64_list(&self.checkpoints)),
            _ => nack(),
        }
    }

    fn dof_vector(&self) -> Vec<i32> {
        let c = self.state.chain();
        (0..c.n())
            .map(|i| i32::from(!c.is_blocked(i).unwrap_or(true)))
            .collect()
    }

    /// `[get] [xdot]`: `J qdot` as velocity, unit axis and angular speed.
    fn task_velocity(&self) -> Vec<f64> {
        let j = self.state.chain().geo_jacobian();
        if j.ncols() != self.vel_cmd.len() || j.ncols() == 0 {
            return vec![0.0; 7];
        }
        let qdot = DVector::from_iterator(j.ncols(), self.vel_cmd.iter().map(|v| v * DEG2RAD));
        let v = j * qdot;
        let w = nalgebra::Vector3::new(v[3], v[4], v[5]);
        let n = w.norm();
        let axis = if n > 0.0 { w / n } else { w };
        vec![v[0], v[1], v[2], axis[0], axis[1], axis[2], n]
    }

    fn set_tracking(&mut self, on: bool, solver: &mut dyn SolverLink) -> bool {
        let mode = if on { word::TRACK } else { word::SINGLE };
        let ok = solver
            .rpc(&set_cmd(word::MODE).with(Value::vocab(mode)))
            .is_some_and(|r| protocol::is_ack(&r));
        if ok {
            self.tracking = on;
        }
        ok
    }

    fn priority(&mut self, solver: &mut dyn SolverLink) -> Option<&'static str> {
        let r = solver.rpc(&get_cmd(word::PRIO))?;
        protocol::is_ack(&r).then(|| {
            if protocol::is_word(&r, 1, word::XYZ) {
                "position"
            } else {
                "orientation"
            }
        })
    }

    fn set_priority(&mut self, position: bool, solver: &mut dyn SolverLink) -> bool {
        let v = if position { word::XYZ } else { word::ANG };
        let ok = solver
            .rpc(&set_cmd(word::PRIO).with(Value::vocab(v)))
            .is_some_and(|r| protocol::is_ack(&r));
        if ok {
            self.position_first = position;
        }
        ok
    }

    fn set_tip(&mut self, tip: [f64; 7], solver: &mut dyn SolverLink) -> bool {
        let ok = solver
            .rpc(&set_cmd(word::TIP).with(protocol::f64_list(&tip)))
            .is_some_and(|r| protocol::is_ack(&r));
        if ok {
            let mut hn = nalgebra::Matrix4::identity();
            let r =
                icub_ikin::pose::axis2dcm(&nalgebra::Vector4::new(tip[3], tip[4], tip[5], tip[6]));
            hn.fixed_view_mut::<3, 3>(0, 0).copy_from(&r);
            for k in 0..3 {
                hn[(k, 3)] = tip[k];
            }
            let _ = self.state.chain_mut().set_hn(hn);
            self.tip = tip;
            self.rebuild_controller();
        }
        ok
    }

    fn tweak(&mut self, opts: &Bottle, solver: &mut dyn SolverLink) -> bool {
        let mut ok = true;
        if let Some(g) = opts.find("straightness").and_then(Value::as_f64) {
            self.ctrl.set_gamma(g);
        }
        if let Some(t2) = opts.find("task_2") {
            ok &= solver
                .rpc(&set_cmd(word::TASK2).with(t2.clone()))
                .is_some_and(|r| protocol::is_ack(&r));
        }
        if ["tol", "constr_tol", "max_iter"]
            .iter()
            .any(|k| opts.check(k))
        {
            ok &= solver
                .rpc(&set_cmd(word::CONVERGENCE).with(Value::List(opts.clone())))
                .is_some_and(|r| protocol::is_ack(&r));
        }
        ok
    }

    /// `[stor]`: the settings of now, under a new id (`storeContext`).
    fn store_context(&mut self, solver: &mut dyn SolverLink) -> Option<i32> {
        if !self.connected {
            return None;
        }
        let rest = |opt: &str, solver: &mut dyn SolverLink| {
            solver
                .rpc(&get_cmd(opt))
                .and_then(|r| r.get(1).and_then(Value::as_list).cloned())
        };
        let limits = (0..self.links())
            .map(|i| {
                solver
                    .rpc(&get_cmd(word::LIM).with(Value::Int32(i as i32)))
                    .filter(protocol::is_ack)
                    .map(|r| {
                        let v = |k| r.get(k).and_then(Value::as_f64).unwrap_or(0.0);
                        (v(1), v(2))
                    })
                    .unwrap_or((0.0, 0.0))
            })
            .collect();
        let ctx = Context {
            dof: self.dof_vector(),
            rest_pos: rest(word::REST_POS, solver),
            rest_weights: rest(word::REST_WEIGHTS, solver),
            tip: self.tip,
            limits,
            traj_time: self.traj_time,
            tol: self.tol,
            tracking: self.tracking,
            references: self.references,
            gamma: self.ctrl.gamma(),
            position_first: self.position_first,
        };
        let id = self.next_context;
        self.next_context += 1;
        self.contexts.insert(id, ctx);
        Some(id)
    }

    /// `[rest] id` (`restoreContext`): each setting replayed, the solver's included.
    fn restore_context(&mut self, id: i32, solver: &mut dyn SolverLink) -> bool {
        let Some(ctx) = self.contexts.get(&id).cloned() else {
            return false;
        };
        if !self.connected {
            return false;
        }
        let mut out = CycleOutput::default();
        if ctx.dof != self.dof_vector() {
            if let Some(r) =
                solver.rpc(&set_cmd(word::DOF).with(protocol::i32_list(ctx.dof.iter().copied())))
            {
                let now = r.get(1).and_then(protocol::numbers).unwrap_or_default();
                self.stop_control(&mut out, solver);
                self.apply_dof(&now);
                self.rebuild_controller();
            }
        }
        for (opt, v) in [
            (word::REST_POS, &ctx.rest_pos),
            (word::REST_WEIGHTS, &ctx.rest_weights),
        ] {
            if let Some(v) = v {
                solver.rpc(&set_cmd(opt).with(Value::List(v.clone())));
            }
        }
        if ctx.tip != self.tip {
            self.set_tip(ctx.tip, solver);
        }
        for (i, (lo, hi)) in ctx.limits.iter().enumerate() {
            solver.rpc(
                &set_cmd(word::LIM)
                    .with(Value::Int32(i as i32))
                    .with(*lo)
                    .with(*hi),
            );
        }
        self.set_tracking(ctx.tracking, solver);
        self.references = ctx.references;
        self.traj_time = self.ctrl.set_exec_time(ctx.traj_time);
        self.tol = ctx.tol;
        self.ctrl.set_in_target_tol(ctx.tol);
        self.ctrl.set_gamma(ctx.gamma);
        self.set_priority(ctx.position_first, solver);
        true
    }

    /// `[get] [info]`'s list.
    fn info(&self) -> Bottle {
        let pair = |k: String, v: String| Value::List(Bottle::new().with(k).with(v));
        let version = self
            .cfg
            .kinematic_type
            .split_once("_v")
            .map(|(_, v)| {
                let (major, minor) = v.split_once('.').unwrap_or((v, "0"));
                format!("{major}.{minor}")
            })
            .unwrap_or_else(|| "1.0".into());
        let events: Bottle = [
            "motion-onset",
            "motion-done",
            "motion-ongoing",
            "closing",
            "*",
        ]
        .into_iter()
        .map(Value::from)
        .collect();
        Bottle::new()
            .with(pair("server_version".into(), SERVER_VERSION.into()))
            .with(pair(format!("{}_version", self.cfg.part), version))
            .with(pair(
                format!("{}_type", self.cfg.part),
                self.cfg.kinematic_type.clone(),
            ))
            .with(Value::List(
                Bottle::new().with("events").with(Value::List(events)),
            ))
    }
}
