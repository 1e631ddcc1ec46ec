//! `remote_controlboard`: the client side of `controlBoard_nws_yarp`, a device whose
//! motor interfaces talk to a remote board as the C++ 3.12 client does.
//!
//! Parameters: [`RemoteControlBoardParams`] (C++'s names and defaults; `carrier` is for
//! the streamed state and commands, `timeout` the seconds after which that state is stale).
//!
//! Opening follows the recorded C++ sequence: ports `<local>/rpc:o`, `<local>/command:o`
//! and `<local>/stateExt:i`; rpc connected over tcp, command over `carrier`; the state
//! connected by the server port's admin protocol (`[list] [out]`, then `[add]
//! "<carrier>:/<local>/stateExt:i"`); then `[get] [prot]` (major version must match)
//! and `[get] [axes]`.
//!
//! Reads of positions, speeds, accelerations, motor positions/speeds/accelerations,
//! torques, duty cycles, currents and modes come from the last `stateExt` message (no
//! RPC); velocity, position-direct, torque, current and duty-cycle references go out on
//! `command:o` as `(head) (values)`; everything else is an RPC on `rpc:o`.

use crate::controlboard::{CommandMessage, JointData, PROTOCOL_VERSION_NUMBER};
use crate::driver::DeviceDriver;
use crate::error::{DevResult, DeviceError};
use crate::interfaces::*;
use crate::runtime;
use crate::vocabs::*;
use parking_lot::{Mutex, MutexGuard};
use std::sync::Arc;
use std::time::{Duration, Instant};
use yarp_net::nameserver::NameClient;
use yarp_net::port::Port;
use yarp_proto::{bottle, Bottle, Property, Stamp, Value, Vocab32};

/// The C++ device name.
pub const NAME: &str = "remote_controlboard";

/// Drivers of this family, by C++ name.
pub(crate) const DRIVERS: &[(&str, crate::driver::Factory)] =
    &[(NAME, || Box::new(RemoteControlBoard::new()))];

/// How long an RPC may wait for its reply before the call fails.
pub const RPC_TIMEOUT: Duration = Duration::from_secs(5);
/// Default staleness limit of the streamed state (C++ `timeout`).
pub const DEFAULT_TIMEOUT: Duration = Duration::from_millis(500);

const fn v(s: &str) -> i32 {
    Vocab32::new(s).0
}
const TORQUES_DIRECT: i32 = v("dtq");
const STATE_ERR: &str = "no fresh state from the remote control board (stateExt:i)";

/// A reply that is `[ok]` but lacks the value asked: the peer speaks another protocol.
fn bad_reply() -> DeviceError {
    DeviceError::failed(
        NAME,
        "the remote control board's reply lacks the value asked",
    )
}

/// The last state received on `<local>/stateExt:i`.
#[derive(Debug, Clone)]
struct Received {
    data: JointData,
    stamp: Option<Stamp>,
    at: Instant,
}

/// What `open` established.
struct Link {
    rpc: Arc<Port>,
    command: Arc<Port>,
    state: Arc<Port>,
    reader: tokio::task::JoinHandle<()>,
    latest: Arc<Mutex<Option<Received>>>,
    axes: usize,
    timeout: Duration,
    write_strict: bool,
    /// The remote control board's port prefix, named in errors.
    remote: String,
}

/// The `remote_controlboard` device.
#[derive(Default)]
pub struct RemoteControlBoard {
    link: Option<Link>,
}

fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    m.lock()
}

crate::device_params! {
    /// What `remote_controlboard` reads (C++ `RemoteControlBoard_params.md`; the QoS
    /// groups are declared but, as without root privileges, not applied).
    pub struct RemoteControlBoardParams for "remote_controlboard" {
        /// Prefix of the port to which to connect.
        remote: String = required,
        /// Port prefix of the port opened by this device.
        local: String = required,
        /// It can be 'on' or 'off'
        "writeStrict" write_strict: String = optional,
        /// carrier used for streaming robot state
        carrier: String = "udp",
        /// timeout for the input port which receives the streamed robot state
        timeout: f64 = 0.5; "s"; check crate::params::positive,
        /// Enable the usage of local Qos
        "local_qos::enable" local_qos_enable: bool = false,
        /// Local Qos. See https://yarp.it/latest/channelprioritization.html
        "local_qos::thread_priority" local_qos_thread_priority: i64 = 0,
        /// Local Qos. See https://yarp.it/latest/channelprioritization.html
        "local_qos::thread_policy" local_qos_thread_policy: i64 = 0,
        /// Local Qos. See https://yarp.it/latest/channelprioritization.html
        "local_qos::packet_priority" local_qos_packet_priority: String = optional,
        /// Enable the usage of remote Qos
        "remote_qos::enable" remote_qos_enable: bool = false,
        /// Remote Qos. See https://yarp.it/latest/channelprioritization.html
        "remote_qos::thread_priority" remote_qos_thread_priority: i64 = 0,
        /// Remote Qos. See https://yarp.it/latest/channelprioritization.html.
        "remote_qos::thread_policy" remote_qos_thread_policy: i64 = 0,
        /// Remote Qos. See https://yarp.it/latest/channelprioritization.html.
        "remote_qos::packet_priority" remote_qos_packet_priority: String = optional,
        /// For development purpose only
        "ignoreProtocolCheck" ignore_protocol_check: bool = false,
        /// For development purpose only
        diagnostic: bool = false,
    }
}

/// The settings read from the configuration.
struct Settings {
    remote: String,
    local: String,
    carrier: String,
    timeout: Duration,
    write_strict: bool,
    ignore_protocol: bool,
}

fn settings(config: &Property) -> DevResult<Settings> {
    let p = RemoteControlBoardParams::read(config)?;
    let bad = |param: &str, expected, got: String| DeviceError::BadParam {
        device: NAME.into(),
        param: param.into(),
        expected,
        got,
    };
    let write_strict = match p.write_strict.as_deref() {
        None | Some("off") => false,
        Some("on") => true,
        Some(other) => return Err(bad("writeStrict", "on or off", other.to_string())),
    };
    Ok(Settings {
        remote: crate::controlboard::port_prefix(&p.remote),
        local: crate::controlboard::port_prefix(&p.local),
        carrier: p.carrier,
        timeout: Duration::from_secs_f64(p.timeout),
        write_strict,
        ignore_protocol: p.ignore_protocol_check,
    })
}

/// C++ `CHECK_FAIL`: a reply is a failure when it is empty or starts with `[fail]`
/// (`[nak]` too: the command was not understood).
fn reply_ok(reply: &Bottle) -> bool {
    match reply.get(0) {
        None => false,
        Some(Value::Vocab32(x)) => x.0 != FAILED && x.0 != NAK,
        Some(_) => true,
    }
}

