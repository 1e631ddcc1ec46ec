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

use crate::controlboard::methods::{self as m, Method};
use crate::controlboard::streaming::{Joints, Kind, Stream};
use crate::controlboard::v3::{self, Answer, Group, Listed, PidType, J16};
use crate::controlboard::v4;
use crate::controlboard::{CommandMessage, JointData, PROTOCOL_VERSION_NUMBER};
use crate::driver::DeviceDriver;
use crate::error::{DevResult, DeviceError};
use crate::interfaces::*;
use crate::runtime;
use parking_lot::{Mutex, MutexGuard};
use std::sync::Arc;
use std::time::{Duration, Instant};
use yarp_net::nameserver::NameClient;
use yarp_net::port::Port;
use yarp_proto::tags::Generation;
use yarp_proto::{bottle, Bottle, Property, Stamp, Value, Vocab32};

/// The C++ device name.
pub const NAME: &str = "remote_controlboard";
/// Its name in YARP 4.0, where `remote_controlboard` is a deprecated alias.
pub const NAME_4: &str = "controlBoard_nwc_yarp";

/// Drivers of this family, by C++ name: 3.12's name takes 3.12's parameters, 4.0's its
/// own; either talks to a server of either generation.
pub(crate) const DRIVERS: &[(&str, crate::driver::Factory)] = &[
    (NAME, || Box::new(RemoteControlBoard::new())),
    (NAME_4, || Box::new(RemoteControlBoard::yarp4())),
];

/// How long an RPC may wait for its reply before the call fails.
pub const RPC_TIMEOUT: Duration = Duration::from_secs(5);
/// Default staleness limit of the streamed state (C++ `timeout`).
pub const DEFAULT_TIMEOUT: Duration = Duration::from_millis(500);

const STATE_ERR: &str = "no fresh state from the remote control board (stateExt:i)";

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
    /// YARP 4.0's client sends the references it would stream by RPC.
    use_streaming: bool,
    /// The remote control board's port prefix, named in errors.
    remote: String,
    /// The server's generation of the protocol, found when opening.
    generation: Generation,
}

