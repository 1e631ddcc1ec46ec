//! `controlBoard_nws_yarp`: the four ports of a control-board network wrapper and the
//! tasks serving them (the thin tokio layer over `rpc`, `streaming` and `state`).
//!
//! * `/<name>/rpc:i` — RPC (`handle_rpc`);
//! * `/<name>/nws/rpc:i` — YARP 4.0's RPC, its thrift form (`v4::handle_rpc`);
//! * `/<name>/command:i` — streaming commands (`handle_command`), no replies;
//! * `/<name>/state:o` — joint positions every `period`, with an envelope;
//! * `/<name>/stateExt:o` — the whole `jointData`, same envelope.
//!
//! With `single_port` (YARP 2's `ServerControlBoard`, as in YARP's design paper) there is
//! one port, named `<name>` itself: it serves every command it receives (`single_port`
//! dialect, `help` included, replies when wanted) and streams the joint positions to
//! every output, reversed text connections included.
//!
//! As in C++, the ports open first and the device comes later through `attach`;
//! publishing starts at attach and stops at detach. The state is published from a thread
//! of its own (C++ `PeriodicThread`): reading the device may block (a
//! `remote_controlboard` attached here waits for its own RPC on the device runtime), and a
//! plain thread does that without handing a runtime worker over every period.

use super::methods::Request;
use super::rpc::{handle_rpc, RpcStamp};
use super::single_port::handle_single_port;
use super::state::{envelope_time, positions_bottle, JointData};
use super::streaming::{handle_command, CommandMessage};
use crate::driver::{DeviceDriver, IWrapper, SharedDevice};
use crate::error::{DevResult, DeviceError};
use crate::runtime;
use crate::sensors::periodic::Ticker;
use crate::vocabs::FAILED;
use parking_lot::{Mutex, MutexGuard};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Weak};
use std::time::Duration;
use tokio::task::JoinHandle;
use yarp_net::nameserver::NameClient;
use yarp_net::peer_generation::PeerGenerations;
use yarp_net::port::{Port, PortError};
use yarp_proto::tags::Generation;
use yarp_proto::{Bottle, Contact, Stamp, Vocab32};

/// The C++ device name.
pub const NAME: &str = "controlBoard_nws_yarp";
/// Publishing period when none is configured (C++ default 0.02 s).
pub const DEFAULT_PERIOD: Duration = Duration::from_millis(20);

crate::device_params! {
    /// What `controlBoard_nws_yarp` reads (C++ `ControlBoard_nws_yarp_params.md`, and
    /// YARP 2's `single_port`).
    pub struct ControlBoardNwsYarpParams for "controlBoard_nws_yarp" {
        /// period of the main thread
        period: crate::params::FloatOnly = 0.02; "s"; check crate::params::positive_float,
        /// Prefix name of the ports opened by the device
        name: String = required,
        /// one port, named `name`, serving every command (YARP 2's ServerControlBoard)
        single_port: bool = false,
    }
}

/// The attached device and its joint count.
#[derive(Clone)]
struct Attached {
    device: SharedDevice,
    axes: usize,
}

type Slot = Arc<Mutex<Option<Attached>>>;

fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    // the guarded data stays consistent even if a holder panicked
    m.lock()
}

/// The port prefix C++ derives from `name`: a leading `/` added if missing.
pub fn port_prefix(name: &str) -> String {
    let base = name.trim_end_matches('/');
    if base.starts_with('/') {
        base.to_string()
    } else {
        format!("/{base}")
    }
}

/// A running `controlBoard_nws_yarp` server.
pub struct ControlBoardNws {
    prefix: String,
    rpc_name: String,
    rpc_contact: Contact,
    /// rpc:i, command:i, state:o, stateExt:o; or the single port
    ports: Vec<Arc<Port>>,
    /// Which of `ports` get the joint positions (state:o, or the single port) and the
    /// whole joint data (stateExt:o, none in single-port mode).
    state: usize,
    state_ext: Option<usize>,
    slot: Slot,
    /// The generations of the state readers (4.0's `jointData` differs).
    readers: PeerGenerations,
    period: Duration,
    tasks: Vec<JoinHandle<()>>,
    publisher: Option<Publisher>,
}

/// The state publisher thread; it ends within a period once stopped.
struct Publisher {
    stop: Arc<AtomicBool>,
    thread: std::thread::JoinHandle<()>,
}