/// Opens the ports and runs the C++ connection sequence; returns the link. On failure
/// the ports opened so far are closed (unregistered) again.
async fn connect(s: Settings, ns: NameClient) -> Result<Link, String> {
    let local = &s.local;
    let mut ports: Vec<Arc<Port>> = Vec::new();
    for suffix in ["rpc:o", "command:o", "stateExt:i"] {
        let name = format!("{local}/{suffix}");
        match Port::open(&name, ns.clone()).await {
            Ok(p) => ports.push(Arc::new(p)),
            Err(e) => {
                close_ports(ports).await;
                return Err(format!("cannot open {name}: {e}"));
            }
        }
    }
    let (rpc, command, state) = (ports[0].clone(), ports[1].clone(), ports[2].clone());
    let latest = Arc::new(Mutex::new(None));
    let reader = tokio::spawn(read_state(state.clone(), latest.clone()));
    match handshake(&s, &ns, &rpc, &command, &state).await {
        Ok(axes) => Ok(Link {
            rpc,
            command,
            state,
            reader,
            latest,
            axes,
            timeout: s.timeout,
            write_strict: s.write_strict,
            remote: s.remote.clone(),
        }),
        Err(e) => {
            reader.abort();
            let _ = reader.await;
            drop((rpc, command, state));
            close_ports(ports).await;
            Err(e)
        }
    }
}

/// Closes ports no task holds any more.
async fn close_ports(ports: Vec<Arc<Port>>) {
    for p in ports {
        if let Ok(p) = Arc::try_unwrap(p) {
            p.close().await;
        }
    }
}

/// Connects the three ports to the server and checks protocol and axes; returns the
/// number of axes.
async fn handshake(
    s: &Settings,
    ns: &NameClient,
    rpc: &Arc<Port>,
    command: &Port,
    state: &Port,
) -> Result<usize, String> {
    let Settings {
        remote,
        local,
        carrier,
        ..
    } = s;
    let remote_rpc = format!("{remote}/rpc:i");
    rpc.connect(&remote_rpc, Some("tcp"))
        .await
        .map_err(|e| format!("cannot connect to {remote_rpc}: {e}"))?;
    let remote_cmd = format!("{remote}/command:i");
    command
        .connect(&remote_cmd, Some(carrier))
        .await
        .map_err(|e| format!("cannot connect to {remote_cmd} ({carrier}): {e}"))?;
    connect_state(ns, &format!("{remote}/stateExt:o"), state.name(), carrier).await?;
    let call = |cmd: Bottle| {
        let rpc = rpc.clone();
        let remote_rpc = remote_rpc.clone();
        async move {
            match tokio::time::timeout(RPC_TIMEOUT, rpc.rpc(&cmd)).await {
                Ok(Ok(r)) if reply_ok(&r) => Ok(r),
                Ok(Ok(r)) => Err(format!("{remote_rpc}: `{cmd}` answered `{r}`")),
                Ok(Err(e)) => Err(format!("{remote_rpc}: `{cmd}`: {e}")),
                Err(_) => Err(format!(
                    "{remote_rpc}: `{cmd}`: no reply in {RPC_TIMEOUT:?}"
                )),
            }
        }
    };
    let prot = call(bottle![Vocab32(GET), Vocab32(PROTOCOL_VERSION)]).await?;
    let (major, minor) = (
        prot.get(1).and_then(Value::as_i32),
        prot.get(2).and_then(Value::as_i32),
    );
    if major != Some(PROTOCOL_VERSION_NUMBER.0) {
        let msg = format!(
            "protocol version mismatch: the server speaks {prot}, this client {}.{}",
            PROTOCOL_VERSION_NUMBER.0, PROTOCOL_VERSION_NUMBER.1
        );
        if !s.ignore_protocol {
            return Err(msg);
        }
        tracing::warn!("{NAME} {local}: {msg} (ignored: ignoreProtocolCheck)");
    } else if minor != Some(PROTOCOL_VERSION_NUMBER.1) {
        tracing::warn!("{NAME} {local}: the server speaks protocol {prot}; minor versions differ");
    }
    let axes = call(bottle![Vocab32(GET), Vocab32(AXES)]).await?;
    axes.get(2)
        .and_then(Value::as_i64)
        .and_then(|n| usize::try_from(n).ok())
        .filter(|n| *n > 0)
        .ok_or_else(|| format!("{remote}: bad number of axes in `{axes}`"))
}

/// Connects `from` to our `to` as C++ `Network::connect` does: through `from`'s admin
/// port, asking first whether the connection exists (`[list] [out] "<to>"`).
async fn connect_state(ns: &NameClient, from: &str, to: &str, carrier: &str) -> Result<(), String> {
    let contact = ns
        .query(from)
        .await
        .map_err(|e| format!("name server: {e}"))?
        .ok_or_else(|| format!("{from} is not registered"))?;
    let list = bottle![Vocab32::new("list"), Vocab32::new("out"), to];
    let existing = yarp_net::network::admin_command(&contact, &list)
        .await
        .map_err(|e| format!("{from}: {e}"))?;
    if !existing.is_empty() {
        return Ok(());
    }
    let add = bottle![Vocab32::new("add"), format!("{carrier}:/{to}")];
    let reply = yarp_net::network::admin_command(&contact, &add)
        .await
        .map_err(|e| format!("{from}: {e}"))?;
    match reply.get(0).and_then(Value::as_i64) {
        Some(0) => Ok(()),
        _ => Err(format!("{from} refused the connection to {to}: {reply}")),
    }
}

/// Keeps the last valid `jointData` received.
async fn read_state(port: Arc<Port>, latest: Arc<Mutex<Option<Received>>>) {
    let mut warned = false;
    while let Some(msg) = port.read().await {
        let data = msg
            .bottle()
            .map_err(|e| e.to_string())
            .and_then(|b| JointData::from_bottle(&b).map_err(|e| e.to_string()));
        match data {
            Ok(data) => {
                *lock(&latest) = Some(Received {
                    data,
                    stamp: msg.stamp,
                    at: Instant::now(),
                })
            }
            Err(e) if !warned => {
                tracing::warn!(
                    "{}: ignoring a state message from {}: {e}",
                    port.name(),
                    msg.from
                );
                warned = true;
            }
            Err(_) => {}
        }
    }
}

impl RemoteControlBoard {
    pub fn new() -> Self {
        Self::default()
    }

    fn link(&self) -> DevResult<&Link> {
        self.link.as_ref().ok_or(DeviceError::NotOpen)
    }

    fn joint(&self, j: usize) -> DevResult<usize> {
        let axes = self.link()?.axes;
        if j < axes {
            Ok(j)
        } else {
            Err(DeviceError::InvalidJoint {
                joint: j as i64,
                axes,
            })
        }
    }

    /// Sends `cmd` on the RPC connection and returns the reply (C++ `rpc_p.write`);
    /// a `[fail]` reply or no reply is an error.
    pub fn call(&self, cmd: &Bottle) -> DevResult<Bottle> {
        let link = self.link()?;
        let reply =
            crate::nwc_ports::call_within(&link.remote, &link.rpc, cmd.clone(), RPC_TIMEOUT)?;
        if reply_ok(&reply) {
            return Ok(reply);
        }
        tracing::debug!("{NAME}: `{cmd}` answered `{reply}`");
        Err(self.refused(cmd))
    }

