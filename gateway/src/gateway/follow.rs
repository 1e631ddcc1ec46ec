//! The gateway's joint trajectory controller: the FollowJointTrajectory goals of an
//! `[[action]]` with a `controller`, run on a group of control boards (one part, or several
//! such as torso and arm) through a `remote_controlboard` each, as joint_trajectory_controller
//! runs them for MoveIt ([`crate::trajectory`] decides; this module moves the boards).
//!
//! Device interfaces are synchronous, so the group is owned by a thread; the action server
//! hands it goals and cancels over a channel. Each period (`rate_hz`) the thread reads the
//! encoders, commands the boards (position mode: one move per segment, started when the
//! previous point is due, at the speed that ends it on time; position_direct: the desired
//! positions), publishes feedback and checks the tolerances. A new goal preempts the one
//! running (CANCELED, INVALID_GOAL, as joint_trajectory_controller says); a cancel or a
//! violated tolerance stops the joints where they are.

use super::commands::{board_err, missing, Board, Failure, OpenError};
use crate::action::GoalId;
use crate::dynmsg::Value as Ros;
use crate::joint_command::{self, BoardInfo, Mode, Target};
use crate::mapping::{ControlBoard, TrajectoryController};
use crate::trajectory::{self, error_code, Plan, Sample, Verdict};
use crate::types::MsgType;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{self as std_mpsc, RecvTimeoutError};
use std::sync::Arc;
use std::time::{Duration, Instant};
use tokio::sync::{mpsc, oneshot};
use tracing::{info, warn};

/// How often unreachable boards are looked for again.
const RETRY: Duration = Duration::from_secs(1);

/// How a goal ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Outcome {
    Succeeded,
    Aborted,
    Canceled,
}

/// A goal's end: its outcome and its `FollowJointTrajectory_Result`.
pub(super) struct Ended {
    pub(super) outcome: Outcome,
    pub(super) result: Ros,
}

impl Ended {
    fn new(outcome: Outcome, v: &Verdict) -> Ended {
        Ended {
            outcome,
            result: v.result(),
        }
    }
}

enum Job {
    Start {
        id: GoalId,
        goal: Ros,
        done: oneshot::Sender<Ended>,
        feedback: mpsc::Sender<Ros>,
    },
    Cancel(GoalId),
}

/// The action server's handle on the controller thread.
pub(super) struct Controller {
    jobs: std_mpsc::Sender<Job>,
    ready: Arc<AtomicBool>,
}

impl Controller {
    /// Starts the thread of `name`'s controller; `prefix` names its client ports and
    /// `feedback` is the action's `_Feedback` type.
    pub(super) fn spawn(
        name: &str,
        prefix: &str,
        c: &TrajectoryController,
        feedback: &'static MsgType,
    ) -> std::io::Result<Controller> {
        let (jobs, rx) = std_mpsc::channel();
        let ready = Arc::new(AtomicBool::new(false));
        let thread = Thread {
            name: name.to_string(),
            prefix: prefix.to_string(),
            c: c.clone(),
            feedback,
            ready: ready.clone(),
        };
        std::thread::Builder::new()
            .name(format!("gw-follow-{name}"))
            .spawn(move || thread.run(rx))?;
        Ok(Controller { jobs, ready })
    }

    /// Whether the boards are open (goals are rejected while they are not).
    pub(super) fn ready(&self) -> bool {
        self.ready.load(Ordering::Relaxed)
    }

    /// Runs goal `id` to its end, sending feedback on `feedback`.
    pub(super) async fn run(&self, id: GoalId, goal: Ros, feedback: mpsc::Sender<Ros>) -> Ended {
        let (done, ended) = oneshot::channel();
        let job = Job::Start {
            id,
            goal,
            done,
            feedback,
        };
        let gone = Verdict {
            code: error_code::INVALID_GOAL,
            message: "the trajectory controller has stopped".into(),
        };
        if self.jobs.send(job).is_err() {
            return Ended::new(Outcome::Aborted, &gone);
        }
        ended
            .await
            .unwrap_or_else(|_| Ended::new(Outcome::Aborted, &gone))
    }

    /// Asks for goal `id` to stop (it ends CANCELED).
    pub(super) fn cancel(&self, id: GoalId) {
        let _ = self.jobs.send(Job::Cancel(id));
    }
}

/// The boards of a controller, their axes one after the other.
struct Group {
    boards: Vec<Board>,
    /// (board, its axis) of each axis of the group.
    axes: Vec<(usize, usize)>,
    info: BoardInfo,
    limits: Vec<(f64, f64)>,
    /// The axes the controller may move.
    controlled: Vec<usize>,
}