impl Publisher {
    fn start(
        slot: Slot,
        readers: PeerGenerations,
        state: &Arc<Port>,
        state_ext: Option<&Arc<Port>>,
        period: Duration,
    ) -> Option<Self> {
        let stop = Arc::new(AtomicBool::new(false));
        let (s, st, ext) = (
            stop.clone(),
            Arc::downgrade(state),
            state_ext.map(Arc::downgrade),
        );
        match std::thread::Builder::new()
            .name("cb_nws state:o".into())
            .spawn(move || publish(&slot, &readers, &st, ext.as_ref(), period, &s))
        {
            Ok(thread) => Some(Publisher { stop, thread }),
            Err(e) => {
                tracing::error!(
                    "{NAME} {}: cannot start the state publisher: {e}",
                    state.name()
                );
                None
            }
        }
    }

    fn stop(&self) {
        self.stop.store(true, Ordering::Relaxed);
    }
}

impl ControlBoardNws {
    /// Opens the ports under `name` and serves `device`, publishing every 20 ms
    /// (the C++ default period).
    pub async fn open(
        name: &str,
        ns: NameClient,
        device: SharedDevice,
    ) -> Result<ControlBoardNws, PortError> {
        let mut nws = Self::open_ports(name, ns, DEFAULT_PERIOD).await?;
        if let Err(e) = nws.attach(device) {
            // the caller asked for a served device; an unusable one is reported on rpc
            tracing::warn!("{NAME} {}: cannot attach: {e}", nws.prefix);
        }
        Ok(nws)
    }

    /// Opens the four ports under `name` (with or without a leading `/`); nothing is
    /// served until [`ControlBoardNws::attach`] (RPCs answer `[fail]`).
    pub async fn open_ports(
        name: &str,
        ns: NameClient,
        period: Duration,
    ) -> Result<ControlBoardNws, PortError> {
        let prefix = port_prefix(name);
        let rpc_name = format!("{prefix}/rpc:i");
        let rpc = Arc::new(Port::open(&rpc_name, ns.clone()).await?);
        let command = Arc::new(Port::open(&format!("{prefix}/command:i"), ns.clone()).await?);
        let state = Arc::new(Port::open(&format!("{prefix}/state:o"), ns.clone()).await?);
        let state_ext = Arc::new(Port::open(&format!("{prefix}/stateExt:o"), ns.clone()).await?);
        // YARP 4.0's clients ask here, in its thrift form
        let rpc4 = Arc::new(Port::open(&format!("{prefix}/nws/rpc:i"), ns.clone()).await?);
        let slot: Slot = Arc::new(Mutex::new(None));
        let readers = PeerGenerations::new(ns.clone());
        let tasks = vec![
            tokio::spawn(serve_rpc(rpc.clone(), slot.clone())),
            tokio::spawn(serve_commands(command.clone(), slot.clone())),
            tokio::spawn(serve_rpc4(rpc4.clone(), slot.clone())),
        ];
        Ok(ControlBoardNws {
            rpc_contact: rpc.contact().clone(),
            rpc_name,
            prefix,
            ports: vec![rpc, command, state, state_ext, rpc4],
            state: 2,
            state_ext: Some(3),
            slot,
            readers,
            period,
            tasks,
            publisher: None,
        })
    }

    /// Opens the one port `name` of the single-port mode (YARP 2's `--single_port`):
    /// commands, RPC and the joint-position stream share it. Nothing is served until
    /// [`ControlBoardNws::attach`].
    pub async fn open_single_port(
        name: &str,
        ns: NameClient,
        period: Duration,
    ) -> Result<ControlBoardNws, PortError> {
        let prefix = port_prefix(name);
        let port = Arc::new(Port::open(&prefix, ns.clone()).await?);
        let slot: Slot = Arc::new(Mutex::new(None));
        let tasks = vec![tokio::spawn(serve_single_port(port.clone(), slot.clone()))];
        Ok(ControlBoardNws {
            rpc_contact: port.contact().clone(),
            rpc_name: prefix.clone(),
            prefix,
            ports: vec![port],
            state: 0,
            state_ext: None,
            slot,
            readers: PeerGenerations::new(ns),
            period,
            tasks,
            publisher: None,
        })
    }

    /// The port prefix (`/icub/left_arm`).
    pub fn prefix(&self) -> &str {
        &self.prefix
    }

    /// The RPC port's name (the single port's name in single-port mode).
    pub fn rpc_name(&self) -> &str {
        &self.rpc_name
    }

    /// Where the RPC port listens.
    pub fn contact(&self) -> &Contact {
        &self.rpc_contact
    }