    /// The remote control board refused `cmd` (or answered it without what was asked).
    fn refused(&self, cmd: &Bottle) -> DeviceError {
        DeviceError::Refused {
            device: self
                .link
                .as_ref()
                .map_or_else(|| NAME.to_string(), |l| l.remote.clone()),
            command: cmd.to_string(),
        }
    }

    /// The number of axes, asked over RPC as C++ `getAxes` does (`[get] [axes]`).
    pub fn axes(&self) -> DevResult<usize> {
        let v = self.get_value(bottle![Vocab32(GET), Vocab32(AXES)])?;
        v.as_i64()
            .and_then(|n| usize::try_from(n).ok())
            .ok_or_else(bad_reply)
    }

    fn set(&self, cmd: Bottle) -> DevResult<()> {
        self.call(&cmd).map(|_| ())
    }

    /// A `get` whose value is the reply's third element (`[is] [xxx] value ...`).
    fn get_value(&self, cmd: Bottle) -> DevResult<Value> {
        let r = self.call(&cmd)?;
        r.get(2).cloned().ok_or_else(bad_reply)
    }

    fn get_f64(&self, cmd: Bottle) -> DevResult<f64> {
        self.get_value(cmd)?.as_f64().ok_or_else(bad_reply)
    }

    fn get_f64s(&self, cmd: Bottle) -> DevResult<Vec<f64>> {
        let v = self.get_value(cmd)?;
        v.as_list()
            .and_then(|l| l.iter().map(Value::as_f64).collect())
            .ok_or_else(bad_reply)
    }

    fn get_bool(&self, cmd: Bottle) -> DevResult<bool> {
        Ok(self.get_f64(cmd)? != 0.0)
    }

    /// Sends a streaming command on `command:o` (dropped if the connection is busy,
    /// unless `writeStrict on`).
    fn stream(&self, head: Bottle, body: Vec<f64>) -> DevResult<()> {
        let link = self.link()?;
        let msg = CommandMessage::new(head, body).to_bottle();
        if link.write_strict {
            let port = link.command.clone();
            runtime::block_on(async move { port.write_strict(&msg, None).await });
        } else {
            link.command.write_nowait(&msg, None);
        }
        Ok(())
    }

    /// An "all joints" command needs one value per joint.
    fn check_all(&self, values: &[f64]) -> DevResult<()> {
        let axes = self.link()?.axes;
        if values.len() == axes {
            Ok(())
        } else {
            Err(DeviceError::WrongSize {
                expected: axes,
                got: values.len(),
            })
        }
    }

    /// Reads from the last fresh state; `f` picks the value (None = not valid).
    fn state<T>(&self, f: impl FnOnce(&JointData, Option<Stamp>) -> Option<T>) -> DevResult<T> {
        let link = self.link()?;
        let latest = lock(&link.latest);
        let r = latest
            .as_ref()
            .filter(|r| r.at.elapsed() <= link.timeout)
            .ok_or_else(|| DeviceError::failed(&link.remote, STATE_ERR))?;
        f(&r.data, r.stamp).ok_or_else(|| DeviceError::failed(&link.remote, STATE_ERR))
    }

    fn state_vec(
        &self,
        pick: fn(&JointData) -> &crate::controlboard::Channel<f64>,
    ) -> DevResult<Vec<f64>> {
        self.state(|d, _| {
            let c = pick(d);
            c.valid.then(|| c.values.clone())
        })
    }

    fn state_one(
        &self,
        j: usize,
        pick: fn(&JointData) -> &crate::controlboard::Channel<f64>,
    ) -> DevResult<f64> {
        let j = self.joint(j)?;
        self.state(|d, _| {
            let c = pick(d);
            c.values.get(j).copied().filter(|_| c.valid)
        })
    }

    /// The stamp of the last state received (C++ `IPreciselyTimed::getLastInputStamp`).
    pub fn last_input_stamp(&self) -> Option<Stamp> {
        let link = self.link.as_ref()?;
        lock(&link.latest).as_ref().and_then(|r| r.stamp)
    }
}

fn joints_value(joints: &[usize]) -> Value {
    Value::List(joints.iter().map(|j| *j as i32).collect())
}
fn floats_value(v: &[f64]) -> Value {
    Value::List(v.iter().copied().collect())
}
fn vocabs_value(v: &[Vocab32]) -> Value {
    Value::List(v.iter().copied().collect())
}
fn j32(j: usize) -> i32 {
    j as i32
}

impl DeviceDriver for RemoteControlBoard {
    fn parameters(&self) -> Vec<crate::params::ParamSpec> {
        RemoteControlBoardParams::PARAMS.to_vec()
    }

    fn open(&mut self, config: &Property) -> DevResult<()> {
        let s = settings(config)?;
        let remote = s.remote.clone();
        let unreachable = |e: String| DeviceError::BadParam {
            device: NAME.into(),
            param: "remote".into(),
            expected: "the port prefix of a running controlBoard_nws_yarp",
            got: format!("{remote}: {e}"),
        };
        let ns = yarp_net::network::name_client().map_err(|e| unreachable(e.to_string()))?;
        let link = runtime::block_on(connect(s, ns)).map_err(unreachable)?;
        self.close()?;
        self.link = Some(link);
        Ok(())
    }

    fn close(&mut self) -> DevResult<()> {
        if let Some(link) = self.link.take() {
            link.reader.abort();
            runtime::block_on(async move {
                let _ = link.reader.await;
                close_ports(vec![link.rpc, link.command, link.state]).await;
            });
        }
        Ok(())
    }

    crate::motor_control_views!();

    crate::views!(as_remote_calibrator);
}

impl Drop for RemoteControlBoard {
    fn drop(&mut self) {
        let _ = self.close();
    }
}

impl IEncoders for RemoteControlBoard {
    fn get_axes(&mut self) -> DevResult<usize> {
        self.axes()
    }
    fn get_encoder(&mut self, j: usize) -> DevResult<f64> {
        self.state_one(j, |d| &d.joint_position)
    }
    fn get_encoder_speed(&mut self, j: usize) -> DevResult<f64> {
        self.state_one(j, |d| &d.joint_velocity)
    }
    fn get_encoder_acceleration(&mut self, j: usize) -> DevResult<f64> {
        self.state_one(j, |d| &d.joint_acceleration)
    }
    fn get_encoder_timed(&mut self, j: usize) -> DevResult<(f64, f64)> {
        let j = self.joint(j)?;
        self.state(|d, stamp| {
            let c = &d.joint_position;
            let t = stamp.map_or(0.0, |s| s.time);
            c.values.get(j).copied().filter(|_| c.valid).map(|p| (p, t))
        })
    }
    fn set_encoder(&mut self, j: usize, value: f64) -> DevResult<()> {
        self.set(bottle![Vocab32(SET), Vocab32(ENCODER), j32(j), value])
    }
    fn reset_encoder(&mut self, j: usize) -> DevResult<()> {
        self.set(bottle![Vocab32(SET), Vocab32(E_RESET), j32(j)])
    }
    fn reset_encoders(&mut self) -> DevResult<()> {
        self.set(bottle![Vocab32(SET), Vocab32(E_RESETS)])
    }
    fn set_encoders(&mut self, values: &[f64]) -> DevResult<()> {
        self.set(bottle![
            Vocab32(SET),
            Vocab32(ENCODERS),
            floats_value(values)
        ])
    }
    fn get_encoders(&mut self) -> DevResult<Vec<f64>> {
        self.state_vec(|d| &d.joint_position)
    }
    fn get_encoder_speeds(&mut self) -> DevResult<Vec<f64>> {
        self.state_vec(|d| &d.joint_velocity)
    }
    fn get_encoder_accelerations(&mut self) -> DevResult<Vec<f64>> {
        self.state_vec(|d| &d.joint_acceleration)
    }
    fn get_encoders_timed(&mut self) -> DevResult<(Vec<f64>, Vec<f64>)> {
        self.state(|d, stamp| {
            let c = &d.joint_position;
            let t = stamp.map_or(0.0, |s| s.time);
            c.valid.then(|| (c.values.clone(), vec![t; c.values.len()]))
        })
    }
}