/// The `remote_controlboard` (3.12) and `controlBoard_nwc_yarp` (4.0) device.
#[derive(Default)]
pub struct RemoteControlBoard {
    link: Option<Link>,
    /// Which of the two names it was made by (its parameters, and the protocol it
    /// prefers from a server that speaks both).
    name: Generation,
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

crate::device_params! {
    /// What `controlBoard_nwc_yarp` reads (C++ 4.0's `ControlBoard_nwc_yarp_params.md`:
    /// fast_tcp by default, a carrier for the commands of its own, and no protocol
    /// override).
    pub struct ControlBoardNwcParams for "controlBoard_nwc_yarp" {
        /// Prefix of the port to which to connect.
        remote: String = required,
        /// Port prefix of the port opened by this device.
        local: String = required,
        /// It can be 'on' or 'off'
        "writeStrict" write_strict: String = optional,
        /// carrier used for streaming robot state
        carrier: String = "fast_tcp",
        /// carrier used for the streamed commands
        carrier_cmd: String = "fast_tcp",
        /// timeout for the input port which receives the streamed robot state
        timeout: f64 = 0.5; "s"; check crate::params::positive,
        /// stream the references (velocity, position direct, torque, current, PWM); else send them by RPC
        use_streaming: bool = true,
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
        diagnostic: bool = false,
    }
}

/// The settings read from the configuration.
struct Settings {
    remote: String,
    local: String,
    carrier: String,
    carrier_cmd: String,
    timeout: Duration,
    write_strict: bool,
    use_streaming: bool,
    ignore_protocol: bool,
    /// The protocol to speak to a server that speaks both.
    prefer: Generation,
}

fn settings(config: &Property, name: Generation) -> DevResult<Settings> {
    let device = match name {
        Generation::V3 => NAME,
        Generation::V4 => NAME_4,
    };
    let s = match name {
        Generation::V3 => {
            let p = RemoteControlBoardParams::read(config)?;
            Settings {
                remote: p.remote,
                local: p.local,
                carrier_cmd: p.carrier.clone(),
                carrier: p.carrier,
                timeout: Duration::from_secs_f64(p.timeout),
                write_strict: false,
                use_streaming: true,
                ignore_protocol: p.ignore_protocol_check,
                prefer: name,
            }
            .strict(p.write_strict.as_deref(), device)?
        }
        Generation::V4 => {
            let p = ControlBoardNwcParams::read(config)?;
            Settings {
                remote: p.remote,
                local: p.local,
                carrier: p.carrier,
                carrier_cmd: p.carrier_cmd,
                timeout: Duration::from_secs_f64(p.timeout),
                write_strict: false,
                use_streaming: p.use_streaming,
                ignore_protocol: false,
                prefer: name,
            }
            .strict(p.write_strict.as_deref(), device)?
        }
    };
    Ok(Settings {
        remote: crate::controlboard::port_prefix(&s.remote),
        local: crate::controlboard::port_prefix(&s.local),
        ..s
    })
}

impl Settings {
    /// `writeStrict`: `on`, `off` or absent.
    fn strict(mut self, value: Option<&str>, device: &str) -> DevResult<Settings> {
        self.write_strict = match value {
            None | Some("off") => false,
            Some("on") => true,
            Some(other) => {
                return Err(DeviceError::BadParam {
                    device: device.into(),
                    param: "writeStrict".into(),
                    expected: "on or off",
                    got: other.to_string(),
                })
            }
        };
        Ok(self)
    }
}

/// Opens the ports and runs the C++ connection sequence; returns the link. On failure
/// the ports opened so far are closed (unregistered) again.
async fn connect(s: Settings, ns: NameClient) -> Result<Link, String> {
    let local = &s.local;
    // the server's generation: 4.0's answers on /nws/rpc:i, 3.12's on /rpc:i (ours on both)
    let has = |suffix: &str| {
        let (ns, port) = (ns.clone(), format!("{}/{suffix}", s.remote));
        async move { ns.query(&port).await.ok().flatten().is_some() }
    };
    let generation = match (has("rpc:i").await, has("nws/rpc:i").await) {
        (true, true) => s.prefer,
        (false, true) => Generation::V4,
        _ => Generation::V3,
    };
    let rpc_suffix = match generation {
        Generation::V3 => "rpc:o",
        Generation::V4 => "nwc/rpc:o",
    };
    let mut ports: Vec<Arc<Port>> = Vec::new();
    for suffix in [rpc_suffix, "command:o", "stateExt:i"] {
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
    let shook = match generation {
        Generation::V3 => handshake(&s, &ns, &rpc, &command, &state).await,
        Generation::V4 => handshake4(&s, &ns, &rpc, &command, &state).await,
    };
    match shook {
        Ok(axes) => Ok(Link {
            rpc,
            command,
            state,
            reader,
            latest,
            axes,
            timeout: s.timeout,
            write_strict: s.write_strict,
            use_streaming: s.use_streaming,
            remote: s.remote.clone(),
            generation,
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
                Ok(Ok(r)) => Ok((cmd, r)),
                Ok(Err(e)) => Err(format!("{remote_rpc}: `{cmd}`: {e}")),
                Err(_) => Err(format!(
                    "{remote_rpc}: `{cmd}`: no reply in {RPC_TIMEOUT:?}"
                )),
            }
        }
    };
    let bad = |(cmd, reply): (Bottle, Bottle)| format!("{remote_rpc}: `{cmd}` answered `{reply}`");
    let exchange = call(v3::request(&m::ProtocolVersion {})).await?;
    let (major, minor, _) = match v3::answer::<m::ProtocolVersion>(&exchange.1) {
        Answer::Value(v) => v,
        _ => return Err(bad(exchange)),
    };
    let (our_major, our_minor, _) = PROTOCOL_VERSION_NUMBER;
    if major != our_major {
        let msg = format!(
            "protocol version mismatch: the server speaks {major}.{minor}, this client {our_major}.{our_minor}"
        );
        if !s.ignore_protocol {
            return Err(msg);
        }
        tracing::warn!("{NAME} {local}: {msg} (ignored: ignoreProtocolCheck)");
    } else if minor != our_minor {
        tracing::warn!(
            "{NAME} {local}: the server speaks protocol {major}.{minor}; minor versions differ"
        );
    }
    let exchange = call(v3::request(&m::Axes {})).await?;
    match v3::answer::<m::Axes>(&exchange.1) {
        Answer::Value(n) if n > 0 => Ok(n),
        _ => Err(format!("{remote}: bad number of axes in `{}`", exchange.1)),
    }
}

/// YARP 4.0's sequence (C++ `ControlBoard_nwc_yarp::open`): commands on `carrier_cmd`,
/// the state on `carrier`, then `nwc/rpc:o` to `nws/rpc:i`; the protocol number must
/// be 4.0's, the axes known and the interfaces listed. Returns the number of axes.
async fn handshake4(
    s: &Settings,
    ns: &NameClient,
    rpc: &Arc<Port>,
    command: &Port,
    state: &Port,
) -> Result<usize, String> {
    let remote = &s.remote;
    let remote_cmd = format!("{remote}/command:i");
    command
        .connect(&remote_cmd, Some(&s.carrier_cmd))
        .await
        .map_err(|e| format!("cannot connect to {remote_cmd} ({}): {e}", s.carrier_cmd))?;
    connect_state(
        ns,
        &format!("{remote}/stateExt:o"),
        state.name(),
        &s.carrier,
    )
    .await?;
    let remote_rpc = format!("{remote}/nws/rpc:i");
    rpc.connect(&remote_rpc, Some("tcp"))
        .await
        .map_err(|e| format!("cannot connect to {remote_rpc}: {e}"))?;
    let call = |bytes: Vec<u8>| {
        let rpc = rpc.clone();
        async move { tokio::time::timeout(RPC_TIMEOUT, rpc.rpc_encoded(bytes)).await }
    };
    // the protocol version's reply is no Bottle: it comes back as bytes
    let protocol = match call(crate::thrift::protocol_version_request()).await {
        Ok(Err(yarp_net::port::PortError::BadReply { bytes, .. })) => {
            crate::thrift::protocol_version_of(&bytes).map(|(p, _)| p)
        }
        other => {
            tracing::warn!("{remote_rpc}: getRemoteProtocolVersion answered {other:?}");
            None
        }
    };
    if protocol != Some(crate::thrift::PROTOCOL) {
        return Err(format!(
            "{remote_rpc}: invalid communication protocol: the server speaks {protocol:?}, this client {}",
            crate::thrift::PROTOCOL
        ));
    }
    let axes = match call(v4::request(&m::Axes {})).await {
        Ok(Ok(reply)) => v4::answer::<m::Axes>(&reply).and_then(|(_, n)| n),
        _ => None,
    };
    let axes = axes.ok_or_else(|| {
        format!("{remote_rpc}: problems with obtaining the number of controlled axes")
    })?;
    match call(v4::interfaces_request()).await {
        Ok(Ok(reply)) if v4::returned_ok(&reply) => Ok(axes),
        _ => Err(format!("{remote_rpc}: unable to getDeviceInterfacesRPC")),
    }
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

    /// `controlBoard_nwc_yarp`: 4.0's parameters, 4.0's protocol preferred.
    pub fn yarp4() -> Self {
        RemoteControlBoard {
            link: None,
            name: Generation::V4,
        }
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
        if v3::reply_ok(&reply) {
            return Ok(reply);
        }
        tracing::debug!("{NAME}: `{cmd}` answered `{reply}`");
        Err(self.refused(cmd))
    }

    /// Makes the remote call `method` and returns its reply's value.
    pub fn ask<M: Method>(&self, method: M) -> DevResult<M::Reply> {
        let link = self.link()?;
        if link.generation == Generation::V4 {
            return self.ask4(link, method);
        }
        let cmd = v3::request(&method);
        let reply =
            crate::nwc_ports::call_within(&link.remote, &link.rpc, cmd.clone(), RPC_TIMEOUT)?;
        match v3::answer::<M>(&reply) {
            Answer::Value(v) => Ok(v),
            Answer::Refused => {
                tracing::debug!("{NAME}: `{cmd}` answered `{reply}`");
                Err(self.refused(&cmd))
            }
            Answer::Malformed => Err(DeviceError::failed(
                &link.remote,
                format!("the reply `{reply}` to `{cmd}` lacks the value asked"),
            )),
        }
    }

    /// [`Self::ask`] of a 4.0 server, in its thrift form.
    fn ask4<M: Method>(&self, link: &Link, method: M) -> DevResult<M::Reply> {
        let Some(name) = M::V4 else {
            return Err(DeviceError::Unsupported(
                "a call YARP 4.0's control-board protocol has not",
            ));
        };
        let reply = crate::nwc_ports::call_encoded_within(
            &link.remote,
            &link.rpc,
            v4::request(&method),
            name,
            RPC_TIMEOUT,
        )?;
        match v4::answer::<M>(&reply) {
            Some((_, Some(v))) => Ok(v),
            Some((code, None)) => Err(code.error(&link.remote, name)),
            None => Err(DeviceError::failed(
                &link.remote,
                format!("the reply `{reply}` to {name} is not its return value"),
            )),
        }
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
        self.ask(m::Axes {})
    }

    /// Sends a streaming command on `command:o` (dropped if the connection is busy,
    /// unless `writeStrict on`).
    fn stream(&self, kind: Kind, joints: Joints, body: Vec<f64>) -> DevResult<()> {
        let link = self.link()?;
        let generation = link.generation;
        if generation == Generation::V4 && !link.use_streaming {
            return self.reference_by_rpc(kind, joints, body);
        }
        let stream = Stream { kind, joints };
        if !stream.has_form(generation) {
            return Err(DeviceError::Unsupported(
                "a YARP 3.12 control board has no IVelocityDirect nor PID feedforward",
            ));
        }
        let head = stream.head(generation);
        let msg = Arc::new(CommandMessage::new(head, body).to_bottle());
        let port = link.command.clone();
        if link.write_strict {
            let _ =
                runtime::block_on(async move { port.write_shared_as(msg, None, generation).await });
        } else {
            port.write_nowait_each(
                &[(Arc::unwrap_or_clone(msg), generation)],
                |_| Some(0),
                None,
            );
        }
        Ok(())
    }

    /// A reference sent by RPC, as 4.0's client does without streaming.
    fn reference_by_rpc(&self, kind: Kind, joints: Joints, values: Vec<f64>) -> DevResult<()> {
        let group = |j: Joints| match j {
            Joints::Group(js) => Group(js),
            _ => Group(Vec::new()),
        };
        let one = |j: &Joints, v: &[f64]| match j {
            Joints::One(j) | Joints::Pid(_, j) => (*j, v.first().copied().unwrap_or(0.0)),
            _ => (0, 0.0),
        };
        let (j, value) = one(&joints, &values);
        let pid = |j: &Joints| match j {
            Joints::Pid(ty, _) => PidType(*ty),
            _ => PidType(Vocab32(0)),
        };
        match kind {
            Kind::PidOffset => self.ask(m::SetPidOffset {
                ty: pid(&joints),
                j: J16(j),
                value,
            }),
            Kind::PidFeedforward => self.ask(m::SetPidFeedforward {
                ty: pid(&joints),
                j: J16(j),
                value,
            }),
            Kind::PositionMoves => self.ask(m::PositionMoves { targets: values }),
            Kind::VelocityMove => self.ask(m::VelocityMove { j, value }),
            Kind::VelocityMoves => self.ask(m::VelocityMoves { speeds: values }),
            Kind::VelocityMoveGroup => self.ask(m::VelocityMoveGroup {
                joints: group(joints),
                values,
            }),
            Kind::RefTorque => self.ask(m::SetRefTorque { j, value }),
            Kind::RefTorques => self.ask(m::SetRefTorques { values }),
            Kind::RefTorqueGroup => self.ask(m::SetRefTorqueGroup {
                joints: group(joints),
                values,
            }),
            Kind::Position => self.ask(m::SetPosition { j, value }),
            Kind::Positions => self.ask(m::SetPositions { values }),
            Kind::PositionGroup => self.ask(m::SetPositionsGroup {
                joints: group(joints),
                values,
            }),
            Kind::RefDutyCycle => self.ask(m::SetRefDutyCycle { j, value }),
            Kind::RefDutyCycles => self.ask(m::SetRefDutyCycles { values }),
            Kind::RefCurrent => self.ask(m::SetRefCurrent { j, value }),
            Kind::RefCurrents => self.ask(m::SetRefCurrents { values }),
            Kind::VelocityDirect => self.ask(m::SetRefVelocityDirect { j, value }),
            Kind::VelocitiesDirect => self.ask(m::SetRefVelocitiesDirect { values }),
            Kind::VelocitiesDirectGroup => self.ask(m::SetRefVelocitiesDirectGroup {
                joints: group(joints),
                values,
            }),
            Kind::RefCurrentGroup => self.ask(m::SetRefCurrentGroup {
                joints: group(joints),
                values,
            }),
        }
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

impl DeviceDriver for RemoteControlBoard {
    fn parameters(&self) -> Vec<crate::params::ParamSpec> {
        RemoteControlBoardParams::PARAMS.to_vec()
    }

    fn open(&mut self, config: &Property) -> DevResult<()> {
        let s = settings(config, self.name)?;
        let remote = s.remote.clone();
        let unreachable = |e: String| DeviceError::BadParam {
            device: NAME.into(),
            param: "remote".into(),
            expected: "the port prefix of a running controlBoard_nws_yarp",
            got: format!("{remote}: {e}"),
        };
        let ns = yarp_net::network::name_client().map_err(|e| unreachable(e.to_string()))?;
        let link = runtime::block_on_result(connect(s, ns)).map_err(unreachable)?;
        self.close()?;
        self.link = Some(link);
        Ok(())
    }

    fn close(&mut self) -> DevResult<()> {
        if let Some(link) = self.link.take() {
            link.reader.abort();
            runtime::block_on_logged("remote_controlboard: closing", async move {
                let _ = link.reader.await;
                close_ports(vec![link.rpc, link.command, link.state]).await;
            });
        }
        Ok(())
    }

    crate::motor_control_views!();

    crate::views!(
        as_remote_calibrator,
        as_velocity_direct,
        as_joint_brake,
        as_joint_fault,
        as_remote_variables
    );
}

impl Drop for RemoteControlBoard {
    fn drop(&mut self) {
        let _ = self.close();
    }
}

/// Trait methods that are one remote call each, declared as
/// `fn name(args) -> Reply => Method { fields };` with the protocol's method struct
/// ([`m`]): what C++'s `RemoteControlBoard` writes out by hand, method by method.
macro_rules! remote_calls {
    ($(
        $(#[$attr:meta])*
        fn $name:ident($($arg:ident: $ty:ty),*) -> $ret:ty => $method:ident { $($field:tt)* };
    )*) => {
        $(
            $(#[$attr])*
            fn $name(&mut self, $($arg: $ty),*) -> DevResult<$ret> {
                self.ask(m::$method { $($field)* })
            }
        )*
    };
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
    remote_calls! {
        fn set_encoder(j: usize, value: f64) -> () => SetEncoder { j, value };
        fn reset_encoder(j: usize) -> () => ResetEncoder { j };
        fn reset_encoders() -> () => ResetEncoders {};
        fn set_encoders(values: &[f64]) -> () => SetEncoders { values: values.to_vec() };
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

fn group(joints: &[usize]) -> Group {
    Group(joints.to_vec())
}

impl IPositionControl for RemoteControlBoard {
    fn get_axes(&mut self) -> DevResult<usize> {
        self.axes()
    }
    remote_calls! {
        fn position_move(j: usize, target: f64) -> () => PositionMove { j, target };
        fn relative_move(j: usize, delta: f64) -> () => RelativeMove { j, delta };
        fn check_motion_done(j: usize) -> bool => CheckMotionDone { j };
        fn set_ref_speed(j: usize, speed: f64) -> () => SetRefSpeed { j, speed };
        fn set_ref_acceleration(j: usize, acc: f64) -> () => SetRefAcceleration { j, acc };
        fn get_ref_speed(j: usize) -> f64 => GetRefSpeed { j };
        fn get_ref_acceleration(j: usize) -> f64 => GetRefAcceleration { j };
        fn stop(j: usize) -> () => Stop { j };
        fn get_target_position(j: usize) -> f64 => GetTargetPosition { j };
        fn position_moves(targets: &[f64]) -> () => PositionMoves { targets: targets.to_vec() };
    }
    fn position_move_group(&mut self, joints: &[usize], targets: &[f64]) -> DevResult<()> {
        let (joints, targets) = (group(joints), targets.to_vec());
        self.ask(m::PositionMoveGroup { joints, targets })
    }
    remote_calls! {
        fn relative_moves(deltas: &[f64]) -> () => RelativeMoves { deltas: deltas.to_vec() };
    }
    fn relative_move_group(&mut self, joints: &[usize], deltas: &[f64]) -> DevResult<()> {
        let (joints, deltas) = (group(joints), deltas.to_vec());
        self.ask(m::RelativeMoveGroup { joints, deltas })
    }
    remote_calls! {
        fn check_motion_dones() -> bool => CheckMotionDones {};
        fn check_motion_done_group(joints: &[usize]) -> bool => CheckMotionDoneGroup {
            joints: group(joints)
        };
        fn set_ref_speeds(speeds: &[f64]) -> () => SetRefSpeeds { speeds: speeds.to_vec() };
    }
    fn set_ref_speed_group(&mut self, joints: &[usize], speeds: &[f64]) -> DevResult<()> {
        let (joints, speeds) = (group(joints), speeds.to_vec());
        self.ask(m::SetRefSpeedGroup { joints, speeds })
    }
    remote_calls! {
        fn set_ref_accelerations(accs: &[f64]) -> () => SetRefAccelerations { accs: accs.to_vec() };
    }
    fn set_ref_acceleration_group(&mut self, joints: &[usize], accs: &[f64]) -> DevResult<()> {
        let (joints, accs) = (group(joints), accs.to_vec());
        self.ask(m::SetRefAccelerationGroup { joints, accs })
    }
    remote_calls! {
        fn get_ref_speeds() -> Vec<f64> => GetRefSpeeds {};
        fn get_ref_accelerations() -> Vec<f64> => GetRefAccelerations {};
        fn stops() -> () => Stops {};
        fn stop_group(joints: &[usize]) -> () => StopGroup { joints: group(joints) };
        fn get_target_positions() -> Vec<f64> => GetTargetPositions {};
        fn get_target_position_group(joints: &[usize]) -> Vec<f64> => GetTargetPositionGroup {
            joints: group(joints)
        };
    }
}

impl IVelocityControl for RemoteControlBoard {
    fn get_axes(&mut self) -> DevResult<usize> {
        self.axes()
    }
    fn velocity_move(&mut self, j: usize, speed: f64) -> DevResult<()> {
        let j = self.joint(j)?;
        self.stream(Kind::VelocityMove, Joints::One(j), vec![speed])
    }
    remote_calls! {
        fn get_ref_velocity(j: usize) -> f64 => GetRefVelocity { j };
    }
    fn velocity_moves(&mut self, speeds: &[f64]) -> DevResult<()> {
        self.check_all(speeds)?;
        self.stream(Kind::VelocityMoves, Joints::All, speeds.to_vec())
    }
    fn velocity_move_group(&mut self, joints: &[usize], speeds: &[f64]) -> DevResult<()> {
        m::sized(joints, speeds)?;
        self.stream(
            Kind::VelocityMoveGroup,
            Joints::Group(joints.to_vec()),
            speeds.to_vec(),
        )
    }
    remote_calls! {
        fn get_ref_velocities() -> Vec<f64> => GetRefVelocities {};
    }
}

impl IVelocityDirect for RemoteControlBoard {
    fn get_axes(&mut self) -> DevResult<usize> {
        self.axes()
    }
    fn set_ref_velocity_direct(&mut self, j: usize, v: f64) -> DevResult<()> {
        let j = self.joint(j)?;
        self.stream(Kind::VelocityDirect, Joints::One(j), vec![v])
    }
    fn set_ref_velocities_direct(&mut self, v: &[f64]) -> DevResult<()> {
        self.check_all(v)?;
        self.stream(Kind::VelocitiesDirect, Joints::All, v.to_vec())
    }
    fn set_ref_velocities_direct_group(&mut self, joints: &[usize], v: &[f64]) -> DevResult<()> {
        m::sized(joints, v)?;
        self.stream(
            Kind::VelocitiesDirectGroup,
            Joints::Group(joints.to_vec()),
            v.to_vec(),
        )
    }
    remote_calls! {
        fn get_ref_velocity_direct(j: usize) -> f64 => GetRefVelocityDirect { j };
        fn get_ref_velocities_direct() -> Vec<f64> => GetRefVelocitiesDirect {};
        fn get_ref_velocities_direct_group(joints: &[usize]) -> Vec<f64> =>
            GetRefVelocitiesDirectGroup {
                joints: group(joints)
            };
    }
}

impl IRemoteVariables for RemoteControlBoard {
    remote_calls! {
        fn get_remote_variable(key: &str) -> Bottle => GetRemoteVariable { key: key.to_string() };
        fn set_remote_variable(key: &str, value: &Bottle) -> () => SetRemoteVariable {
            key: key.to_string(), value: crate::controlboard::v3::Flat(value.clone())
        };
    }
    fn get_remote_variables_list(&mut self) -> DevResult<Bottle> {
        self.ask(m::GetRemoteVariablesList {}).map(|k| k.0)
    }
}

impl IJointFault for RemoteControlBoard {
    remote_calls! {
        fn get_last_joint_fault(j: usize) -> (i32, String) => GetLastJointFault { j };
    }
}

impl IJointBrake for RemoteControlBoard {
    remote_calls! {
        fn is_joint_braked(j: usize) -> bool => IsJointBraked { j };
        fn set_manual_brake_active(j: usize, active: bool) -> () => SetManualBrakeActive {
            j, active
        };
        fn set_auto_brake_enabled(j: usize, enabled: bool) -> () => SetAutoBrakeEnabled {
            j, enabled
        };
        fn get_auto_brake_enabled(j: usize) -> bool => GetAutoBrakeEnabled { j };
    }
}

impl IControlMode for RemoteControlBoard {
    fn get_axes(&mut self) -> DevResult<usize> {
        self.axes()
    }
    remote_calls! {
        fn get_available_control_modes(j: usize) -> Vec<Vocab32> => GetAvailableControlModes {
            j: J16(j)
        };
    }
    fn get_control_mode(&mut self, j: usize) -> DevResult<Vocab32> {
        let j = self.joint(j)?;
        self.state(|d, _| {
            let c = &d.control_mode;
            c.values.get(j).copied().filter(|_| c.valid).map(Vocab32)
        })
    }
    remote_calls! {
        fn set_control_mode(j: usize, mode: Vocab32) -> () => SetControlMode { j, mode };
    }
    fn get_control_modes(&mut self) -> DevResult<Vec<Vocab32>> {
        self.state(|d, _| {
            let c = &d.control_mode;
            c.valid
                .then(|| c.values.iter().copied().map(Vocab32).collect())
        })
    }
    remote_calls! {
        fn set_control_modes(modes: &[Vocab32]) -> () => SetControlModes { modes: modes.to_vec() };
    }
    fn set_control_modes_group(&mut self, joints: &[usize], modes: &[Vocab32]) -> DevResult<()> {
        let (joints, modes) = (group(joints), modes.to_vec());
        self.ask(m::SetControlModesGroup { joints, modes })
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
    remote_calls! {
        fn set_interaction_mode(j: usize, mode: Vocab32) -> () => SetInteractionMode { j, mode };
    }
    fn get_interaction_modes(&mut self) -> DevResult<Vec<Vocab32>> {
        self.state(|d, _| {
            let c = &d.interaction_mode;
            c.valid
                .then(|| c.values.iter().copied().map(Vocab32).collect())
        })
    }
    remote_calls! {
        fn set_interaction_modes(modes: &[Vocab32]) -> () => SetInteractionModes {
            modes: modes.to_vec()
        };
    }
    fn set_interaction_modes_group(
        &mut self,
        joints: &[usize],
        modes: &[Vocab32],
    ) -> DevResult<()> {
        let (joints, modes) = (group(joints), modes.to_vec());
        self.ask(m::SetInteractionModesGroup { joints, modes })
    }
}

impl IAxisInfo for RemoteControlBoard {
    remote_calls! {
        fn get_axis_name(j: usize) -> String => GetAxisName { j };
    }
    fn get_joint_type(&mut self, j: usize) -> DevResult<Vocab32> {
        self.ask(m::GetJointType { j }).map(Vocab32)
    }
}

impl IControlLimits for RemoteControlBoard {
    remote_calls! {
        fn set_limits(j: usize, min: f64, max: f64) -> () => SetLimits { j: J16(j), min, max };
        fn get_limits(j: usize) -> (f64, f64) => GetLimits { j: J16(j) };
        fn set_vel_limits(j: usize, min: f64, max: f64) -> () => SetVelLimits {
            j: J16(j), min, max
        };
        fn get_vel_limits(j: usize) -> (f64, f64) => GetVelLimits { j: J16(j) };
    }
}

impl ITorqueControl for RemoteControlBoard {
    fn get_axes(&mut self) -> DevResult<usize> {
        self.axes()
    }
    fn get_motor_torque_params(&mut self, j: usize) -> DevResult<[f64; 9]> {
        let got = self.ask(m::GetMotorTorqueParams { j })?;
        got.0
            .as_slice()
            .try_into()
            .map_err(|_| DeviceError::WrongSize {
                expected: 9,
                got: got.0.len(),
            })
    }
    remote_calls! {
        fn set_motor_torque_params(j: usize, p: [f64; 9]) -> () => SetMotorTorqueParams {
            j, params: crate::controlboard::v3::Listed(p.to_vec())
        };
    }
    fn get_torque(&mut self, j: usize) -> DevResult<f64> {
        self.state_one(j, |d| &d.torque)
    }
    fn set_ref_torque(&mut self, j: usize, t: f64) -> DevResult<()> {
        let j = self.joint(j)?;
        self.stream(Kind::RefTorque, Joints::One(j), vec![t])
    }
    remote_calls! {
        fn get_ref_torque(j: usize) -> f64 => GetRefTorque { j };
    }
    fn get_torques(&mut self) -> DevResult<Vec<f64>> {
        self.state_vec(|d| &d.torque)
    }
    remote_calls! {
        fn get_torque_range(j: usize) -> (f64, f64) => GetTorqueRange { j };
    }
}

impl IMotorEncoders for RemoteControlBoard {
    remote_calls! {
        fn get_num_of_motor_encoders() -> usize => GetNumOfMotorEncoders {};
        fn set_motor_encoder(m: usize, value: f64) -> () => SetMotorEncoder { m, value };
        fn set_motor_encoders(values: &[f64]) -> () => SetMotorEncoders { values: values.to_vec() };
        fn reset_motor_encoder(m: usize) -> () => ResetMotorEncoder { m };
        fn reset_motor_encoders() -> () => ResetMotorEncoders {};
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
    remote_calls! {
        fn enable_amp(j: usize) -> () => EnableAmp { j };
        fn disable_amp(j: usize) -> () => DisableAmp { j };
        fn get_amp_statuses() -> Vec<i32> => GetAmpStatuses {};
    }
    fn get_current(&mut self, j: usize) -> DevResult<f64> {
        self.state_one(j, |d| &d.current)
    }
    remote_calls! {
        fn get_max_current(j: usize) -> f64 => GetMaxCurrent { j };
        fn set_max_current(j: usize, value: f64) -> () => SetMaxCurrent { j, value };
        fn get_amp_status(j: usize) -> i32 => GetAmpStatus { j };
        fn get_nominal_current(m: usize) -> f64 => GetNominalCurrent { m };
        fn set_nominal_current(m: usize, value: f64) -> () => SetNominalCurrent { m, value };
        fn get_peak_current(m: usize) -> f64 => GetPeakCurrent { m };
        fn set_peak_current(m: usize, value: f64) -> () => SetPeakCurrent { m, value };
        fn get_pwm(m: usize) -> f64 => GetPwm { m };
        fn get_pwm_limit(m: usize) -> f64 => GetPwmLimit { m };
        fn set_pwm_limit(m: usize, value: f64) -> () => SetPwmLimit { m, value };
        fn get_power_supply_voltage(m: usize) -> f64 => GetPowerSupplyVoltage { m };
    }
}

impl IMotor for RemoteControlBoard {
    remote_calls! {
        fn get_temperature(m: usize) -> f64 => GetTemperature { m };
        fn get_number_of_motors() -> usize => GetNumberOfMotors {};
        fn get_gearbox_ratio(m: usize) -> f64 => GetGearboxRatio { m };
        fn set_gearbox_ratio(m: usize, value: f64) -> () => SetGearboxRatio { m, value };
        fn get_temperature_limit(m: usize) -> f64 => GetTemperatureLimit { m };
        fn set_temperature_limit(m: usize, value: f64) -> () => SetTemperatureLimit { m, value };
    }
}

impl RemoteControlBoard {
    fn pid_feedforward(&self, ty: Vocab32, j: usize) -> DevResult<f64> {
        self.ask(m::GetPidFeedforward {
            ty: PidType(ty),
            j: J16(j),
        })
    }
}

impl IPidControl for RemoteControlBoard {
    /// Streamed, as 4.0's client does, when streaming (4.0 only: 3.12 has no feedforward).
    fn set_pid_feedforward(&mut self, ty: Vocab32, j: usize, v: f64) -> DevResult<()> {
        let j = self.joint(j)?;
        self.stream(Kind::PidFeedforward, Joints::Pid(ty, j), vec![v])
    }
    fn get_pid_feedforward(&mut self, ty: Vocab32, j: usize) -> DevResult<f64> {
        self.pid_feedforward(ty, j)
    }
    remote_calls! {
        fn get_pid_extra_info(ty: Vocab32, j: usize) -> PidExtraInfo => GetPidExtraInfo {
            ty: PidType(ty), j: J16(j)
        };
    }
    fn get_available_pids(&mut self, j: usize) -> DevResult<Vec<Vocab32>> {
        let numbered = self.ask(m::GetAvailablePids { j: J16(j) })?;
        Ok(numbered
            .into_iter()
            .map(|v| PidType::from_v4(v).0)
            .collect())
    }
    remote_calls! {
        fn get_pid(ty: Vocab32, j: usize) -> Pid => GetPid { ty: PidType(ty), j: J16(j) };
        fn set_pid(ty: Vocab32, j: usize, pid: Pid) -> () => SetPid {
            ty: PidType(ty), j: J16(j), pid
        };
        fn enable_pid(ty: Vocab32, j: usize) -> () => EnablePid { ty: PidType(ty), j: J16(j) };
        fn disable_pid(ty: Vocab32, j: usize) -> () => DisablePid { ty: PidType(ty), j: J16(j) };
        fn is_pid_enabled(ty: Vocab32, j: usize) -> bool => IsPidEnabled {
            ty: PidType(ty), j: J16(j)
        };
        fn set_pid_reference(ty: Vocab32, j: usize, value: f64) -> () => SetPidReference {
            ty: PidType(ty), j: J16(j), value
        };
        fn get_pid_reference(ty: Vocab32, j: usize) -> f64 => GetPidReference {
            ty: PidType(ty), j: J16(j)
        };
        fn get_pid_error(ty: Vocab32, j: usize) -> f64 => GetPidError {
            ty: PidType(ty), j: J16(j)
        };
        fn get_pid_output(ty: Vocab32, j: usize) -> f64 => GetPidOutput {
            ty: PidType(ty), j: J16(j)
        };
        fn reset_pid(ty: Vocab32, j: usize) -> () => ResetPid { ty: PidType(ty), j: J16(j) };
    }
}

impl ICurrentControl for RemoteControlBoard {
    remote_calls! {
        fn get_ref_current(j: usize) -> f64 => GetRefCurrent { j };
        fn get_current_range(j: usize) -> (f64, f64) => GetCurrentRange { j };
    }
    fn set_ref_current(&mut self, j: usize, current: f64) -> DevResult<()> {
        let j = self.joint(j)?;
        self.stream(Kind::RefCurrent, Joints::One(j), vec![current])
    }
    fn set_ref_currents(&mut self, currents: &[f64]) -> DevResult<()> {
        self.check_all(currents)?;
        self.stream(Kind::RefCurrents, Joints::All, currents.to_vec())
    }
    fn set_ref_current_group(&mut self, joints: &[usize], currents: &[f64]) -> DevResult<()> {
        m::sized(joints, currents)?;
        self.stream(
            Kind::RefCurrentGroup,
            Joints::Group(joints.to_vec()),
            currents.to_vec(),
        )
    }
}

impl IPwmControl for RemoteControlBoard {
    remote_calls! {
        fn get_ref_duty_cycle(j: usize) -> f64 => GetRefDutyCycle { j };
    }
    fn set_ref_duty_cycle(&mut self, j: usize, duty: f64) -> DevResult<()> {
        let j = self.joint(j)?;
        self.stream(Kind::RefDutyCycle, Joints::One(j), vec![duty])
    }
    fn set_ref_duty_cycles(&mut self, duties: &[f64]) -> DevResult<()> {
        self.check_all(duties)?;
        self.stream(Kind::RefDutyCycles, Joints::All, duties.to_vec())
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
        self.stream(Kind::Position, Joints::One(j), vec![reference])
    }
    remote_calls! {
        fn get_ref_position(j: usize) -> f64 => GetRefPosition { j };
    }
    fn set_positions(&mut self, references: &[f64]) -> DevResult<()> {
        self.check_all(references)?;
        self.stream(Kind::Positions, Joints::All, references.to_vec())
    }
    fn set_positions_group(&mut self, joints: &[usize], references: &[f64]) -> DevResult<()> {
        m::sized(joints, references)?;
        self.stream(
            Kind::PositionGroup,
            Joints::Group(joints.to_vec()),
            references.to_vec(),
        )
    }
    remote_calls! {
        fn get_ref_positions() -> Vec<f64> => GetRefPositions {};
        fn get_ref_positions_group(joints: &[usize]) -> Vec<f64> => GetRefPositionsGroup {
            joints: group(joints)
        };
    }
}

/// An impedance reply's list, padded with 0 to 4 values as C++ reads missing items.
fn padded(mut v: Vec<f64>) -> Vec<f64> {
    v.resize(4.max(v.len()), 0.0);
    v
}

impl IImpedanceControl for RemoteControlBoard {
    fn get_axes(&mut self) -> DevResult<usize> {
        self.axes()
    }
    fn get_impedance(&mut self, j: usize) -> DevResult<(f64, f64)> {
        let v = padded(self.ask(m::GetImpedance { j })?.0);
        Ok((v[0], v[1]))
    }
    remote_calls! {
        fn set_impedance(j: usize, stiffness: f64, damping: f64) -> () => SetImpedance {
            j, values: Listed(vec![stiffness, damping])
        };
    }
    fn get_impedance_offset(&mut self, j: usize) -> DevResult<f64> {
        Ok(padded(self.ask(m::GetImpedanceOffset { j })?.0)[0])
    }
    remote_calls! {
        fn set_impedance_offset(j: usize, offset: f64) -> () => SetImpedanceOffset {
            j, values: Listed(vec![offset])
        };
    }
    fn get_current_impedance_limit(&mut self, j: usize) -> DevResult<ImpedanceLimits> {
        let v = padded(self.ask(m::GetImpedanceLimits { j })?.0);
        Ok(ImpedanceLimits {
            min_stiffness: v[0],
            max_stiffness: v[1],
            min_damping: v[2],
            max_damping: v[3],
        })
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
        self.ask(m::CalibrateAxisWithParams {
            j,
            kind,
            p1,
            p2,
            p3,
        })
    }
    fn set_calibration_parameters(
        &mut self,
        j: usize,
        params: &CalibrationParameters,
    ) -> DevResult<()> {
        let CalibrationParameters {
            kind,
            param1: p1,
            param2: p2,
            param3: p3,
            param4: p4,
            ..
        } = *params;
        self.ask(m::SetCalibrationParameters {
            j,
            kind,
            p1,
            p2,
            p3,
            p4,
        })
    }
    fn calibration_done(&mut self, j: usize) -> DevResult<bool> {
        self.ask(m::CalibrationDone { j }).map(|d| d.0)
    }
    remote_calls! {
        fn calibrate_robot() -> () => CalibrateRobot {};
    }
    fn park(&mut self, _wait: bool) -> DevResult<()> {
        // a lone vocab, as C++ sends it
        self.ask(m::Park { wait: None })
    }
    remote_calls! {
        fn abort_calibration() -> () => AbortCalibration {};
        fn abort_park() -> () => AbortPark {};
    }
}

impl IRemoteCalibrator for RemoteControlBoard {
    remote_calls! {
        fn is_calibrator_device_present() -> bool => IsCalibratorPresent {};
        fn calibrate_single_joint(j: usize) -> () => CalibrateSingleJoint { j };
        fn calibrate_whole_part() -> () => CalibrateWholePart {};
        fn homing_single_joint(j: usize) -> () => HomingSingleJoint { j };
        fn homing_whole_part() -> () => HomingWholePart {};
    }
    fn park_single_joint(&mut self, j: usize, _wait: bool) -> DevResult<()> {
        // the wait flag does not travel (C++ drops it too)
        self.ask(m::ParkSingleJoint { j })
    }
    remote_calls! {
        fn park_whole_part() -> () => ParkWholePart {};
        fn quit_calibrate() -> () => QuitCalibrate {};
        fn quit_park() -> () => QuitPark {};
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn settings_follow_cpp_defaults_and_reject_bad_values() {
        let p = |t: &str| Property::from_config_text(t).unwrap();
        let s = settings(&p("remote /r\nlocal l\n"), Generation::V3).unwrap();
        assert_eq!((s.remote.as_str(), s.local.as_str()), ("/r", "/l"));
        assert_eq!((s.carrier.as_str(), s.carrier_cmd.as_str()), ("udp", "udp"));
        assert_eq!(s.timeout, DEFAULT_TIMEOUT);
        assert!(!s.write_strict && !s.ignore_protocol);
        // 4.0's name: fast_tcp for both, streaming on
        let s = settings(&p("remote /r\nlocal l\n"), Generation::V4).unwrap();
        assert_eq!(
            (s.carrier.as_str(), s.carrier_cmd.as_str()),
            ("fast_tcp", "fast_tcp")
        );
        assert!(s.use_streaming && s.prefer == Generation::V4);
        let err = |t: &str| settings(&p(t), Generation::V3).err().unwrap().to_string();
        assert!(err("local /l\n").contains("`remote`"));
        assert!(err("remote /r\n").contains("`local`"));
        assert!(err("remote /r\nlocal /l\ntimeout -1\n").contains("`timeout`"));
        assert!(err("remote /r\nlocal /l\nwriteStrict maybe\n").contains("`writeStrict`"));
    }

    #[test]
    fn failure_replies() {
        assert!(!v3::reply_ok(&Bottle::new()));
        assert!(!v3::reply_ok(&Bottle::from_text("[fail]")));
        assert!(!v3::reply_ok(&Bottle::from_text("[nak]")));
        assert!(v3::reply_ok(&Bottle::from_text("[ok]")));
        assert!(v3::reply_ok(&Bottle::from_text("[is] [axes] 4 [ok]")));
    }
}