    /// The publishing period.
    pub fn period(&self) -> Duration {
        self.period
    }

    /// Serves `device` and starts publishing its state; fails if a device is attached
    /// already or the device reports no joints.
    pub fn attach(&mut self, device: SharedDevice) -> DevResult<()> {
        if lock(&self.slot).is_some() {
            return Err(DeviceError::Unsupported(
                "controlBoard_nws_yarp already serves a device (detach it first)",
            ));
        }
        let axes = {
            let mut pd = lock(&device);
            axes_of(pd.device())?
        };
        *lock(&self.slot) = Some(Attached { device, axes });
        self.publisher = Publisher::start(
            self.slot.clone(),
            self.readers.clone(),
            &self.ports[self.state],
            self.state_ext.map(|i| &self.ports[i]),
            self.period,
        );
        Ok(())
    }

    /// Stops serving the device (the ports stay open).
    pub fn detach(&mut self) {
        if let Some(p) = self.publisher.take() {
            p.stop();
        }
        *lock(&self.slot) = None;
    }

    /// Stops serving and closes the ports (unregistering them).
    pub async fn close(mut self) {
        if let Some(p) = self.publisher.take() {
            p.stop();
            // it holds the state ports now and then: let go of them before closing
            let _ = tokio::task::spawn_blocking(move || p.thread.join()).await;
        }
        self.detach();
        for t in self.tasks.drain(..) {
            t.abort();
            let _ = t.await;
        }
        for p in std::mem::take(&mut self.ports) {
            if let Ok(port) = Arc::try_unwrap(p) {
                port.close().await;
            }
        }
    }
}

impl Drop for ControlBoardNws {
    fn drop(&mut self) {
        if let Some(p) = self.publisher.take() {
            p.stop();
        }
        for t in &self.tasks {
            t.abort();
        }
    }
}

/// The joint count of a device, from the first motor interface it has (as C++).
fn axes_of(dev: &mut dyn DeviceDriver) -> DevResult<usize> {
    let n = if let Some(e) = dev.as_encoders() {
        e.get_axes()?
    } else if let Some(p) = dev.as_position_control() {
        p.get_axes()?
    } else if let Some(v) = dev.as_velocity_control() {
        v.get_axes()?
    } else if let Some(t) = dev.as_torque_control() {
        t.get_axes()?
    } else {
        return Err(DeviceError::Unsupported(
            "controlBoard_nws_yarp needs a device with encoders, position, velocity or torque control",
        ));
    };
    if n == 0 {
        return Err(DeviceError::Unsupported(
            "controlBoard_nws_yarp: the attached device has no joints",
        ));
    }
    Ok(n)
}

fn attached(slot: &Slot) -> Option<Attached> {
    lock(slot).clone()
}

async fn serve_rpc(port: Arc<Port>, slot: Slot) {
    let mut stamp = RpcStamp::new();
    while let Some(mut msg) = port.read().await {
        let reply = match msg.bottle() {
            Err(e) => {
                tracing::warn!(
                    "{}: undecodable command from {}: {e}",
                    port.name(),
                    msg.from
                );
                fail()
            }
            Ok(cmd) => match attached(&slot) {
                Some(a) => crate::runtime::device_call(|| {
                    match remote_calibrator_target(&cmd, &a.device) {
                        Some(calibrator) => match calibrator.try_lock() {
                            Some(mut c) => handle_rpc(&cmd, c.device(), &mut stamp),
                            // busy with a procedure: only a quit can reach it
                            None if is_quit(&cmd) => match quit_signal(&a.device) {
                                Some(_) => ok(),
                                None => fail(),
                            },
                            None => {
                                tracing::warn!("{}: `{cmd}`: the calibrator is busy", port.name());
                                fail()
                            }
                        },
                        None => handle_rpc(&cmd, lock(&a.device).device(), &mut stamp),
                    }
                }),
                None => {
                    tracing::warn!("{}: `{cmd}` but no device is attached", port.name());
                    fail()
                }
            },
        };
        msg.reply(reply);
    }
}

/// YARP 4.0's RPC (`<name>/nws/rpc:i`): thrift calls, answered as C++ 4.0 answers them.
async fn serve_rpc4(port: Arc<Port>, slot: Slot) {
    while let Some(mut msg) = port.read().await {
        let reply = match (msg.bottle(), attached(&slot)) {
            (Ok(cmd), Some(a)) => crate::runtime::device_call(|| {
                super::v4::handle_rpc(&cmd, lock(&a.device).device())
            }),
            (Err(e), _) => {
                tracing::warn!("{}: undecodable call from {}: {e}", port.name(), msg.from);
                crate::thrift::fail_reply()
            }
            (Ok(cmd), None) => {
                tracing::warn!("{}: `{cmd}` but no device is attached", port.name());
                crate::thrift::fail_reply()
            }
        };
        msg.reply_encoded(reply);
    }
}

