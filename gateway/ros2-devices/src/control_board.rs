//! `controlBoard_nws_ros2` (yarp-devices-ros2's `ControlBoard_nws_ros2`): serves an
//! attached control board to ROS 2.
//!
//! * `topic_name` — `sensor_msgs/JointState` every `period` (the board's axis names;
//!   revolute joints in rad and rad/s, prismatic ones as the board gives them; effort from
//!   `ITorqueControl`, zeros without it), stamped with the mean of the encoders' times;
//! * `topic_name/controlModes` — `std_msgs/Int8MultiArray`, each joint's control-mode
//!   vocab cut to 8 bits (as C++ does);
//! * with `msgs_name` (a leading `/` added if missing): the command topics
//!   `msgs_name/position`, `/position_direct`, `/velocity` (`yarp_control_msgs`
//!   Position, PositionDirect, Velocity: all joints or the named ones, in rad) and the
//!   services `msgs_name/get_joints_names`, `/get_modes`, `/set_modes`,
//!   `/get_available_modes`, `/get_position`, `/get_velocity`.
//!
//! Like C++ it publishes only while a subscriber is matched. Unlike C++, the command
//! endpoints exist from `open` (C++ makes them at attach, only for the interfaces the
//! board has); before a board is attached, or for an interface it lacks, commands are
//! dropped with a warning and services answer `INVALID`.

use crate::control_msgs::{self as cm, JointIndexes, JointNames, OnlyImplemented, SetModes};
use crate::node::{CommonParams, DeviceNode, NodeBuilder};
use crate::periodic::Periodic;
use futures::StreamExt;
use parking_lot::{Mutex, MutexGuard};
use ros2_client::{Publisher, Server};
use std::collections::HashMap;
use std::sync::Arc;
use std::time::Duration;
use tokio::task::JoinHandle;
use yarp_devices::vocabs::JOINTTYPE_PRISMATIC;
use yarp_devices::{DevResult, DeviceDriver, DeviceError, IWrapper, SharedDevice};
use yarp_ros2_gateway::counters::header;
use yarp_ros2_gateway::dynmsg::{MsgSeed, Value as Ros};

/// The device name.
pub const NAME: &str = "controlBoard_nws_ros2";

yarp_devices::device_params! {
    /// What `controlBoard_nws_ros2` reads (C++ `ControlBoard_nws_ros2_params.md`).
    pub struct ControlBoardNwsRos2Params for "controlBoard_nws_ros2" {
        /// set the name for ROS node
        node_name: String = required; check crate::node::node_name,
        /// optional namespace for ros2 node
        namespace: String = optional,
        /// set the name for ROS topic
        topic_name: String = required; check crate::node::topic_name,
        /// set the base name for the topics and interfaces (a leading '/' is added if
        /// missing); without it, the control related topics and services are not made
        msgs_name: String = optional,
        /// refresh period of the broadcasted values in s
        period: f64 = 0.02; "s"; check crate::node::period,
    }
}

/// How long a service answer waits for the client's reader (as the gateway's services).
const CLIENT_MATCH_TIMEOUT: Duration = Duration::from_secs(2);

/// The attached board, with what the wrapper learns from it once.
pub struct Board {
    device: SharedDevice,
    names: Vec<String>,
    /// Per joint: whether it is prismatic (not converted between degrees and radians).
    prismatic: Vec<bool>,
    index: HashMap<String, usize>,
}

type Slot = Arc<Mutex<Option<Arc<Board>>>>;

fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    m.lock()
}