impl IPositionControl for RemoteControlBoard {
    fn get_axes(&mut self) -> DevResult<usize> {
        self.axes()
    }
    fn position_move(&mut self, j: usize, target: f64) -> DevResult<()> {
        self.set(bottle![
            Vocab32(SET),
            Vocab32(POSITION_MOVE),
            j32(j),
            target
        ])
    }
    fn relative_move(&mut self, j: usize, delta: f64) -> DevResult<()> {
        self.set(bottle![Vocab32(SET), Vocab32(RELATIVE_MOVE), j32(j), delta])
    }
    fn check_motion_done(&mut self, j: usize) -> DevResult<bool> {
        self.get_bool(bottle![Vocab32(GET), Vocab32(MOTION_DONE), j32(j)])
    }
    fn set_ref_speed(&mut self, j: usize, speed: f64) -> DevResult<()> {
        self.set(bottle![Vocab32(SET), Vocab32(REF_SPEED), j32(j), speed])
    }
    fn set_ref_acceleration(&mut self, j: usize, acc: f64) -> DevResult<()> {
        self.set(bottle![
            Vocab32(SET),
            Vocab32(REF_ACCELERATION),
            j32(j),
            acc
        ])
    }
    fn get_ref_speed(&mut self, j: usize) -> DevResult<f64> {
        self.get_f64(bottle![Vocab32(GET), Vocab32(REF_SPEED), j32(j)])
    }
    fn get_ref_acceleration(&mut self, j: usize) -> DevResult<f64> {
        self.get_f64(bottle![Vocab32(GET), Vocab32(REF_ACCELERATION), j32(j)])
    }
    fn stop(&mut self, j: usize) -> DevResult<()> {
        self.set(bottle![Vocab32(SET), Vocab32(STOP), j32(j)])
    }
    fn get_target_position(&mut self, j: usize) -> DevResult<f64> {
        self.get_f64(bottle![Vocab32(GET), Vocab32(POSITION_MOVE), j32(j)])
    }
    fn position_moves(&mut self, targets: &[f64]) -> DevResult<()> {
        self.set(bottle![
            Vocab32(SET),
            Vocab32(POSITION_MOVES),
            floats_value(targets)
        ])
    }
    fn position_move_group(&mut self, joints: &[usize], targets: &[f64]) -> DevResult<()> {
        self.set(bottle![
            Vocab32(SET),
            Vocab32(POSITION_MOVE_GROUP),
            joints.len() as i32,
            joints_value(joints),
            floats_value(targets)
        ])
    }
    fn relative_moves(&mut self, deltas: &[f64]) -> DevResult<()> {
        self.set(bottle![
            Vocab32(SET),
            Vocab32(RELATIVE_MOVES),
            floats_value(deltas)
        ])
    }
    fn relative_move_group(&mut self, joints: &[usize], deltas: &[f64]) -> DevResult<()> {
        self.set(bottle![
            Vocab32(SET),
            Vocab32(RELATIVE_MOVE_GROUP),
            joints.len() as i32,
            joints_value(joints),
            floats_value(deltas)
        ])
    }
    fn check_motion_dones(&mut self) -> DevResult<bool> {
        self.get_bool(bottle![Vocab32(GET), Vocab32(MOTION_DONES)])
    }
    fn check_motion_done_group(&mut self, joints: &[usize]) -> DevResult<bool> {
        self.get_bool(bottle![
            Vocab32(GET),
            Vocab32(MOTION_DONE_GROUP),
            joints.len() as i32,
            joints_value(joints)
        ])
    }
    fn set_ref_speeds(&mut self, speeds: &[f64]) -> DevResult<()> {
        self.set(bottle![
            Vocab32(SET),
            Vocab32(REF_SPEEDS),
            floats_value(speeds)
        ])
    }
    fn set_ref_speed_group(&mut self, joints: &[usize], speeds: &[f64]) -> DevResult<()> {
        self.set(bottle![
            Vocab32(SET),
            Vocab32(REF_SPEED_GROUP),
            joints.len() as i32,
            joints_value(joints),
            floats_value(speeds)
        ])
    }
    fn set_ref_accelerations(&mut self, accs: &[f64]) -> DevResult<()> {
        self.set(bottle![
            Vocab32(SET),
            Vocab32(REF_ACCELERATIONS),
            floats_value(accs)
        ])
    }
    fn set_ref_acceleration_group(&mut self, joints: &[usize], accs: &[f64]) -> DevResult<()> {
        self.set(bottle![
            Vocab32(SET),
            Vocab32(REF_ACCELERATION_GROUP),
            joints.len() as i32,
            joints_value(joints),
            floats_value(accs)
        ])
    }
    fn get_ref_speeds(&mut self) -> DevResult<Vec<f64>> {
        self.get_f64s(bottle![Vocab32(GET), Vocab32(REF_SPEEDS)])
    }
    fn get_ref_accelerations(&mut self) -> DevResult<Vec<f64>> {
        self.get_f64s(bottle![Vocab32(GET), Vocab32(REF_ACCELERATIONS)])
    }
    fn stops(&mut self) -> DevResult<()> {
        self.set(bottle![Vocab32(SET), Vocab32(STOPS)])
    }
    fn stop_group(&mut self, joints: &[usize]) -> DevResult<()> {
        self.set(bottle![
            Vocab32(SET),
            Vocab32(STOP_GROUP),
            joints.len() as i32,
            joints_value(joints)
        ])
    }
    fn get_target_positions(&mut self) -> DevResult<Vec<f64>> {
        self.get_f64s(bottle![Vocab32(GET), Vocab32(POSITION_MOVES)])
    }
    fn get_target_position_group(&mut self, joints: &[usize]) -> DevResult<Vec<f64>> {
        self.get_f64s(bottle![
            Vocab32(GET),
            Vocab32(POSITION_MOVE_GROUP),
            joints.len() as i32,
            joints_value(joints)
        ])
    }
}