/// For `[set] [reca] …`, the calibrator device the attached part forwards to (C++
/// `getCalibratorDevice`): the request is served by it with the part unlocked, because
/// calibrating, homing or parking takes seconds and the state streams and the other
/// clients of the part must go on meanwhile.
fn remote_calibrator_target(cmd: &Bottle, part: &SharedDevice) -> Option<SharedDevice> {
    match Request::from_v3(cmd)? {
        Request::IsCalibratorPresent(_) => return None,
        r if !r.is_remote_calibrator() => return None,
        _ => {}
    }
    lock(part)
        .device()
        .as_remote_calibrator()?
        .calibrator_device()
}

/// `[set] [reca] [quca|qupa]`.
fn is_quit(cmd: &Bottle) -> bool {
    matches!(
        Request::from_v3(cmd),
        Some(Request::QuitCalibrate(_) | Request::QuitPark(_))
    )
}

/// Raises the quit flag of the part's calibrator, which is busy with a procedure (the
/// part keeps the flag from when the calibrator became its calibrator device).
fn quit_signal(part: &SharedDevice) -> Option<()> {
    let flag = lock(part).device().as_remote_calibrator()?.quit_signal()?;
    flag.store(true, std::sync::atomic::Ordering::SeqCst);
    Some(())
}

fn ok() -> Bottle {
    let mut b = Bottle::new();
    b.push(yarp_proto::Vocab32(crate::vocabs::OK));
    b
}

fn fail() -> Bottle {
    let mut b = Bottle::new();
    b.push(Vocab32(FAILED));
    b
}

/// The single port: every message is a command (YARP 2 also took streamed ones), answered
/// as a device responder when the sender waits for a reply.
async fn serve_single_port(port: Arc<Port>, slot: Slot) {
    let mut stamp = RpcStamp::new();
    while let Some(mut msg) = port.read().await {
        let reply = match msg.bottle() {
            Err(e) => {
                tracing::warn!(
                    "{}: undecodable command from {}: {e}",
                    port.name(),
                    msg.from
                );
                fail()
            }
            Ok(cmd) => match attached(&slot) {
                Some(a) => crate::runtime::device_call(|| {
                    handle_single_port(&cmd, lock(&a.device).device(), &mut stamp, a.axes)
                }),
                None => {
                    tracing::warn!("{}: `{cmd}` but no device is attached", port.name());
                    fail()
                }
            },
        };
        msg.reply_as_responder(reply);
    }
}

async fn serve_commands(port: Arc<Port>, slot: Slot) {
    while let Some(msg) = port.read().await {
        let cmd = msg
            .bottle()
            .map_err(|e| e.to_string())
            .and_then(|b| CommandMessage::from_bottle(&b).map_err(|e| e.to_string()));
        let result = match (cmd, attached(&slot)) {
            (Err(e), _) => Err(e),
            (Ok(_), None) => Err("no device is attached".to_string()),
            (Ok(cmd), Some(a)) => crate::runtime::device_call(|| {
                handle_command(&cmd, lock(&a.device).device(), a.axes)
            })
            .map_err(|e| e.to_string()),
        };
        if let Err(e) = result {
            tracing::warn!(
                "{}: streaming command from {} ignored: {e}",
                port.name(),
                msg.from
            );
        }
    }
}