impl Board {
    /// Reads the joint count, names and types (IEncoders and IAxisInfo are required, as
    /// in C++).
    pub fn read(device: SharedDevice) -> DevResult<Board> {
        let (names, prismatic) = {
            let mut pd = lock(&device);
            let dev = pd.device();
            let axes = dev
                .as_encoders()
                .ok_or(DeviceError::Unsupported(
                    "controlBoard_nws_ros2 needs a device with IEncoders",
                ))?
                .get_axes()?;
            if axes == 0 {
                return Err(DeviceError::Unsupported(
                    "controlBoard_nws_ros2: the attached device has no joints",
                ));
            }
            let info = dev.as_axis_info().ok_or(DeviceError::Unsupported(
                "controlBoard_nws_ros2 needs a device with IAxisInfo (every joint needs a name)",
            ))?;
            let mut names = Vec::with_capacity(axes);
            let mut prismatic = Vec::with_capacity(axes);
            for j in 0..axes {
                names.push(info.get_axis_name(j)?);
                prismatic.push(
                    info.get_joint_type(j)
                        .is_ok_and(|t| t == JOINTTYPE_PRISMATIC),
                );
            }
            (names, prismatic)
        };
        let index = names
            .iter()
            .enumerate()
            .map(|(i, n)| (n.clone(), i))
            .collect();
        Ok(Board {
            device,
            names,
            prismatic,
            index,
        })
    }

    pub fn axes(&self) -> usize {
        self.names.len()
    }

    /// Board units (degrees for revolute joints) to ROS units (radians).
    fn to_ros(&self, j: usize, v: f64) -> f64 {
        if self.prismatic[j] {
            v
        } else {
            v.to_radians()
        }
    }

    fn to_board(&self, j: usize, v: f64) -> f64 {
        if self.prismatic[j] {
            v
        } else {
            v.to_degrees()
        }
    }

    /// The joints `names` select (all when empty); `None` if one is unknown or there are
    /// more names than joints (C++ `namesCheck`).
    fn select(&self, names: &[String]) -> Option<Vec<usize>> {
        if names.len() > self.axes() {
            return None;
        }
        if names.is_empty() {
            return Some((0..self.axes()).collect());
        }
        names.iter().map(|n| self.index.get(n).copied()).collect()
    }
}

/// A command of the `yarp_control_msgs` topics, checked and in board units.
#[derive(Debug, Clone, PartialEq)]
pub struct Command {
    /// `None`: every joint, in order (the message named none).
    pub joints: Option<Vec<usize>>,
    pub values: Vec<f64>,
    /// Reference speeds (Position) or accelerations (Velocity); empty: unchanged.
    pub refs: Vec<f64>,
}

impl Board {
    /// C++ `messageVectorsCheck` and the unit conversion of the topic callbacks.
    pub fn command(
        &self,
        names: &[String],
        values: &[f64],
        refs: &[f64],
    ) -> Result<Command, CommandError> {
        let Some(joints) = self.select(names) else {
            return Err(CommandError::Names(names.to_vec()));
        };
        let n = self.axes();
        let all = names.is_empty() || names.len() == n;
        if values.is_empty() {
            return Err(CommandError::NoValues);
        }
        if !all && names.len() != values.len() {
            return Err(CommandError::Values(names.len(), values.len()));
        }
        if !refs.is_empty() && refs.len() != values.len() {
            return Err(CommandError::Refs(values.len(), refs.len()));
        }
        if all && values.len() != n {
            return Err(CommandError::Joints(values.len(), n));
        }
        let conv = |v: &[f64]| -> Vec<f64> {
            joints
                .iter()
                .zip(v)
                .map(|(&j, &x)| self.to_board(j, x))
                .collect()
        };
        Ok(Command {
            values: conv(values),
            refs: conv(refs),
            joints: (!names.is_empty()).then_some(joints),
        })
    }
}

/// Why a command message does not fit the board (C++ `messageVectorsCheck`).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CommandError {
    #[error("unknown joint names (or too many) in {0:?}")]
    Names(Vec<String>),
    #[error("no values")]
    NoValues,
    #[error("{0} names but {1} values")]
    Values(usize, usize),
    #[error("{0} values but {1} reference values")]
    Refs(usize, usize),
    #[error("{0} values for {1} joints")]
    Joints(usize, usize),
}

