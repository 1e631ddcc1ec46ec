//! Joint-command bridges: ROS messages -> a control board through `remote_controlboard`.
//!
//! Device interfaces are synchronous (as in C++), so each board is owned by a thread of
//! its own; the tokio task only hands ROS messages over a bounded channel (a full channel
//! counts a drop). The thread opens the board (retrying every second while it is not
//! there), learns axis names and types from IAxisInfo, decodes each message with
//! [`crate::joint_command`] and follows trajectories point by point. A board that stops
//! answering is closed and opened again on the next command.
//!
//! A board is open only while a ROS publisher is matched to the command topic (or a
//! trajectory is still being followed): an open `remote_controlboard` streams the board's
//! state to the gateway, which nobody needs while nobody commands. The board is opened
//! when a publisher appears (checked every [`RETRY`]) or, at the latest, by the first
//! command, and closed [`LINGER`] after the last publisher went away.

use crate::counters::Counters;
use crate::dynmsg::{MsgSeed, Value as Ros};
use crate::joint_command::{self, BoardInfo, Command, Mode, Target, TrajectoryPoint};
use crate::mapping::{ControlBoard, TopicEntry};
use futures::{pin_mut, StreamExt};
use ros2_client::{Node, Subscription};
use std::collections::VecDeque;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{self, Receiver, RecvTimeoutError, SyncSender, TrySendError};
use std::sync::Arc;
use std::time::{Duration, Instant};
use tracing::{debug, info, warn};
use yarp_devices::vocabs::{CM_POSITION, CM_POSITION_DIRECT, CM_VELOCITY, JOINTTYPE_PRISMATIC};
use yarp_devices::{DeviceError, PolyDriver};
use yarp_proto::Property;

/// How often an absent board is looked for again.
const RETRY: Duration = Duration::from_secs(1);
/// How long an idle board stays open after the command topic lost its last publisher.
const LINGER: Duration = Duration::from_secs(5);

/// Starts the board thread for entry `t`; returns the sender the ROS task feeds.
/// `wanted` says whether a ROS publisher is matched (kept by [`ros_to_board`]).
pub(super) fn spawn_board(
    t: &TopicEntry,
    c: Arc<Counters>,
    wanted: Arc<AtomicBool>,
) -> std::io::Result<SyncSender<Ros>> {
    let (tx, rx) = mpsc::sync_channel(t.qos.depth.max(1) as usize);
    let t = t.clone();
    std::thread::Builder::new()
        .name(format!("gw-board-{}", t.name))
        .spawn(move || board_thread(rx, t, c, wanted))?;
    Ok(tx)
}

/// ROS -> board: hands every received message to the board thread, and tells it
/// whether a publisher is matched (`wanted`).
pub(super) async fn ros_to_board(
    node: Arc<Node>,
    sub: Subscription<Ros>,
    tx: SyncSender<Ros>,
    wanted: Arc<AtomicBool>,
    t: TopicEntry,
    c: Arc<Counters>,
) {
    let Some(seed) = MsgSeed::new(&t.ros_type) else {
        return;
    };
    let stream = sub.async_stream_seed(seed);
    pin_mut!(stream);
    let mut tick = tokio::time::interval(RETRY);
    loop {
        let r = tokio::select! {
            r = stream.next() => match r {
                Some(r) => r,
                None => return,
            },
            _ = tick.tick() => {
                wanted.store(sub.get_publisher_count(&node) > 0, Ordering::Relaxed);
                continue;
            }
        };
        match r {
            Ok((m, _)) => match tx.try_send(m) {
                Ok(()) => {}
                Err(TrySendError::Full(_)) => {
                    warn!(
                        "{}: command not applied: the board is busy with earlier ones",
                        t.name
                    );
                    c.refused("the board is busy with earlier commands");
                }
                Err(TrySendError::Disconnected(_)) => return,
            },
            Err(e) => {
                debug!("{}: take: {e:?}", t.name);
                c.refused(format!("undecodable message: {e:?}"));
            }
        }
    }
}

/// An open board and what the gateway learned about it.
pub(super) struct Board {
    pub(super) dev: PolyDriver,
    pub(super) info: BoardInfo,
    /// Axes an unnamed message addresses.
    default_axes: Vec<usize>,
    /// Axes already switched to the entry's control mode.
    in_mode: Vec<bool>,
}

/// Why a command was not applied.
pub(super) enum Failure {
    /// The board is fine: the message does not fit it, or it refused the command.
    Message(String),
    /// The board did not answer or its connection broke (it is reopened).
    Board(String),
}

/// A board's error: only a board that is unreachable is reopened; a refusal (a joint in
/// fault, a mode it does not take) is reported and counted.
pub(super) fn board_err(e: DeviceError) -> Failure {
    if e.is_lost_peer() {
        Failure::Board(e.to_string())
    } else {
        Failure::Message(e.to_string())
    }
}

pub(super) fn missing(what: &str) -> Failure {
    Failure::Board(format!("remote_controlboard lacks {what}"))
}