impl IVelocityControl for RemoteControlBoard {
    fn get_axes(&mut self) -> DevResult<usize> {
        self.axes()
    }
    fn velocity_move(&mut self, j: usize, speed: f64) -> DevResult<()> {
        let j = self.joint(j)?;
        self.stream(bottle![Vocab32(VELOCITY_MOVE), j32(j)], vec![speed])
    }
    fn get_ref_velocity(&mut self, j: usize) -> DevResult<f64> {
        self.get_f64(bottle![Vocab32(GET), Vocab32(VELOCITY_MOVE), j32(j)])
    }
    fn velocity_moves(&mut self, speeds: &[f64]) -> DevResult<()> {
        self.check_all(speeds)?;
        self.stream(bottle![Vocab32(VELOCITY_MOVES)], speeds.to_vec())
    }
    fn velocity_move_group(&mut self, joints: &[usize], speeds: &[f64]) -> DevResult<()> {
        check_group(joints, speeds)?;
        self.stream(
            bottle![
                Vocab32(VELOCITY_MOVE_GROUP),
                joints.len() as i32,
                joints_value(joints)
            ],
            speeds.to_vec(),
        )
    }
    fn get_ref_velocities(&mut self) -> DevResult<Vec<f64>> {
        self.get_f64s(bottle![Vocab32(GET), Vocab32(VELOCITY_MOVES)])
    }
}

impl IControlMode for RemoteControlBoard {
    fn get_axes(&mut self) -> DevResult<usize> {
        self.axes()
    }
    fn get_control_mode(&mut self, j: usize) -> DevResult<Vocab32> {
        let j = self.joint(j)?;
        self.state(|d, _| {
            let c = &d.control_mode;
            c.values.get(j).copied().filter(|_| c.valid).map(Vocab32)
        })
    }
    fn set_control_mode(&mut self, j: usize, mode: Vocab32) -> DevResult<()> {
        self.set(bottle![
            Vocab32(SET),
            Vocab32(ICONTROLMODE),
            Vocab32(CM_CONTROL_MODE),
            j32(j),
            mode
        ])
    }
    fn get_control_modes(&mut self) -> DevResult<Vec<Vocab32>> {
        self.state(|d, _| {
            let c = &d.control_mode;
            c.valid
                .then(|| c.values.iter().copied().map(Vocab32).collect())
        })
    }
    fn set_control_modes(&mut self, modes: &[Vocab32]) -> DevResult<()> {
        self.set(bottle![
            Vocab32(SET),
            Vocab32(ICONTROLMODE),
            Vocab32(CM_CONTROL_MODES),
            vocabs_value(modes)
        ])
    }
    fn set_control_modes_group(&mut self, joints: &[usize], modes: &[Vocab32]) -> DevResult<()> {
        self.set(bottle![
            Vocab32(SET),
            Vocab32(ICONTROLMODE),
            Vocab32(CM_CONTROL_MODE_GROUP),
            joints.len() as i32,
            joints_value(joints),
            vocabs_value(modes)
        ])
    }
}

impl IInteractionMode for RemoteControlBoard {
    fn get_axes(&mut self) -> DevResult<usize> {
        self.axes()
    }
    fn get_interaction_mode(&mut self, j: usize) -> DevResult<Vocab32> {
        let j = self.joint(j)?;
        self.state(|d, _| {
            let c = &d.interaction_mode;
            c.values.get(j).copied().filter(|_| c.valid).map(Vocab32)
        })
    }
    fn set_interaction_mode(&mut self, j: usize, mode: Vocab32) -> DevResult<()> {
        self.set(bottle![
            Vocab32(SET),
            Vocab32(INTERACTION_MODE_IFACE),
            Vocab32(INTERACTION_MODE),
            j32(j),
            mode
        ])
    }
    fn get_interaction_modes(&mut self) -> DevResult<Vec<Vocab32>> {
        self.state(|d, _| {
            let c = &d.interaction_mode;
            c.valid
                .then(|| c.values.iter().copied().map(Vocab32).collect())
        })
    }
    fn set_interaction_modes(&mut self, modes: &[Vocab32]) -> DevResult<()> {
        self.set(bottle![
            Vocab32(SET),
            Vocab32(INTERACTION_MODE_IFACE),
            Vocab32(INTERACTION_MODES),
            vocabs_value(modes)
        ])
    }
    fn set_interaction_modes_group(
        &mut self,
        joints: &[usize],
        modes: &[Vocab32],
    ) -> DevResult<()> {
        self.set(bottle![
            Vocab32(SET),
            Vocab32(INTERACTION_MODE_IFACE),
            Vocab32(INTERACTION_MODE_GROUP),
            joints.len() as i32,
            joints_value(joints),
            vocabs_value(modes)
        ])
    }
}

impl IAxisInfo for RemoteControlBoard {
    fn get_axis_name(&mut self, j: usize) -> DevResult<String> {
        let v = self.get_value(bottle![Vocab32(GET), Vocab32(INFO_NAME), j32(j)])?;
        v.as_str().map(str::to_string).ok_or_else(bad_reply)
    }
    fn get_joint_type(&mut self, j: usize) -> DevResult<Vocab32> {
        let v = self.get_value(bottle![Vocab32(GET), Vocab32(INFO_TYPE), j32(j)])?;
        v.as_i32()
            .or_else(|| v.as_vocab().map(|x| x.0))
            .map(Vocab32)
            .ok_or_else(bad_reply)
    }
}

impl IControlLimits for RemoteControlBoard {
    fn set_limits(&mut self, j: usize, min: f64, max: f64) -> DevResult<()> {
        self.set(bottle![Vocab32(SET), Vocab32(LIMITS), j32(j), min, max])
    }
    fn get_limits(&mut self, j: usize) -> DevResult<(f64, f64)> {
        let r = self.call(&bottle![Vocab32(GET), Vocab32(LIMITS), j32(j)])?;
        two_numbers(&r)
    }
    fn set_vel_limits(&mut self, j: usize, min: f64, max: f64) -> DevResult<()> {
        self.set(bottle![Vocab32(SET), Vocab32(VEL_LIMITS), j32(j), min, max])
    }
    fn get_vel_limits(&mut self, j: usize) -> DevResult<(f64, f64)> {
        let r = self.call(&bottle![Vocab32(GET), Vocab32(VEL_LIMITS), j32(j)])?;
        two_numbers(&r)
    }
}

/// `[is] [xxx] a b ...` -> (a, b).
fn two_numbers(r: &Bottle) -> DevResult<(f64, f64)> {
    match (
        r.get(2).and_then(Value::as_f64),
        r.get(3).and_then(Value::as_f64),
    ) {
        (Some(a), Some(b)) => Ok((a, b)),
        _ => Err(bad_reply()),
    }
}

impl ITorqueControl for RemoteControlBoard {
    fn get_axes(&mut self) -> DevResult<usize> {
        self.axes()
    }
    fn get_torque(&mut self, j: usize) -> DevResult<f64> {
        self.state_one(j, |d| &d.torque)
    }
    fn set_ref_torque(&mut self, j: usize, t: f64) -> DevResult<()> {
        let j = self.joint(j)?;
        self.stream(bottle![Vocab32(TORQUES_DIRECT), j32(j)], vec![t])
    }
    fn get_ref_torque(&mut self, j: usize) -> DevResult<f64> {
        self.get_f64(bottle![Vocab32(GET), Vocab32(TORQUE), Vocab32(REF), j32(j)])
    }
    fn get_torques(&mut self) -> DevResult<Vec<f64>> {
        self.state_vec(|d| &d.torque)
    }
    fn get_torque_range(&mut self, j: usize) -> DevResult<(f64, f64)> {
        let r = self.call(&bottle![
            Vocab32(GET),
            Vocab32(TORQUE),
            Vocab32(RANGE),
            j32(j)
        ])?;
        two_numbers(&r)
    }
}