/// Why a command message was not applied.
#[derive(Debug, thiserror::Error)]
enum ApplyError {
    #[error("no board is attached")]
    NoBoard,
    #[error(transparent)]
    Command(#[from] CommandError),
    #[error("the board has no {0}")]
    Lacks(&'static str),
    #[error(transparent)]
    Device(#[from] DeviceError),
}

/// Which command topic a message came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Topic {
    Position,
    PositionDirect,
    Velocity,
}

impl Topic {
    fn ros_type(self) -> &'static str {
        match self {
            Topic::Position => "yarp_control_msgs/msg/Position",
            Topic::PositionDirect => "yarp_control_msgs/msg/PositionDirect",
            Topic::Velocity => "yarp_control_msgs/msg/Velocity",
        }
    }
    fn suffix(self) -> &'static str {
        match self {
            Topic::Position => "/position",
            Topic::PositionDirect => "/position_direct",
            Topic::Velocity => "/velocity",
        }
    }
}

fn strings(v: Option<&Ros>) -> Vec<String> {
    match v {
        Some(Ros::List(items)) => items
            .iter()
            .filter_map(|s| match s {
                Ros::Str(s) => Some(s.clone()),
                _ => None,
            })
            .collect(),
        _ => Vec::new(),
    }
}

fn floats(v: Option<&Ros>) -> Vec<f64> {
    match v {
        Some(Ros::List(items)) => items.iter().filter_map(Ros::as_f64).collect(),
        _ => Vec::new(),
    }
}

/// Applies one command message to the board.
fn apply(board: &Board, topic: Topic, msg: &Ros) -> Result<(), ApplyError> {
    let f = msg.fields().unwrap_or_default();
    let names = strings(f.first());
    let values = floats(f.get(1));
    let refs = floats(f.get(2));
    let c = board.command(&names, &values, &refs)?;
    let mut pd = lock(&board.device);
    let dev = pd.device();
    use ApplyError::Lacks;
    match topic {
        Topic::Position => {
            let p = dev.as_position_control().ok_or(Lacks("IPositionControl"))?;
            match &c.joints {
                None => {
                    if !c.refs.is_empty() {
                        p.set_ref_speeds(&c.refs)?;
                    }
                    p.position_moves(&c.values)?
                }
                Some(j) => {
                    if !c.refs.is_empty() {
                        p.set_ref_speed_group(j, &c.refs)?;
                    }
                    p.position_move_group(j, &c.values)?
                }
            }
        }
        Topic::PositionDirect => {
            let p = dev.as_position_direct().ok_or(Lacks("IPositionDirect"))?;
            match &c.joints {
                None => p.set_positions(&c.values)?,
                Some(j) => p.set_positions_group(j, &c.values)?,
            }
        }
        Topic::Velocity => {
            if !c.refs.is_empty() {
                // C++ sets them through IVelocityControl, which shares them with
                // IPositionControl; here they live on the latter.
                let p = dev
                    .as_position_control()
                    .ok_or(Lacks("reference accelerations"))?;
                match &c.joints {
                    None => p.set_ref_accelerations(&c.refs)?,
                    Some(j) => p.set_ref_acceleration_group(j, &c.refs)?,
                }
            }
            let v = dev.as_velocity_control().ok_or(Lacks("IVelocityControl"))?;
            match &c.joints {
                None => v.velocity_moves(&c.values)?,
                Some(j) => v.velocity_move_group(j, &c.values)?,
            }
        }
    }
    Ok(())
}

async fn serve_topic(sub: ros2_client::Subscription<Ros>, topic: Topic, slot: Slot, name: String) {
    let Some(seed) = MsgSeed::new(topic.ros_type()) else {
        return;
    };
    let stream = sub.async_stream_seed(seed);
    futures::pin_mut!(stream);
    while let Some(r) = stream.next().await {
        let msg = match r {
            Ok((m, _)) => m,
            Err(e) => {
                tracing::warn!("{name}: undecodable {}: {e:?}", topic.ros_type());
                continue;
            }
        };
        let board = lock(&slot).clone();
        let result = match board {
            None => Err(ApplyError::NoBoard),
            Some(b) => yarp_devices::runtime::device_call(|| apply(&b, topic, &msg)),
        };
        if let Err(e) = result {
            tracing::warn!("{name}: {} ignored: {e}", topic.ros_type());
        }
    }
}