/// Publishes `state:o` and `stateExt:o` every `period` (C++ `ControlBoard_nws_yarp::run`)
/// until stopped, detached or the ports are gone; in single-port mode the positions go
/// out on the single port and there is no `stateExt:o`.
fn publish(
    slot: &Slot,
    readers: &PeerGenerations,
    state: &Weak<Port>,
    state_ext: Option<&Weak<Port>>,
    period: Duration,
    stop: &AtomicBool,
) {
    let mut tick = Ticker::new(period);
    let mut count: i32 = 0;
    let mut warned = false;
    loop {
        tick.tick_blocking();
        if stop.load(Ordering::Relaxed) {
            return;
        }
        let Some(state) = state.upgrade() else { return };
        let state_ext = match state_ext.map(Weak::upgrade) {
            Some(None) => return,
            Some(Some(p)) => Some(p),
            None => None,
        };
        let Some(a) = attached(slot) else { return };
        let to_state = state.has_outputs();
        let to_ext = state_ext.filter(|p| p.has_outputs());
        if !to_state && to_ext.is_none() {
            // nobody listens: keep the sequence going without reading the board
            count = if count == i32::MAX { 0 } else { count + 1 };
            continue;
        }
        let (data, times) = JointData::read(lock(&a.device).device(), a.axes);
        // without encoder timestamps C++ averages its zero-initialised times
        let time = if times.is_empty() {
            Some(0.0)
        } else {
            envelope_time(&times)
        };
        let Some(time) = time else {
            if !warned {
                tracing::error!(
                    "{}: encoder timestamps are not consistent; state not published",
                    state.name()
                );
                warned = true;
            }
            continue;
        };
        let stamp = Stamp::new(count, time);
        count = if count == i32::MAX { 0 } else { count + 1 };
        // each reader in its generation (4.0's jointData has temperatures and float
        // PWMs; its doubles are tagged anew), asked first when new
        let mut outs = state.outputs();
        outs.extend(to_ext.iter().flat_map(|p| p.outputs()));
        crate::wrapper_ports::learn_readers(outs, readers);
        if let Some(state_ext) = to_ext {
            state_ext.write_nowait_forms(
                readers,
                || data.to_bottle(),
                || data.to_bottle_as(Generation::V4),
                Some(stamp),
            );
        }
        if to_state {
            let positions = positions_bottle(&data.joint_position.values);
            state.write_nowait_by_generation(&positions, readers, Some(stamp));
        }
    }
}

/// `controlBoard_nws_yarp` as a registered device: `name` (port prefix, required) and
/// `period` (seconds, a float as C++ requires, default 0.02); serves the device given
/// by `attach` / `attach_all` (exactly one) or by `subdevice`. With `single_port` (a
/// flag, as YARP 2's `controlboard`) it opens the one port `name` instead of four.
#[derive(Default)]
pub struct ControlBoardNwsDevice {
    server: Option<ControlBoardNws>,
}

impl ControlBoardNwsDevice {
    pub fn new() -> Self {
        Self::default()
    }

    /// The running server, once opened.
    pub fn server(&self) -> Option<&ControlBoardNws> {
        self.server.as_ref()
    }

    fn server_mut(&mut self) -> DevResult<&mut ControlBoardNws> {
        self.server.as_mut().ok_or(DeviceError::NotOpen)
    }
}

/// Reads `period` as C++ does: a float number of seconds, greater than zero.
impl DeviceDriver for ControlBoardNwsDevice {
    fn parameters(&self) -> Vec<crate::params::ParamSpec> {
        ControlBoardNwsYarpParams::PARAMS.to_vec()
    }

    fn open(&mut self, config: &yarp_proto::Property) -> DevResult<()> {
        let p = ControlBoardNwsYarpParams::read(config)?;
        let name = p.name;
        let period = Duration::from_secs_f64(p.period.0);
        let network = |e: String| DeviceError::BadParam {
            device: NAME.into(),
            param: "name".into(),
            expected: "a port prefix that can be registered (is the name server running?)",
            got: format!("{name}: {e}"),
        };
        let ns = yarp_net::network::name_client().map_err(|e| network(e.to_string()))?;
        let prefix = name.clone();
        let single = p.single_port;
        let server = runtime::block_on_result(async move {
            if single {
                ControlBoardNws::open_single_port(&prefix, ns, period).await
            } else {
                ControlBoardNws::open_ports(&prefix, ns, period).await
            }
            .map_err(|e| e.to_string())
        })
        .map_err(network)?;
        if let Some(old) = self.server.replace(server) {
            runtime::block_on_logged("nws: closing", old.close());
        }
        Ok(())
    }

    fn close(&mut self) -> DevResult<()> {
        if let Some(s) = self.server.take() {
            runtime::block_on_logged("nws: closing", s.close());
        }
        Ok(())
    }

    crate::views!(as_wrapper, as_multiple_wrapper);
}

impl IWrapper for ControlBoardNwsDevice {
    fn attach(&mut self, device: SharedDevice) -> DevResult<()> {
        self.server_mut()?.attach(device)
    }

    fn detach(&mut self) -> DevResult<()> {
        self.server_mut()?.detach();
        Ok(())
    }
}

crate::one_device_multiple_wrapper!(
    ControlBoardNwsDevice,
    "controlBoard_nws_yarp attaches exactly one device (join several with controlboardremapper)"
);