impl Group {
    fn open(prefix: &str, c: &TrajectoryController) -> Result<Group, OpenError> {
        let mut g = Group {
            boards: Vec::new(),
            axes: Vec::new(),
            info: BoardInfo::default(),
            limits: Vec::new(),
            controlled: Vec::new(),
        };
        for (b, remote) in c.boards.iter().enumerate() {
            let cb = ControlBoard {
                remote: remote.clone(),
                mode: c.mode,
                joints: Vec::new(),
            };
            let of = |e: OpenError| OpenError::Of {
                remote: remote.clone(),
                source: Box::new(e),
            };
            let mut board = Board::open(&format!("{prefix}{remote}"), &cb).map_err(of)?;
            let n = board.info.names.len();
            let lim = board
                .dev
                .device()
                .as_control_limits()
                .ok_or_else(|| of(OpenError::Missing("IControlLimits")))?;
            for j in 0..n {
                g.limits.push(lim.get_limits(j).map_err(|e| of(e.into()))?);
                g.axes.push((b, j));
            }
            g.info.names.extend(board.info.names.iter().cloned());
            g.info
                .prismatic
                .extend(board.info.prismatic.iter().copied());
            g.boards.push(board);
        }
        g.controlled = g.info.select(&c.joints)?;
        Ok(g)
    }

    /// Every axis's position (YARP units).
    fn positions(&mut self) -> Result<Vec<f64>, Failure> {
        let mut out = Vec::with_capacity(self.axes.len());
        for b in &mut self.boards {
            let e = b
                .dev
                .device()
                .as_encoders()
                .ok_or_else(|| missing("IEncoders"))?;
            out.extend(e.get_encoders().map_err(board_err)?);
        }
        Ok(out)
    }

    /// Every axis's velocity, if the boards stream them.
    fn velocities(&mut self) -> Option<Vec<f64>> {
        let mut out = Vec::with_capacity(self.axes.len());
        for b in &mut self.boards {
            out.extend(b.dev.device().as_encoders()?.get_encoder_speeds().ok()?);
        }
        Some(out)
    }

    /// Applies a group target, board by board.
    fn apply(&mut self, mode: Mode, t: &Target, speeds: &[Option<f64>]) -> Result<(), Failure> {
        for (b, board) in self.boards.iter_mut().enumerate() {
            let mut part = Target {
                joints: Vec::new(),
                values: Vec::new(),
            };
            let mut part_speeds = Vec::new();
            for (k, &j) in t.joints.iter().enumerate() {
                if let Some(&(jb, axis)) = self.axes.get(j) {
                    if jb == b {
                        part.joints.push(axis);
                        part.values.push(t.values[k]);
                        part_speeds.push(speeds.get(k).copied().flatten());
                    }
                }
            }
            if !part.joints.is_empty() {
                board.apply(mode, &part, &part_speeds)?;
            }
        }
        Ok(())
    }

    /// Stops `joints` where they are.
    fn stop(&mut self, mode: Mode, joints: &[usize]) -> Result<(), Failure> {
        if mode == Mode::PositionDirect {
            let now = self.positions()?;
            let t = Target {
                joints: joints.to_vec(),
                values: joints.iter().map(|&j| now[j]).collect(),
            };
            return self.apply(mode, &t, &[]);
        }
        for (b, board) in self.boards.iter_mut().enumerate() {
            let local: Vec<usize> = joints
                .iter()
                .filter_map(|&j| self.axes.get(j).filter(|(jb, _)| *jb == b).map(|x| x.1))
                .collect();
            if !local.is_empty() {
                board
                    .dev
                    .device()
                    .as_position_control()
                    .ok_or_else(|| missing("IPositionControl"))?
                    .stop_group(&local)
                    .map_err(board_err)?;
            }
        }
        Ok(())
    }

    fn close(self) {
        for mut b in self.boards {
            let _ = b.dev.close();
        }
    }
}

/// The goal being followed.
struct Active {
    id: GoalId,
    plan: Plan,
    /// The goal's joints' positions when it started.
    start: Vec<f64>,
    t0: Instant,
    /// Position mode: how many points have been sent.
    sent: usize,
    done: oneshot::Sender<Ended>,
    feedback: mpsc::Sender<Ros>,
}

struct Thread {
    name: String,
    prefix: String,
    c: TrajectoryController,
    feedback: &'static MsgType,
    ready: Arc<AtomicBool>,
}