impl IMotorEncoders for RemoteControlBoard {
    fn get_num_of_motor_encoders(&mut self) -> DevResult<usize> {
        let v = self.get_value(bottle![Vocab32(GET), Vocab32(MOTOR_ENCODER_NUMBER)])?;
        v.as_i64()
            .and_then(|n| usize::try_from(n).ok())
            .ok_or_else(bad_reply)
    }
    fn get_motor_encoder(&mut self, m: usize) -> DevResult<f64> {
        self.state_one(m, |d| &d.motor_position)
    }
    fn get_motor_encoders(&mut self) -> DevResult<Vec<f64>> {
        self.state_vec(|d| &d.motor_position)
    }
    fn get_motor_encoder_speed(&mut self, m: usize) -> DevResult<f64> {
        self.state_one(m, |d| &d.motor_velocity)
    }
    fn get_motor_encoder_acceleration(&mut self, m: usize) -> DevResult<f64> {
        self.state_one(m, |d| &d.motor_acceleration)
    }
    fn get_motor_encoder_speeds(&mut self) -> DevResult<Vec<f64>> {
        self.state_vec(|d| &d.motor_velocity)
    }
    fn get_motor_encoder_accelerations(&mut self) -> DevResult<Vec<f64>> {
        self.state_vec(|d| &d.motor_acceleration)
    }
}

impl IAmplifierControl for RemoteControlBoard {
    fn enable_amp(&mut self, j: usize) -> DevResult<()> {
        self.set(bottle![Vocab32(SET), Vocab32(AMP_ENABLE), j32(j)])
    }
    fn disable_amp(&mut self, j: usize) -> DevResult<()> {
        self.set(bottle![Vocab32(SET), Vocab32(AMP_DISABLE), j32(j)])
    }
    fn get_amp_statuses(&mut self) -> DevResult<Vec<i32>> {
        let v = self.get_value(bottle![Vocab32(GET), Vocab32(AMP_STATUS)])?;
        v.as_list()
            .and_then(|l| l.iter().map(Value::as_i32).collect())
            .ok_or_else(bad_reply)
    }
    fn get_current(&mut self, j: usize) -> DevResult<f64> {
        self.state_one(j, |d| &d.current)
    }
    fn get_max_current(&mut self, j: usize) -> DevResult<f64> {
        self.get_f64(bottle![Vocab32(GET), Vocab32(AMP_MAXCURRENT), j32(j)])
    }
    fn set_max_current(&mut self, j: usize, v: f64) -> DevResult<()> {
        self.set(bottle![Vocab32(SET), Vocab32(AMP_MAXCURRENT), j32(j), v])
    }
    fn get_amp_status(&mut self, j: usize) -> DevResult<i32> {
        let v = self.get_value(bottle![Vocab32(GET), Vocab32(AMP_STATUS_SINGLE), j32(j)])?;
        v.as_i32().ok_or_else(bad_reply)
    }
    fn get_nominal_current(&mut self, m: usize) -> DevResult<f64> {
        self.get_f64(bottle![Vocab32(GET), Vocab32(AMP_NOMINAL_CURRENT), j32(m)])
    }
    fn set_nominal_current(&mut self, m: usize, v: f64) -> DevResult<()> {
        self.set(bottle![
            Vocab32(SET),
            Vocab32(AMP_NOMINAL_CURRENT),
            j32(m),
            v
        ])
    }
    fn get_peak_current(&mut self, m: usize) -> DevResult<f64> {
        self.get_f64(bottle![Vocab32(GET), Vocab32(AMP_PEAK_CURRENT), j32(m)])
    }
    fn set_peak_current(&mut self, m: usize, v: f64) -> DevResult<()> {
        self.set(bottle![Vocab32(SET), Vocab32(AMP_PEAK_CURRENT), j32(m), v])
    }
    fn get_pwm(&mut self, m: usize) -> DevResult<f64> {
        self.get_f64(bottle![Vocab32(GET), Vocab32(AMP_PWM), j32(m)])
    }
    fn get_pwm_limit(&mut self, m: usize) -> DevResult<f64> {
        self.get_f64(bottle![Vocab32(GET), Vocab32(AMP_PWM_LIMIT), j32(m)])
    }
    fn set_pwm_limit(&mut self, m: usize, v: f64) -> DevResult<()> {
        self.set(bottle![Vocab32(SET), Vocab32(AMP_PWM_LIMIT), j32(m), v])
    }
    fn get_power_supply_voltage(&mut self, m: usize) -> DevResult<f64> {
        self.get_f64(bottle![Vocab32(GET), Vocab32(AMP_VOLTAGE_SUPPLY), j32(m)])
    }
}

impl IMotor for RemoteControlBoard {
    fn get_temperature(&mut self, m: usize) -> DevResult<f64> {
        self.get_f64(bottle![Vocab32(GET), Vocab32(TEMPERATURE), j32(m)])
    }
    fn get_number_of_motors(&mut self) -> DevResult<usize> {
        let v = self.get_value(bottle![Vocab32(GET), Vocab32(MOTORS_NUMBER)])?;
        v.as_i64()
            .and_then(|n| usize::try_from(n).ok())
            .ok_or_else(bad_reply)
    }
    fn get_gearbox_ratio(&mut self, m: usize) -> DevResult<f64> {
        self.get_f64(bottle![Vocab32(GET), Vocab32(GEARBOX_RATIO), j32(m)])
    }
    fn set_gearbox_ratio(&mut self, m: usize, v: f64) -> DevResult<()> {
        self.set(bottle![Vocab32(SET), Vocab32(GEARBOX_RATIO), j32(m), v])
    }
    fn get_temperature_limit(&mut self, m: usize) -> DevResult<f64> {
        self.get_f64(bottle![Vocab32(GET), Vocab32(TEMPERATURE_LIMIT), j32(m)])
    }
    fn set_temperature_limit(&mut self, m: usize, v: f64) -> DevResult<()> {
        self.set(bottle![Vocab32(SET), Vocab32(TEMPERATURE_LIMIT), j32(m), v])
    }
}