/// Why a control board (or a trajectory controller's group of them) cannot be driven yet.
#[derive(Debug, thiserror::Error)]
pub(super) enum OpenError {
    #[error(transparent)]
    Config(#[from] yarp_proto::ParseError),
    #[error(transparent)]
    Device(#[from] DeviceError),
    #[error("no {0}")]
    Missing(&'static str),
    #[error(transparent)]
    Joints(#[from] joint_command::CommandError),
    /// One board of a group.
    #[error("{remote}: {source}")]
    Of {
        remote: String,
        source: Box<OpenError>,
    },
}

impl Board {
    pub(super) fn open(local: &str, cb: &ControlBoard) -> Result<Board, OpenError> {
        let text = format!(
            "device remote_controlboard\nremote {}\nlocal {local}\ncarrier tcp\n",
            cb.remote
        );
        let prop = Property::from_config_text(&text)?;
        let mut dev = PolyDriver::open(&prop)?;
        let d = dev.device();
        let axes = d
            .as_encoders()
            .ok_or(OpenError::Missing("IEncoders"))?
            .get_axes()?;
        let ai = d.as_axis_info().ok_or(OpenError::Missing("IAxisInfo"))?;
        let mut info = BoardInfo::default();
        for j in 0..axes {
            info.names.push(ai.get_axis_name(j)?);
            info.prismatic
                .push(ai.get_joint_type(j)? == JOINTTYPE_PRISMATIC);
        }
        let default_axes = info.select(&cb.joints)?;
        Ok(Board {
            dev,
            info,
            default_axes,
            in_mode: vec![false; axes],
        })
    }

    /// Switches `joints` to the control mode of `mode` (once per axis and connection).
    fn ensure_mode(&mut self, mode: Mode, joints: &[usize]) -> Result<(), Failure> {
        let todo: Vec<usize> = joints
            .iter()
            .copied()
            .filter(|&j| !self.in_mode[j])
            .collect();
        if todo.is_empty() {
            return Ok(());
        }
        let cm = match mode {
            Mode::Position => CM_POSITION,
            Mode::PositionDirect => CM_POSITION_DIRECT,
            Mode::Velocity => CM_VELOCITY,
        };
        self.dev
            .device()
            .as_control_mode()
            .ok_or_else(|| missing("IControlMode"))?
            .set_control_modes_group(&todo, &vec![cm; todo.len()])
            .map_err(board_err)?;
        for j in todo {
            self.in_mode[j] = true;
        }
        Ok(())
    }

    /// Sends one setpoint; `speeds` (position mode) first sets reference speeds.
    pub(super) fn apply(
        &mut self,
        mode: Mode,
        t: &Target,
        speeds: &[Option<f64>],
    ) -> Result<(), Failure> {
        self.ensure_mode(mode, &t.joints)?;
        let d = self.dev.device();
        match mode {
            // Streamed on command:o (`[dpog]`), as the C++ client does.
            Mode::PositionDirect => d
                .as_position_direct()
                .ok_or_else(|| missing("IPositionDirect"))?
                .set_positions_group(&t.joints, &t.values)
                .map_err(board_err),
            Mode::Velocity => d
                .as_velocity_control()
                .ok_or_else(|| missing("IVelocityControl"))?
                .velocity_move_group(&t.joints, &t.values)
                .map_err(board_err),
            _ => {
                let p = d
                    .as_position_control()
                    .ok_or_else(|| missing("IPositionControl"))?;
                let (js, vs): (Vec<usize>, Vec<f64>) = t
                    .joints
                    .iter()
                    .zip(speeds)
                    .filter_map(|(j, s)| s.map(|s| (*j, s)))
                    .unzip();
                if !js.is_empty() {
                    p.set_ref_speed_group(&js, &vs).map_err(board_err)?;
                }
                p.position_move_group(&t.joints, &t.values)
                    .map_err(board_err)
            }
        }
    }

    /// The board's positions now (YARP units), if the stream has them.
    fn positions(&mut self) -> Option<Vec<f64>> {
        self.dev.device().as_encoders()?.get_encoders().ok()
    }
}

/// A trajectory being followed.
struct Plan {
    start: Instant,
    points: VecDeque<TrajectoryPoint>,
    /// When the point before the next one was due (position mode moves start then).
    prev_at: Duration,
    /// Where the axes were last sent (YARP units, one per axis), for segment speeds.
    last: Vec<f64>,
}

impl Plan {
    /// When the next point must be sent: position mode starts each segment when the
    /// previous point is due (so the move ends on time); position-direct sends each
    /// point at its own time.
    fn due(&self, mode: Mode) -> Option<Instant> {
        let p = self.points.front()?;
        Some(
            self.start
                + if mode == Mode::Position {
                    self.prev_at
                } else {
                    p.at
                },
        )
    }
}

fn board_thread(rx: Receiver<Ros>, t: TopicEntry, c: Arc<Counters>, wanted: Arc<AtomicBool>) {
    let Some(cb) = t.control_board.clone() else {
        return;
    };
    let local = t.yarp_port.clone().unwrap_or_default();
    let mut board: Option<Board> = None;
    let mut next_open = Instant::now();
    let mut plan: Option<Plan> = None;
    let mut warned = false;
    // When the command topic last had a publisher (or a command came).
    let mut last_wanted = Instant::now();
    let mut first = true;
    loop {
        let mut want = wanted.load(Ordering::Relaxed) || plan.is_some();
        if want {
            last_wanted = Instant::now();
        }
        if board.is_some() && !want && last_wanted.elapsed() >= LINGER {
            if let Some(mut b) = board.take() {
                info!(
                    "{}: no ROS publisher: {} closed until one comes",
                    t.name, cb.remote
                );
                let _ = b.dev.close();
            }
        }
        // A command that arrives first opens the board on the spot.
        let pending = if board.is_none() && !want {
            match rx.recv_timeout(RETRY) {
                Ok(m) => {
                    want = true;
                    last_wanted = Instant::now();
                    Some(m)
                }
                Err(RecvTimeoutError::Timeout) => None,
                Err(RecvTimeoutError::Disconnected) => break,
            }
        } else {
            None
        };
        if board.is_none() && (want || first) && Instant::now() >= next_open {
            // The first attempt happens at start even without a publisher: a wrong
            // remote is reported at once, not at the first command.
            first = false;
            match Board::open(&local, &cb) {
                Ok(b) => {
                    info!(
                        "{}: driving {} ({} axes: {:?})",
                        t.name,
                        cb.remote,
                        b.info.names.len(),
                        b.info.names
                    );
                    board = Some(b);
                    warned = false;
                }
                Err(e) => {
                    if !warned {
                        warn!("{}: control board {}: {e}", t.name, cb.remote);
                        warned = true;
                    }
                    next_open = Instant::now() + RETRY;
                }
            }
        }
        let now = Instant::now();
        let mut wait = RETRY;
        if let Some(due) = plan.as_ref().and_then(|p| p.due(cb.mode)) {
            wait = wait.min(due.saturating_duration_since(now));
        }
        let next = match pending {
            Some(m) => Ok(m),
            None if board.is_none() && !want => continue,
            None => rx.recv_timeout(wait),
        };
        match next {
            Ok(m) => {
                let t0 = Instant::now();
                let Some(b) = board.as_mut() else {
                    let why = format!("control board {} not reachable yet", cb.remote);
                    warn!("{}: command not applied: {why}", t.name);
                    c.refused(why);
                    continue;
                };
                let cmd = joint_command::decode(&t.ros_type, &m, cb.mode, &b.info, &b.default_axes);
                let r = match cmd {
                    Err(e) => Err(Failure::Message(e.to_string())),
                    Ok(Command::Set(target)) => {
                        plan = None;
                        b.apply(cb.mode, &target, &[])
                    }
                    Ok(Command::Trajectory(points)) => {
                        let last = b.positions().unwrap_or_default();
                        plan = Some(Plan {
                            start: t0,
                            points: points.into(),
                            prev_at: Duration::ZERO,
                            last,
                        });
                        Ok(())
                    }
                };
                settle(&t.name, r, &c, t0, &mut board, &mut plan);
            }
            Err(RecvTimeoutError::Timeout) => {
                let (Some(b), Some(p)) = (board.as_mut(), plan.as_mut()) else {
                    continue;
                };
                if p.due(cb.mode).is_none_or(|d| d > Instant::now()) {
                    continue;
                }
                let Some(point) = p.points.pop_front() else {
                    continue;
                };
                let speeds = if cb.mode == Mode::Position {
                    joint_command::segment_speeds(&p.last, &point.target, point.at - p.prev_at)
                } else {
                    Vec::new()
                };
                let r = b.apply(cb.mode, &point.target, &speeds);
                if r.is_ok() {
                    for (&j, &x) in point.target.joints.iter().zip(&point.target.values) {
                        if let Some(slot) = p.last.get_mut(j) {
                            *slot = x;
                        }
                    }
                    p.prev_at = point.at;
                    if p.points.is_empty() {
                        plan = None;
                    }
                    continue; // the trajectory message was counted when it arrived
                }
                settle(&t.name, r, &c, Instant::now(), &mut board, &mut plan);
            }
            Err(RecvTimeoutError::Disconnected) => break,
        }
    }
    if let Some(mut b) = board {
        let _ = b.dev.close();
    }
}

/// Counts the outcome of one command; a board failure closes the board (reopened on
/// the next try) and abandons the trajectory.
fn settle(
    name: &str,
    r: Result<(), Failure>,
    c: &Counters,
    t0: Instant,
    board: &mut Option<Board>,
    plan: &mut Option<Plan>,
) {
    match r {
        Ok(()) => c.applied(t0.elapsed()),
        Err(Failure::Message(e)) => {
            warn!("{name}: command not applied: {e}");
            c.refused(e);
        }
        Err(Failure::Board(e)) => {
            warn!("{name}: command not applied: {e}; reconnecting");
            c.refused(e);
            *plan = None;
            if let Some(mut b) = board.take() {
                let _ = b.dev.close();
            }
        }
    }
}