async fn serve<Req, Resp>(
    server: Server<Req, Resp>,
    node: Arc<ros2_client::Node>,
    slot: Slot,
    handle: impl Fn(Option<&Board>, Req) -> Resp,
) where
    Req: ros2_client::Message + Clone + 'static,
    Resp: ros2_client::Message + 'static,
{
    loop {
        let (id, req) = match server.async_receive_request().await {
            Ok(x) => x,
            Err(e) => {
                tracing::debug!("{NAME}: service request: {e:?}");
                continue;
            }
        };
        let board = lock(&slot).clone();
        let resp = yarp_devices::runtime::device_call(|| handle(board.as_deref(), req));
        // A client's first request can come before our writer matched its reader.
        let _ = tokio::time::timeout(CLIENT_MATCH_TIMEOUT, server.wait_for_client(&node, id)).await;
        if let Err(e) = server.async_send_response(id, resp).await {
            tracing::debug!("{NAME}: service response: {e:?}");
        }
    }
}

fn get_joints_names(b: Option<&Board>, r: JointIndexes) -> cm::StringsOutcome {
    let Some(b) = b else {
        return cm::StringsOutcome::new(vec![], "INVALID");
    };
    if r.joint_indexes.len() > b.axes() {
        return cm::StringsOutcome::new(vec![], "SIZE_ERROR");
    }
    if r.joint_indexes.is_empty() {
        return cm::StringsOutcome::new(b.names.clone(), "OK");
    }
    let names: Option<Vec<String>> = r
        .joint_indexes
        .iter()
        .map(|&i| {
            usize::try_from(i)
                .ok()
                .and_then(|i| b.names.get(i).cloned())
        })
        .collect();
    match names {
        Some(n) => cm::StringsOutcome::new(n, "OK"),
        None => cm::StringsOutcome::new(vec![], "GET_NAME_ERROR"),
    }
}

fn get_available_modes(b: Option<&Board>, r: OnlyImplemented) -> cm::StringsOutcome {
    if b.is_none() {
        return cm::StringsOutcome::new(vec![], "INVALID");
    }
    let modes = if r.only_implemented {
        cm::IMPLEMENTED.iter().map(|s| s.to_string()).collect()
    } else {
        cm::settable_modes()
    };
    cm::StringsOutcome::new(modes, "OK")
}

fn get_modes(b: Option<&Board>, r: JointNames) -> cm::StringsOutcome {
    let Some(b) = b else {
        return cm::StringsOutcome::new(vec![], "INVALID");
    };
    let Some(joints) = b.select(&r.names) else {
        return cm::StringsOutcome::new(vec![], "NAMES_ERROR");
    };
    let mut pd = lock(&b.device);
    let Some(cmd) = pd.device().as_control_mode() else {
        return cm::StringsOutcome::new(vec![], "INVALID");
    };
    let mut modes = Vec::with_capacity(joints.len());
    for j in joints {
        match cmd.get_control_mode(j) {
            Ok(m) => modes.push(cm::mode_name(m).unwrap_or("UNKNOWN").to_string()),
            Err(_) => return cm::StringsOutcome::new(vec![], "RETRIEVE_ERROR"),
        }
    }
    cm::StringsOutcome::new(modes, "OK")
}

fn set_modes(b: Option<&Board>, r: SetModes) -> cm::Outcome {
    let Some(b) = b else {
        return cm::Outcome::new("INVALID");
    };
    let n = b.axes();
    let all = r.names.is_empty() || r.names.len() == n;
    let Some(joints) = b.select(&r.names) else {
        return cm::Outcome::new("INVALID");
    };
    if r.modes.is_empty() || (!all && r.names.len() != r.modes.len()) || (all && r.modes.len() != n)
    {
        return cm::Outcome::new("INVALID");
    }
    let mut pd = lock(&b.device);
    let Some(cmd) = pd.device().as_control_mode() else {
        return cm::Outcome::new("INVALID");
    };
    for (j, mode) in joints.into_iter().zip(&r.modes) {
        let Some(v) = cm::settable_mode(mode) else {
            // C++ logs the unknown mode and leaves `response` at its default
            return cm::Outcome::new(cm::NOT_SPECIFIED);
        };
        if cmd.set_control_mode(j, v).is_err() {
            return cm::Outcome::new("SET_ERROR");
        }
    }
    cm::Outcome::new("OK")
}