impl Thread {
    fn run(self, jobs: std_mpsc::Receiver<Job>) {
        let period = Duration::from_secs_f64(1.0 / self.c.rate_hz);
        let mut group: Option<Group> = None;
        let mut active: Option<Active> = None;
        let mut next_open = Instant::now();
        let mut warned = false;
        loop {
            if group.is_none() && Instant::now() >= next_open {
                match Group::open(&self.prefix, &self.c) {
                    Ok(g) => {
                        info!(
                            "{}: trajectory controller on {:?} ({} joints: {:?})",
                            self.name,
                            self.c.boards,
                            g.controlled.len(),
                            g.controlled
                                .iter()
                                .map(|&j| &g.info.names[j])
                                .collect::<Vec<_>>()
                        );
                        group = Some(g);
                        warned = false;
                    }
                    Err(e) => {
                        if !warned {
                            warn!("{}: control boards: {e}", self.name);
                            warned = true;
                        }
                        next_open = Instant::now() + RETRY;
                    }
                }
                self.ready.store(group.is_some(), Ordering::Relaxed);
            }
            let wait = if active.is_some() { period } else { RETRY };
            match jobs.recv_timeout(wait) {
                Ok(Job::Start {
                    id,
                    goal,
                    done,
                    feedback,
                }) => {
                    if let Some(a) = active.take() {
                        let v = Verdict {
                            code: error_code::INVALID_GOAL,
                            message: trajectory::PREEMPTED.into(),
                        };
                        let _ = a.done.send(Ended::new(Outcome::Canceled, &v));
                    }
                    match group.as_mut() {
                        None => {
                            let v = Verdict {
                                code: error_code::INVALID_GOAL,
                                message: format!(
                                    "control boards {:?} not reachable",
                                    self.c.boards
                                ),
                            };
                            let _ = done.send(Ended::new(Outcome::Aborted, &v));
                        }
                        Some(g) => match self.start(g, id, &goal) {
                            Ok((plan, start)) => {
                                active = Some(Active {
                                    id,
                                    t0: Instant::now() + plan.delay,
                                    plan,
                                    start,
                                    sent: 0,
                                    done,
                                    feedback,
                                })
                            }
                            Err(v) => {
                                info!("{}: goal refused: {}", self.name, v.message);
                                let _ = done.send(Ended::new(Outcome::Aborted, &v));
                            }
                        },
                    }
                }
                Ok(Job::Cancel(id)) => {
                    if let (Some(g), Some(a)) = (group.as_mut(), active.as_ref()) {
                        if a.id == id {
                            if let Err(Failure::Board(e) | Failure::Message(e)) =
                                g.stop(self.c.mode, &a.plan.joints)
                            {
                                warn!("{}: stop: {e}", self.name);
                            }
                            if let Some(a) = active.take() {
                                let v = Verdict {
                                    code: error_code::SUCCESSFUL,
                                    message: trajectory::CANCELED.into(),
                                };
                                let _ = a.done.send(Ended::new(Outcome::Canceled, &v));
                            }
                        }
                    }
                }
                Err(RecvTimeoutError::Timeout) => {}
                Err(RecvTimeoutError::Disconnected) => break,
            }
            let (Some(g), Some(a)) = (group.as_mut(), active.as_mut()) else {
                continue;
            };
            match self.step(g, a) {
                Ok(None) => {}
                Ok(Some((ok, v))) => {
                    if !ok {
                        let _ = g.stop(self.c.mode, &a.plan.joints);
                    }
                    info!("{}: goal ended: {}", self.name, v.message);
                    if let Some(a) = active.take() {
                        let outcome = if ok {
                            Outcome::Succeeded
                        } else {
                            Outcome::Aborted
                        };
                        let _ = a.done.send(Ended::new(outcome, &v));
                    }
                }
                Err(f) => {
                    let (message, lost) = match f {
                        Failure::Message(e) => (format!("the boards refused: {e}"), false),
                        Failure::Board(e) => (format!("control board lost: {e}"), true),
                    };
                    warn!("{}: goal aborted: {message}", self.name);
                    if let Some(a) = active.take() {
                        let v = Verdict {
                            code: error_code::INVALID_GOAL,
                            message,
                        };
                        let _ = a.done.send(Ended::new(Outcome::Aborted, &v));
                    }
                    if lost {
                        if let Some(g) = group.take() {
                            g.close();
                        }
                        self.ready.store(false, Ordering::Relaxed);
                        next_open = Instant::now() + RETRY;
                    }
                }
            }
        }
        if let Some(a) = active {
            let v = Verdict {
                code: error_code::INVALID_GOAL,
                message: "the gateway is stopping".into(),
            };
            let _ = a.done.send(Ended::new(Outcome::Aborted, &v));
        }
        if let Some(g) = group {
            g.close();
        }
    }