impl IPidControl for RemoteControlBoard {
    fn get_pid(&mut self, pid_type: Vocab32, j: usize) -> DevResult<Pid> {
        let gains = self.get_f64s(bottle![
            Vocab32(GET),
            Vocab32(PID),
            Vocab32(PID),
            pid_type,
            j32(j)
        ])?;
        Ok(Pid::from_slice(&gains))
    }
    fn set_pid(&mut self, pid_type: Vocab32, j: usize, pid: Pid) -> DevResult<()> {
        self.set(bottle![
            Vocab32(SET),
            Vocab32(PID),
            Vocab32(PID),
            pid_type,
            j32(j),
            floats_value(&pid.to_array())
        ])
    }
    fn enable_pid(&mut self, pid_type: Vocab32, j: usize) -> DevResult<()> {
        self.set(bottle![
            Vocab32(SET),
            Vocab32(PID),
            Vocab32(PID_ENABLE),
            pid_type,
            j32(j)
        ])
    }
    fn disable_pid(&mut self, pid_type: Vocab32, j: usize) -> DevResult<()> {
        self.set(bottle![
            Vocab32(SET),
            Vocab32(PID),
            Vocab32(PID_DISABLE),
            pid_type,
            j32(j)
        ])
    }
    fn is_pid_enabled(&mut self, pid_type: Vocab32, j: usize) -> DevResult<bool> {
        self.get_bool(bottle![
            Vocab32(GET),
            Vocab32(PID),
            Vocab32(PID_ENABLE),
            pid_type,
            j32(j)
        ])
    }
    fn set_pid_reference(&mut self, pid_type: Vocab32, j: usize, r: f64) -> DevResult<()> {
        self.set(bottle![
            Vocab32(SET),
            Vocab32(PID),
            Vocab32(REF),
            pid_type,
            j32(j),
            r
        ])
    }
    fn get_pid_reference(&mut self, pid_type: Vocab32, j: usize) -> DevResult<f64> {
        self.get_f64(bottle![
            Vocab32(GET),
            Vocab32(PID),
            Vocab32(REF),
            pid_type,
            j32(j)
        ])
    }
    fn get_pid_error(&mut self, pid_type: Vocab32, j: usize) -> DevResult<f64> {
        self.get_f64(bottle![
            Vocab32(GET),
            Vocab32(PID),
            Vocab32(PID_ERROR),
            pid_type,
            j32(j)
        ])
    }
    fn get_pid_output(&mut self, pid_type: Vocab32, j: usize) -> DevResult<f64> {
        self.get_f64(bottle![
            Vocab32(GET),
            Vocab32(PID),
            Vocab32(PID_OUTPUT),
            pid_type,
            j32(j)
        ])
    }
    fn reset_pid(&mut self, pid_type: Vocab32, j: usize) -> DevResult<()> {
        self.set(bottle![
            Vocab32(SET),
            Vocab32(PID),
            Vocab32(PID_RESET),
            pid_type,
            j32(j)
        ])
    }
}

impl ICurrentControl for RemoteControlBoard {
    fn get_ref_current(&mut self, j: usize) -> DevResult<f64> {
        self.get_f64(bottle![
            Vocab32(GET),
            Vocab32(CURRENT_IFACE),
            Vocab32(REF),
            j32(j)
        ])
    }
    fn get_current_range(&mut self, j: usize) -> DevResult<(f64, f64)> {
        let r = self.call(&bottle![
            Vocab32(GET),
            Vocab32(CURRENT_IFACE),
            Vocab32(RANGE),
            j32(j)
        ])?;
        two_numbers(&r)
    }
    fn set_ref_current(&mut self, j: usize, current: f64) -> DevResult<()> {
        let j = self.joint(j)?;
        self.stream(
            bottle![Vocab32(CURRENT_IFACE), Vocab32(REF), j32(j)],
            vec![current],
        )
    }
    fn set_ref_currents(&mut self, currents: &[f64]) -> DevResult<()> {
        self.check_all(currents)?;
        self.stream(
            bottle![Vocab32(CURRENT_IFACE), Vocab32(REFS)],
            currents.to_vec(),
        )
    }
    fn set_ref_current_group(&mut self, joints: &[usize], currents: &[f64]) -> DevResult<()> {
        check_group(joints, currents)?;
        self.stream(
            bottle![
                Vocab32(CURRENT_IFACE),
                Vocab32(REF_GROUP),
                joints.len() as i32,
                joints_value(joints)
            ],
            currents.to_vec(),
        )
    }
}

impl IPwmControl for RemoteControlBoard {
    fn get_ref_duty_cycle(&mut self, j: usize) -> DevResult<f64> {
        self.get_f64(bottle![
            Vocab32(GET),
            Vocab32(PWM_IFACE),
            Vocab32(REF),
            j32(j)
        ])
    }
    fn set_ref_duty_cycle(&mut self, j: usize, duty: f64) -> DevResult<()> {
        let j = self.joint(j)?;
        self.stream(
            bottle![Vocab32(PWM_IFACE), Vocab32(REF), j32(j)],
            vec![duty],
        )
    }
    fn set_ref_duty_cycles(&mut self, duties: &[f64]) -> DevResult<()> {
        self.check_all(duties)?;
        self.stream(bottle![Vocab32(PWM_IFACE), Vocab32(REFS)], duties.to_vec())
    }
    fn get_duty_cycle(&mut self, m: usize) -> DevResult<f64> {
        self.state_one(m, |d| &d.pwm_duty_cycle)
    }
}

impl IPositionDirect for RemoteControlBoard {
    fn get_axes(&mut self) -> DevResult<usize> {
        self.axes()
    }
    fn set_position(&mut self, j: usize, reference: f64) -> DevResult<()> {
        let j = self.joint(j)?;
        self.stream(bottle![Vocab32(POSITION_DIRECT), j32(j)], vec![reference])
    }
    fn get_ref_position(&mut self, j: usize) -> DevResult<f64> {
        self.get_f64(bottle![Vocab32(GET), Vocab32(POSITION_DIRECT), j32(j)])
    }
    fn set_positions(&mut self, references: &[f64]) -> DevResult<()> {
        self.check_all(references)?;
        self.stream(bottle![Vocab32(POSITION_DIRECTS)], references.to_vec())
    }
    fn set_positions_group(&mut self, joints: &[usize], references: &[f64]) -> DevResult<()> {
        check_group(joints, references)?;
        self.stream(
            bottle![
                Vocab32(POSITION_DIRECT_GROUP),
                joints.len() as i32,
                joints_value(joints)
            ],
            references.to_vec(),
        )
    }
    fn get_ref_positions(&mut self) -> DevResult<Vec<f64>> {
        self.get_f64s(bottle![Vocab32(GET), Vocab32(POSITION_DIRECTS)])
    }
    fn get_ref_positions_group(&mut self, joints: &[usize]) -> DevResult<Vec<f64>> {
        self.get_f64s(bottle![
            Vocab32(GET),
            Vocab32(POSITION_DIRECT_GROUP),
            joints.len() as i32,
            joints_value(joints)
        ])
    }
}