/// `GetPosition` (`speeds` false) and `GetVelocity`.
fn get_values(b: Option<&Board>, r: JointNames, speeds: bool) -> cm::ValuesOutcome {
    let Some(b) = b else {
        return cm::ValuesOutcome::new(vec![], "INVALID");
    };
    let Some(joints) = b.select(&r.names) else {
        return cm::ValuesOutcome::new(vec![], "NAMES_ERROR");
    };
    let mut pd = lock(&b.device);
    let Some(enc) = pd.device().as_encoders() else {
        return cm::ValuesOutcome::new(vec![], "RETRIEVE_ERROR");
    };
    let all = if speeds {
        enc.get_encoder_speeds()
    } else {
        enc.get_encoders()
    };
    match all {
        Ok(v) if v.len() == b.axes() => cm::ValuesOutcome::new(
            joints.into_iter().map(|j| b.to_ros(j, v[j])).collect(),
            "OK",
        ),
        _ => cm::ValuesOutcome::new(vec![], "RETRIEVE_ERROR"),
    }
}

/// One period's `JointState` and control modes of `b`.
fn read_state(b: &Board, stamp_now_ns: u64) -> DevResult<(Ros, Option<Ros>)> {
    let n = b.axes();
    let mut pd = lock(&b.device);
    let dev = pd.device();
    let enc = dev.as_encoders().ok_or(DeviceError::NotOpen)?;
    let (pos, times) = enc.get_encoders_timed()?;
    let vel = enc.get_encoder_speeds().unwrap_or_else(|_| vec![0.0; n]);
    let eff = dev
        .as_torque_control()
        .and_then(|t| t.get_torques().ok())
        .unwrap_or_else(|| vec![0.0; n]);
    let modes = dev
        .as_control_mode()
        .and_then(|c| c.get_control_modes().ok());
    drop(pd);
    if pos.len() != n {
        return Err(DeviceError::WrongSize {
            expected: n,
            got: pos.len(),
        });
    }
    let mean = times.iter().sum::<f64>() / n as f64;
    let stamp = if mean > 0.0 && mean.is_finite() {
        (mean * 1e9) as u64
    } else {
        stamp_now_ns
    };
    let list = |v: &[f64]| {
        Ros::List(
            (0..n)
                .map(|j| Ros::F64(b.to_ros(j, v.get(j).copied().unwrap_or(0.0))))
                .collect(),
        )
    };
    let state = Ros::Struct(vec![
        header(stamp, ""),
        Ros::List(b.names.iter().map(|s| Ros::Str(s.clone())).collect()),
        list(&pos),
        list(&vel),
        // effort is not converted
        Ros::List(
            (0..n)
                .map(|j| Ros::F64(eff.get(j).copied().unwrap_or(0.0)))
                .collect(),
        ),
    ]);
    let modes = modes.map(|m| {
        Ros::Struct(vec![
            Ros::Struct(vec![Ros::List(vec![]), Ros::U32(0)]),
            // C++ assigns each int vocab to an int8_t element
            Ros::List(m.iter().map(|v| Ros::I8(v.0 as i8)).collect()),
        ])
    });
    Ok((state, modes))
}

fn now_ns() -> u64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_nanos() as u64)
}

/// The periodic publisher thread (C++ `PeriodicThread::run`): the board's state, to
/// whichever of the two topics has a subscriber.
fn stream(
    board: Arc<Board>,
    node: Arc<ros2_client::Node>,
    state: Arc<Publisher<Ros>>,
    modes: Arc<Publisher<Ros>>,
    period: Duration,
    name: String,
) -> DevResult<Periodic> {
    Periodic::every(NAME, format!("{NAME} {name}"), period, move || {
        let want_state = state.get_subscription_count(&node) > 0;
        let want_modes = modes.get_subscription_count(&node) > 0;
        if !(want_state || want_modes) {
            return;
        }
        match read_state(&board, now_ns()) {
            Ok((st, md)) => {
                if want_state {
                    let _ = state.publish(st);
                }
                if let (true, Some(md)) = (want_modes, md) {
                    let _ = modes.publish(md);
                }
            }
            Err(e) => tracing::debug!("{NAME} {name}: {e}"),
        }
    })
}