    /// Checks a new goal and reads where its joints start.
    fn start(&self, g: &mut Group, id: GoalId, goal: &Ros) -> Result<(Plan, Vec<f64>), Verdict> {
        let plan = trajectory::plan(
            goal,
            &g.info,
            &g.controlled,
            &g.limits,
            &self.c.defaults(),
            super::now_ns(),
        )?;
        let now = g.positions().map_err(|f| Verdict {
            code: error_code::INVALID_GOAL,
            message: match f {
                Failure::Board(e) | Failure::Message(e) => format!("encoders: {e}"),
            },
        })?;
        let start = plan.joints.iter().map(|&j| now[j]).collect();
        info!(
            "{}: goal {:02x?}: {} points over {:.3} s for {:?}",
            self.name,
            &id[..4],
            plan.points.len(),
            plan.end().as_secs_f64(),
            plan.names
        );
        Ok((plan, start))
    }

    /// One period of the goal: command, feedback, tolerances.
    fn step(&self, g: &mut Group, a: &mut Active) -> Result<Option<(bool, Verdict)>, Failure> {
        let Some(t) = Instant::now().checked_duration_since(a.t0) else {
            return Ok(None); // a start in the future
        };
        let p = &a.plan;
        match self.c.mode {
            Mode::PositionDirect => {
                let d = p.sample(&a.start, t);
                g.apply(
                    Mode::PositionDirect,
                    &Target {
                        joints: p.joints.clone(),
                        values: d.positions,
                    },
                    &[],
                )?;
            }
            _ => {
                // Each segment starts when the previous point is due, at the speed that
                // ends it when its own point is due.
                while a.sent < p.points.len() {
                    let (from, since) = match a.sent.checked_sub(1) {
                        Some(k) => (&p.points[k].positions, p.points[k].at),
                        None => (&a.start, Duration::ZERO),
                    };
                    if t < since {
                        break;
                    }
                    let to = &p.points[a.sent];
                    let speeds =
                        joint_command::speeds(from.iter().copied(), &to.positions, to.at - since);
                    g.apply(
                        Mode::Position,
                        &Target {
                            joints: p.joints.clone(),
                            values: to.positions.clone(),
                        },
                        &speeds,
                    )?;
                    a.sent += 1;
                }
            }
        }
        let all = g.positions()?;
        let actual: Vec<f64> = p.joints.iter().map(|&j| all[j]).collect();
        let speeds = g
            .velocities()
            .map(|v| p.joints.iter().map(|&j| v[j]).collect::<Vec<f64>>());
        let desired = p.sample(&a.start, t);
        let _ = a.feedback.try_send(self.feedback_of(
            &g.info,
            p,
            t,
            &desired,
            &actual,
            speeds.as_deref(),
        ));
        Ok(p.check(&g.info, t, &desired, &actual, speeds.as_deref()))
    }

    /// The `_Feedback` message: desired, actual and error in ROS units (the `index`
    /// fields only where the release has them).
    fn feedback_of(
        &self,
        info: &BoardInfo,
        p: &Plan,
        t: Duration,
        desired: &Sample,
        actual: &[f64],
        speeds: Option<&[f64]>,
    ) -> Ros {
        let si = |v: &[f64]| -> Ros {
            Ros::List(
                p.joints
                    .iter()
                    .zip(v)
                    .map(|(&j, &x)| Ros::F64(info.to_si(j, x)))
                    .collect(),
            )
        };
        let at = Ros::Struct(vec![
            Ros::I32(t.as_secs() as i32),
            Ros::U32(t.subsec_nanos()),
        ]);
        let point = |pos: Ros, vel: Ros| {
            Ros::Struct(vec![
                pos,
                vel,
                Ros::List(Vec::new()),
                Ros::List(Vec::new()),
                at.clone(),
            ])
        };
        let diff =
            |a: &[f64], b: &[f64]| -> Vec<f64> { a.iter().zip(b).map(|(x, y)| x - y).collect() };
        let ty = self.feedback;
        let Some(mut m) = Ros::zero(ty.name) else {
            return Ros::Struct(Vec::new());
        };
        m.set(
            ty,
            "header",
            Ros::Struct(vec![Ros::time(super::now_ns()), Ros::Str(String::new())]),
        );
        m.set(
            ty,
            "joint_names",
            Ros::List(p.names.iter().cloned().map(Ros::Str).collect()),
        );
        m.set(
            ty,
            "desired",
            point(si(&desired.positions), si(&desired.velocities)),
        );
        let (vel, vel_err) = match speeds {
            Some(v) => (si(v), si(&diff(&desired.velocities, v))),
            None => (Ros::List(Vec::new()), Ros::List(Vec::new())),
        };
        m.set(ty, "actual", point(si(actual), vel));
        m.set(
            ty,
            "error",
            point(si(&diff(&desired.positions, actual)), vel_err),
        );
        m.set(ty, "index", Ros::I32(desired.index as i32));
        m
    }
}