impl IImpedanceControl for RemoteControlBoard {
    fn get_axes(&mut self) -> DevResult<usize> {
        self.axes()
    }
    fn get_impedance(&mut self, j: usize) -> DevResult<(f64, f64)> {
        let v = self.impedance_list(IMP_PARAM, j)?;
        Ok((v[0], v[1]))
    }
    fn set_impedance(&mut self, j: usize, stiffness: f64, damping: f64) -> DevResult<()> {
        self.set(bottle![
            Vocab32(SET),
            Vocab32(IMPEDANCE),
            Vocab32(IMP_PARAM),
            j32(j),
            floats_value(&[stiffness, damping])
        ])
    }
    fn get_impedance_offset(&mut self, j: usize) -> DevResult<f64> {
        Ok(self.impedance_list(IMP_OFFSET, j)?[0])
    }
    fn set_impedance_offset(&mut self, j: usize, offset: f64) -> DevResult<()> {
        self.set(bottle![
            Vocab32(SET),
            Vocab32(IMPEDANCE),
            Vocab32(IMP_OFFSET),
            j32(j),
            floats_value(&[offset])
        ])
    }
    fn get_current_impedance_limit(&mut self, j: usize) -> DevResult<ImpedanceLimits> {
        // C++ 3.12 asks with the generic `[llim]`
        let v = self.impedance_list(LIMITS, j)?;
        Ok(ImpedanceLimits {
            min_stiffness: v[0],
            max_stiffness: v[1],
            min_damping: v[2],
            max_damping: v[3],
        })
    }
}

impl RemoteControlBoard {
    /// `[get] [iimp] <what> j` -> the reply's list, padded with 0 to 4 values as C++
    /// reads missing items.
    fn impedance_list(&self, what: i32, j: usize) -> DevResult<Vec<f64>> {
        let mut v = self.get_f64s(bottle![
            Vocab32(GET),
            Vocab32(IMPEDANCE),
            Vocab32(what),
            j32(j)
        ])?;
        v.resize(4.max(v.len()), 0.0);
        Ok(v)
    }
}

impl IControlCalibration for RemoteControlBoard {
    fn calibrate_axis_with_params(
        &mut self,
        j: usize,
        kind: u32,
        p1: f64,
        p2: f64,
        p3: f64,
    ) -> DevResult<()> {
        self.set(bottle![
            Vocab32(CALIBRATE_JOINT),
            j32(j),
            kind as i32,
            p1,
            p2,
            p3
        ])
    }
    fn set_calibration_parameters(
        &mut self,
        j: usize,
        params: &CalibrationParameters,
    ) -> DevResult<()> {
        // C++ sends type and param1..4 only
        self.set(bottle![
            Vocab32(CALIBRATE_JOINT_PARAMS),
            j32(j),
            params.kind as i32,
            params.param1,
            params.param2,
            params.param3,
            params.param4
        ])
    }
    fn calibration_done(&mut self, j: usize) -> DevResult<bool> {
        // `[fail]` means "not done"; no answer stays an error
        match self.call(&bottle![Vocab32(CALIBRATE_DONE), j32(j)]) {
            Ok(_) => Ok(true),
            Err(DeviceError::Refused { .. }) => Ok(false),
            Err(e) => Err(e),
        }
    }
    // These four send a lone vocab, as C++ does; a 3.12 server refuses commands shorter
    // than two elements, so they fail against it as they do in C++.
    fn calibrate_robot(&mut self) -> DevResult<()> {
        self.set(bottle![Vocab32(CALIBRATE)])
    }
    fn park(&mut self, _wait: bool) -> DevResult<()> {
        self.set(bottle![Vocab32(PARK)])
    }
    fn abort_calibration(&mut self) -> DevResult<()> {
        self.set(bottle![Vocab32(ABORTCALIB)])
    }
    fn abort_park(&mut self) -> DevResult<()> {
        self.set(bottle![Vocab32(ABORTPARK)])
    }
}

impl RemoteControlBoard {
    /// `[set] [reca] <what> [j]`.
    fn remote_calibrator(&self, what: i32, j: Option<usize>) -> DevResult<()> {
        let mut cmd = bottle![
            Vocab32(SET),
            Vocab32(REMOTE_CALIBRATOR_IFACE),
            Vocab32(what)
        ];
        if let Some(j) = j {
            cmd.push(j32(j));
        }
        self.set(cmd)
    }
}

impl IRemoteCalibrator for RemoteControlBoard {
    fn is_calibrator_device_present(&mut self) -> DevResult<bool> {
        self.get_bool(bottle![
            Vocab32(GET),
            Vocab32(REMOTE_CALIBRATOR_IFACE),
            Vocab32(IS_CALIBRATOR_PRESENT)
        ])
    }
    fn calibrate_single_joint(&mut self, j: usize) -> DevResult<()> {
        self.remote_calibrator(CALIBRATE_SINGLE_JOINT, Some(j))
    }
    fn calibrate_whole_part(&mut self) -> DevResult<()> {
        self.remote_calibrator(CALIBRATE_WHOLE_PART, None)
    }
    fn homing_single_joint(&mut self, j: usize) -> DevResult<()> {
        self.remote_calibrator(HOMING_SINGLE_JOINT, Some(j))
    }
    fn homing_whole_part(&mut self) -> DevResult<()> {
        self.remote_calibrator(HOMING_WHOLE_PART, None)
    }
    fn park_single_joint(&mut self, j: usize, _wait: bool) -> DevResult<()> {
        // the wait flag does not travel (C++ drops it too)
        self.remote_calibrator(PARK_SINGLE_JOINT, Some(j))
    }
    fn park_whole_part(&mut self) -> DevResult<()> {
        self.remote_calibrator(PARK_WHOLE_PART, None)
    }
    fn quit_calibrate(&mut self) -> DevResult<()> {
        self.remote_calibrator(QUIT_CALIBRATE, None)
    }
    fn quit_park(&mut self) -> DevResult<()> {
        self.remote_calibrator(QUIT_PARK, None)
    }
}

/// A group command needs one value per joint.
fn check_group(joints: &[usize], values: &[f64]) -> DevResult<()> {
    if joints.len() == values.len() {
        Ok(())
    } else {
        Err(DeviceError::WrongSize {
            expected: joints.len(),
            got: values.len(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn settings_follow_cpp_defaults_and_reject_bad_values() {
        let p = |t: &str| Property::from_config_text(t).unwrap();
        let s = settings(&p("remote /r\nlocal l\n")).unwrap();
        assert_eq!((s.remote.as_str(), s.local.as_str()), ("/r", "/l"));
        assert_eq!(s.carrier, "udp");
        assert_eq!(s.timeout, DEFAULT_TIMEOUT);
        assert!(!s.write_strict && !s.ignore_protocol);
        let err = |t: &str| settings(&p(t)).err().unwrap().to_string();
        assert!(err("local /l\n").contains("`remote`"));
        assert!(err("remote /r\n").contains("`local`"));
        assert!(err("remote /r\nlocal /l\ntimeout -1\n").contains("`timeout`"));
        assert!(err("remote /r\nlocal /l\nwriteStrict maybe\n").contains("`writeStrict`"));
    }

    #[test]
    fn failure_replies() {
        assert!(!reply_ok(&Bottle::new()));
        assert!(!reply_ok(&Bottle::from_text("[fail]")));
        assert!(!reply_ok(&Bottle::from_text("[nak]")));
        assert!(reply_ok(&Bottle::from_text("[ok]")));
        assert!(reply_ok(&Bottle::from_text("[is] [axes] 4 [ok]")));
    }
}