struct Opened {
    params: CommonParams,
    node: DeviceNode,
    state: Arc<Publisher<Ros>>,
    modes: Arc<Publisher<Ros>>,
    slot: Slot,
    tasks: Vec<JoinHandle<()>>,
    streamer: Option<Periodic>,
}

impl Drop for Opened {
    fn drop(&mut self) {
        self.streamer = None;
        for t in &self.tasks {
            t.abort();
        }
    }
}

/// The `controlBoard_nws_ros2` driver.
#[derive(Default)]
pub struct ControlBoardNwsRos2 {
    opened: Option<Opened>,
}

impl ControlBoardNwsRos2 {
    pub fn new() -> Self {
        Self::default()
    }

    fn open_ros(config: &yarp_proto::Property) -> DevResult<Opened> {
        let ControlBoardNwsRos2Params {
            node_name,
            namespace,
            topic_name,
            msgs_name,
            period,
        } = ControlBoardNwsRos2Params::read(config)?;
        let params = CommonParams {
            period,
            node_name,
            namespace,
            topic_name,
        };
        let msgs_name = msgs_name.filter(|s| !s.is_empty()).map(|s| {
            if s.starts_with('/') {
                s
            } else {
                format!("/{s}")
            }
        });
        let mut b = NodeBuilder::new(NAME, params.namespace(), &params.node_name)?;
        let state = Arc::new(b.publisher(&params.topic_name, "sensor_msgs/msg/JointState")?);
        let modes = Arc::new(b.publisher(
            &format!("{}/controlModes", params.topic_name),
            "std_msgs/msg/Int8MultiArray",
        )?);
        let slot: Slot = Arc::new(Mutex::new(None));
        let mut subs = Vec::new();
        let mut servers = None;
        if let Some(m) = &msgs_name {
            for t in [Topic::Position, Topic::PositionDirect, Topic::Velocity] {
                subs.push((
                    t,
                    b.subscription(&format!("{m}{}", t.suffix()), t.ros_type())?,
                ));
            }
            let srv = |s: &str| format!("yarp_control_msgs/srv/{s}");
            servers = Some((
                b.server::<JointIndexes, cm::StringsOutcome>(
                    &format!("{m}/get_joints_names"),
                    &srv("GetJointsNames"),
                )?,
                b.server::<JointNames, cm::StringsOutcome>(
                    &format!("{m}/get_modes"),
                    &srv("GetControlModes"),
                )?,
                b.server::<SetModes, cm::Outcome>(
                    &format!("{m}/set_modes"),
                    &srv("SetControlModes"),
                )?,
                b.server::<OnlyImplemented, cm::StringsOutcome>(
                    &format!("{m}/get_available_modes"),
                    &srv("GetAvailableControlModes"),
                )?,
                b.server::<JointNames, cm::ValuesOutcome>(
                    &format!("{m}/get_position"),
                    &srv("GetPosition"),
                )?,
                b.server::<JointNames, cm::ValuesOutcome>(
                    &format!("{m}/get_velocity"),
                    &srv("GetVelocity"),
                )?,
            ));
        }
        let node = b.spin()?;
        let rt = yarp_devices::runtime::handle();
        let mut tasks = Vec::new();
        for (t, sub) in subs {
            tasks.push(rt.spawn(serve_topic(sub, t, slot.clone(), params.node_name.clone())));
        }
        if let Some((names, get, set, avail, pos, vel)) = servers {
            let n = &node.node;
            tasks.push(rt.spawn(serve(names, n.clone(), slot.clone(), get_joints_names)));
            tasks.push(rt.spawn(serve(get, n.clone(), slot.clone(), get_modes)));
            tasks.push(rt.spawn(serve(set, n.clone(), slot.clone(), set_modes)));
            tasks.push(rt.spawn(serve(avail, n.clone(), slot.clone(), get_available_modes)));
            tasks.push(rt.spawn(serve(pos, n.clone(), slot.clone(), |b, r| {
                get_values(b, r, false)
            })));
            tasks.push(rt.spawn(serve(vel, n.clone(), slot.clone(), |b, r| {
                get_values(b, r, true)
            })));
        }
        Ok(Opened {
            params,
            node,
            state,
            modes,
            slot,
            tasks,
            streamer: None,
        })
    }

    fn opened(&mut self) -> DevResult<&mut Opened> {
        self.opened.as_mut().ok_or(DeviceError::NotOpen)
    }
}

impl DeviceDriver for ControlBoardNwsRos2 {
    fn parameters(&self) -> Vec<yarp_devices::params::ParamSpec> {
        ControlBoardNwsRos2Params::PARAMS.to_vec()
    }

    fn open(&mut self, config: &yarp_proto::Property) -> DevResult<()> {
        self.opened = None;
        self.opened = Some(Self::open_ros(config)?);
        Ok(())
    }

    fn close(&mut self) -> DevResult<()> {
        self.opened = None;
        Ok(())
    }

    yarp_devices::views!(as_wrapper, as_multiple_wrapper);
}

impl IWrapper for ControlBoardNwsRos2 {
    fn attach(&mut self, device: SharedDevice) -> DevResult<()> {
        let o = self.opened()?;
        if lock(&o.slot).is_some() {
            return Err(DeviceError::Unsupported(
                "controlBoard_nws_ros2 already serves a device (detach it first)",
            ));
        }
        let board = Arc::new(Board::read(device)?);
        tracing::info!(
            "{NAME} {}: {} joints on {}",
            o.params.node_name,
            board.axes(),
            o.params.topic_name
        );
        *lock(&o.slot) = Some(board.clone());
        o.streamer = Some(stream(
            board,
            o.node.node.clone(),
            o.state.clone(),
            o.modes.clone(),
            o.params.period_duration(),
            o.params.node_name.clone(),
        )?);
        Ok(())
    }

    fn detach(&mut self) -> DevResult<()> {
        let o = self.opened()?;
        o.streamer = None;
        *lock(&o.slot) = None;
        Ok(())
    }
}

yarp_devices::one_device_multiple_wrapper!(
    ControlBoardNwsRos2,
    "controlBoard_nws_ros2 attaches exactly one device (join several with controlboardremapper)"
);

#[cfg(test)]
mod tests {
    use super::*;
    use yarp_devices::{shared, PolyDriver};
    use yarp_proto::Property;

    fn fake_board(axes: usize) -> Board {
        let c = Property::from_text(format!("(device fakeMotionControl) (axes {axes})"));
        Board::read(shared(PolyDriver::open(&c).expect("fakeMotionControl"))).unwrap()
    }

    #[test]
    fn command_errors_say_what_is_wrong() {
        let b = fake_board(3);
        let err = |names: &[&str], values: &[f64], refs: &[f64]| {
            let names: Vec<String> = names.iter().map(|s| s.to_string()).collect();
            b.command(&names, values, refs).unwrap_err().to_string()
        };
        let j0 = b.names[0].as_str();
        assert_eq!(
            err(&["nope"], &[1.0], &[]),
            r#"unknown joint names (or too many) in ["nope"]"#
        );
        assert_eq!(err(&[], &[], &[]), "no values");
        assert_eq!(err(&[j0], &[1.0, 2.0], &[]), "1 names but 2 values");
        assert_eq!(
            err(&[j0], &[1.0], &[1.0, 2.0]),
            "1 values but 2 reference values"
        );
        assert_eq!(err(&[], &[1.0], &[]), "1 values for 3 joints");
    }

    #[test]
    fn commands_are_checked_as_in_cpp_and_converted_to_degrees() {
        let b = fake_board(3);
        let n = |v: &[&str]| v.iter().map(|s| s.to_string()).collect::<Vec<_>>();
        let all = b
            .command(&[], &[0.0, std::f64::consts::FRAC_PI_2, 1.0], &[])
            .unwrap();
        assert_eq!(all.joints, None);
        assert!((all.values[1] - 90.0).abs() < 1e-9);
        let one = b
            .command(&n(&[&b.names[2]]), &[std::f64::consts::PI], &[0.1])
            .unwrap();
        assert_eq!(one.joints, Some(vec![2]));
        assert!((one.values[0] - 180.0).abs() < 1e-9);
        assert!((one.refs[0] - 0.1f64.to_degrees()).abs() < 1e-9);
        assert!(
            b.command(&[], &[1.0], &[]).is_err(),
            "all joints need all values"
        );
        assert!(b.command(&n(&["nope"]), &[1.0], &[]).is_err());
        assert!(b.command(&n(&[&b.names[0]]), &[], &[]).is_err());
        assert!(b.command(&n(&[&b.names[0]]), &[1.0], &[1.0, 2.0]).is_err());
    }

    #[test]
    fn services_answer_as_cpp() {
        let b = fake_board(2);
        let r = get_joints_names(Some(&b), JointIndexes::default());
        assert_eq!((r.values.len(), r.response.as_str()), (2, "OK"));
        let r = get_joints_names(
            Some(&b),
            JointIndexes {
                joint_indexes: vec![1],
            },
        );
        assert_eq!(r.values, vec![b.names[1].clone()]);
        let r = get_joints_names(
            Some(&b),
            JointIndexes {
                joint_indexes: vec![7],
            },
        );
        assert_eq!(r.response, "GET_NAME_ERROR");
        assert_eq!(
            get_joints_names(None, JointIndexes::default()).response,
            "INVALID"
        );
        let r = get_available_modes(
            Some(&b),
            OnlyImplemented {
                only_implemented: true,
            },
        );
        assert_eq!(r.values, cm::IMPLEMENTED);
        let set = set_modes(
            Some(&b),
            SetModes {
                names: vec![b.names[1].clone()],
                modes: vec!["VELOCITY".into()],
            },
        );
        assert_eq!(set.response, "OK");
        let r = get_modes(
            Some(&b),
            JointNames {
                names: vec![b.names[1].clone()],
            },
        );
        assert_eq!(
            (r.values, r.response.as_str()),
            (vec!["VELOCITY".to_string()], "OK")
        );
        let r = get_modes(
            Some(&b),
            JointNames {
                names: vec!["x".into()],
            },
        );
        assert_eq!(r.response, "NAMES_ERROR");
        let r = get_values(Some(&b), JointNames::default(), false);
        assert_eq!((r.values.len(), r.response.as_str()), (2, "OK"));
    }

    /// `string[] names, float64[] positions, float64[] ref_velocities` (Position.msg) in
    /// CDR, worked out by hand: what a client on this ROS layer puts on the wire.
    #[test]
    fn position_bytes_follow_the_msg_definition() {
        let m = Ros::Struct(vec![
            Ros::List(vec![Ros::Str("ab".into())]),
            Ros::List(vec![Ros::F64(1.5)]),
            Ros::List(vec![]),
        ]);
        assert!(m.conforms_to(Topic::Position.ros_type()));
        let bytes = cdr_encoding::to_vec::<_, byteorder::LittleEndian>(&m).unwrap();
        let mut want = vec![1, 0, 0, 0, 3, 0, 0, 0, b'a', b'b', 0]; // 1 name: "ab\0"
        want.extend([0, 1, 0, 0, 0]); // pad to 4, 1 position
        want.extend(1.5f64.to_le_bytes()); // at offset 16: 8-aligned already
        want.extend([0, 0, 0, 0]); // no reference velocities
        assert_eq!(bytes, want);
    }

    #[test]
    fn joint_state_has_the_catalog_layout() {
        let b = fake_board(4);
        let (st, modes) = read_state(&b, 5).unwrap();
        assert!(st.conforms_to("sensor_msgs/msg/JointState"), "{st:?}");
        assert!(modes.unwrap().conforms_to("std_msgs/msg/Int8MultiArray"));
    }
}
