//! The `cartesiancontrollerserver` device: a [`ServerCore`] with its ports, the boards it
//! is attached to and its control thread.
//!
//! * `/<ctrl>/rpc:i`, `/<ctrl>/command:i`, `/<ctrl>/state:o`, `/<ctrl>/events:o`;
//! * toward the solver `SolverNameToConnect`: `/<ctrl>/<slv>/in` (from `/<slv>/out`, udp),
//!   `/<ctrl>/<slv>/out` (to `/<slv>/in`, udp) and `/<ctrl>/<slv>/rpc` (to `/<slv>/rpc`),
//!   connected at attach and retried every second while the solver is away.
//!
//! The thread reads the encoders every `ControllerPeriod`, steps the controller and
//! sends position-direct references (or velocities, `PositionControl off`).

use parking_lot::Mutex;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};
use yarp_devices::driver::{DeviceDriver, IMultipleWrapper, SharedDevice};
use yarp_devices::error::{DevResult, DeviceError};
use yarp_devices::{runtime, vocabs};
use yarp_net::port::Port;
use yarp_proto::{Bottle, Property, Stamp};

use crate::protocol::nack;
use crate::server::{
    CartesianControllerServerParams, CycleOutput, Reply, ServerConfig, ServerCore, SolverLink, NAME,
};

/// How long a solver RPC may take before the solver counts as gone.
const SOLVER_RPC_TIMEOUT: Duration = Duration::from_secs(5);

type SharedCore = Arc<Mutex<Option<ServerCore>>>;

/// What `rpc:i` and `command:i` did to the motion (a stop, its events), for the control
/// thread to carry out and send.
type Pending = Arc<Mutex<CycleOutput>>;

/// Adds what a command did to what the thread will apply.
fn defer(pending: &Pending, out: CycleOutput) {
    if out.stop || !out.events.is_empty() {
        let mut p = pending.lock();
        p.stop |= out.stop;
        p.events.extend(out.events);
    }
}

/// The ports of a server.
struct Ports {
    rpc: Arc<Port>,
    command: Arc<Port>,
    state: Arc<Port>,
    events: Arc<Port>,
    slv_in: Arc<Port>,
    slv_out: Arc<Port>,
    slv_rpc: Arc<Port>,
}

impl Ports {
    fn all(&self) -> [&Arc<Port>; 7] {
        [
            &self.rpc,
            &self.command,
            &self.state,
            &self.events,
            &self.slv_in,
            &self.slv_out,
            &self.slv_rpc,
        ]
    }
}

/// The solver's ports as the core uses them.
#[derive(Clone)]
struct PortLink {
    out: Arc<Port>,
    rpc: Arc<Port>,
}

impl SolverLink for PortLink {
    fn rpc(&mut self, cmd: &Bottle) -> Option<Bottle> {
        let (rpc, cmd) = (self.rpc.clone(), cmd.clone());
        runtime::block_on_within(SOLVER_RPC_TIMEOUT, async move { rpc.rpc(&cmd).await.ok() })
            .ok()
            .flatten()
    }

    fn send(&mut self, target: &Bottle) {
        let (out, b) = (self.out.clone(), target.clone());
        runtime::block_on_logged("cartesiancontrollerserver: target", async move {
            out.write_strict(&b, None).await;
        });
    }
}

/// The latest token the solver answered, for sync `[go]`s waiting on it.
type TokenWatch = tokio::sync::watch::Sender<f64>;

/// `cartesiancontrollerserver`.
#[derive(Default)]
pub struct CartesianControllerServer {
    config: Option<ServerConfig>,
    ports: Option<Arc<Ports>>,
    core: SharedCore,
    tasks: Vec<tokio::task::JoinHandle<()>>,
    thread: Option<(Arc<AtomicBool>, std::thread::JoinHandle<()>)>,
    /// The solver's latest answer, taken by the control thread.
    latest: Arc<Mutex<Option<Bottle>>>,
    pending: Pending,
    tokens: Option<Arc<TokenWatch>>,
}

impl CartesianControllerServer {
    pub fn new() -> Self {
        Self::default()
    }

    /// The name of the state port (`/<ControllerName>/state:o`), once opened.
    pub fn state_port_name(&self) -> Option<String> {
        self.ports.as_ref().map(|p| p.state.name().to_string())
    }

    fn stop_thread(&mut self) {
        if let Some((stop, t)) = self.thread.take() {
            stop.store(true, Ordering::SeqCst);
            let _ = t.join();
        }
    }
}

impl Drop for CartesianControllerServer {
    fn drop(&mut self) {
        let _ = self.close();
    }
}

fn open_ports(cfg: &ServerConfig) -> DevResult<Ports> {
    let ctrl = format!("/{}", cfg.name);
    let slv = format!("{ctrl}/{}", cfg.solver);
    let names = [
        format!("{ctrl}/rpc:i"),
        format!("{ctrl}/command:i"),
        format!("{ctrl}/state:o"),
        format!("{ctrl}/events:o"),
        format!("{slv}/in"),
        format!("{slv}/out"),
        format!("{slv}/rpc"),
    ];
    let refused = |why: String| DeviceError::BadParam {
        device: NAME.into(),
        param: "GENERAL::ControllerName".into(),
        expected: "a port prefix that can be registered (is the name server running?)",
        got: why,
    };
    let ns = yarp_net::network::name_client().map_err(|e| refused(e.to_string()))?;
    let opened = runtime::block_on_result(async move {
        let mut opened = Vec::new();
        for n in names {
            match Port::open(&n, ns.clone()).await {
                Ok(p) => opened.push(Arc::new(p)),
                Err(e) => {
                    for p in opened {
                        if let Ok(p) = Arc::try_unwrap(p) {
                            p.close().await;
                        }
                    }
                    return Err(format!("{n}: {e}"));
                }
            }
        }
        Ok(opened)
    })
    .map_err(refused)?;
    let mut it = opened.into_iter();
    let mut next = || it.next().expect("seven ports");
    Ok(Ports {
        rpc: next(),
        command: next(),
        state: next(),
        events: next(),
        slv_in: next(),
        slv_out: next(),
        slv_rpc: next(),
    })
}

impl DeviceDriver for CartesianControllerServer {
    fn parameters(&self) -> Vec<yarp_devices::params::ParamSpec> {
        CartesianControllerServerParams::PARAMS.to_vec()
    }

    fn open(&mut self, config: &Property) -> DevResult<()> {
        let cfg = ServerConfig::from_property(config)?;
        self.close()?;
        let ports = Arc::new(open_ports(&cfg)?);
        let link = PortLink {
            out: ports.slv_out.clone(),
            rpc: ports.slv_rpc.clone(),
        };
        let (tokens, _) = tokio::sync::watch::channel(f64::NEG_INFINITY);
        let tokens = Arc::new(tokens);
        let rt = runtime::handle();
        self.tasks.push(rt.spawn(serve_rpc(
            ports.rpc.clone(),
            self.core.clone(),
            link.clone(),
            tokens.clone(),
            self.pending.clone(),
        )));
        self.tasks.push(rt.spawn(serve_commands(
            ports.command.clone(),
            self.core.clone(),
            link,
            self.pending.clone(),
        )));
        self.tasks
            .push(rt.spawn(keep_latest(ports.slv_in.clone(), self.latest.clone())));
        self.tokens = Some(tokens);
        self.ports = Some(ports);
        self.config = Some(cfg);
        Ok(())
    }

    fn close(&mut self) -> DevResult<()> {
        self.stop_thread();
        for t in self.tasks.drain(..) {
            t.abort();
        }
        *self.core.lock() = None;
        if let Some(ports) = self.ports.take() {
            let ports: Vec<Arc<Port>> = ports.all().into_iter().cloned().collect();
            runtime::block_on_logged("cartesiancontrollerserver: closing", async move {
                for p in ports {
                    // tasks just aborted may still hold a clone for a moment
                    for _ in 0..50 {
                        if Arc::strong_count(&p) == 1 {
                            break;
                        }
                        tokio::time::sleep(Duration::from_millis(10)).await;
                    }
                    if let Ok(p) = Arc::try_unwrap(p) {
                        p.close().await;
                    }
                }
            });
        }
        Ok(())
    }

    yarp_devices::views!(as_multiple_wrapper);
}

/// The attached boards, in the drivers' order, with their axes.
struct Boards {
    devices: Vec<SharedDevice>,
    /// `(driver, axis)` of each link, in chain order.
    links: Vec<(usize, usize)>,
}

impl Boards {
    /// Encoders of every link \[deg\].
    fn feedback(&self) -> DevResult<Vec<f64>> {
        let per_board: Vec<Vec<f64>> = self
            .devices
            .iter()
            .map(|b| {
                let mut pd = b.lock();
                pd.device()
                    .as_encoders()
                    .ok_or(DeviceError::NotOpen)?
                    .get_encoders()
            })
            .collect::<DevResult<_>>()?;
        self.links
            .iter()
            .map(|&(d, a)| {
                per_board[d].get(a).copied().ok_or(DeviceError::WrongSize {
                    expected: a + 1,
                    got: per_board[d].len(),
                })
            })
            .collect()
    }

    /// Position-direct references (or velocities) of the released links, part by part.
    fn command(&self, released: &[usize], values: &[f64], velocity: bool) -> DevResult<()> {
        for (d, dev) in self.devices.iter().enumerate() {
            let (joints, refs): (Vec<usize>, Vec<f64>) = released
                .iter()
                .zip(values)
                .filter(|(&l, _)| self.links[l].0 == d)
                .map(|(&l, &v)| (self.links[l].1, v))
                .unzip();
            if joints.is_empty() {
                continue;
            }
            let mut pd = dev.lock();
            if velocity {
                let vel = pd
                    .device()
                    .as_velocity_control()
                    .ok_or(DeviceError::Unsupported("no IVelocityControl"))?;
                for (j, v) in joints.iter().zip(&refs) {
                    vel.velocity_move(*j, *v)?;
                }
            } else {
                pd.device()
                    .as_position_direct()
                    .ok_or(DeviceError::Unsupported("no IPositionDirect"))?
                    .set_positions_group(&joints, &refs)?;
            }
        }
        Ok(())
    }

    /// The control mode the motion needs on the released links.
    fn set_mode(&self, released: &[usize], velocity: bool) {
        let mode = if velocity {
            vocabs::CM_VELOCITY
        } else {
            vocabs::CM_POSITION_DIRECT
        };
        for &l in released {
            let (d, a) = self.links[l];
            let mut pd = self.devices[d].lock();
            if let Some(cm) = pd.device().as_control_mode() {
                if cm.get_control_mode(a).ok() != Some(mode) {
                    let _ = cm.set_control_mode(a, mode);
                }
            }
        }
    }

    fn stop(&self, released: &[usize]) {
        for &l in released {
            let (d, a) = self.links[l];
            let mut pd = self.devices[d].lock();
            if let Some(p) = pd.device().as_position_control() {
                let _ = p.stop(a);
            }
        }
    }
}

impl IMultipleWrapper for CartesianControllerServer {
    fn attach_all(&mut self, devices: &[(String, SharedDevice)]) -> DevResult<()> {
        let (Some(cfg), Some(ports), Some(tokens)) =
            (self.config.clone(), self.ports.clone(), self.tokens.clone())
        else {
            return Err(DeviceError::NotOpen);
        };
        let mut boards = Vec::new();
        for d in &cfg.drivers {
            let Some((_, dev)) = devices.iter().find(|(k, _)| *k == d.key) else {
                return Err(DeviceError::MissingParam {
                    device: NAME.into(),
                    param: format!("attach network `{}` (DRIVER Key)", d.key),
                });
            };
            boards.push(dev.clone());
        }
        let axes = boards
            .iter()
            .map(|b| {
                let mut pd = b.lock();
                pd.device()
                    .as_encoders()
                    .ok_or(DeviceError::Unsupported(
                        "cartesiancontrollerserver: an attached device has no encoders",
                    ))?
                    .get_axes()
            })
            .collect::<DevResult<Vec<usize>>>()?;
        let probe = ServerCore::new(cfg.clone(), &[])?;
        let links = probe.link_map(&axes);
        if links.len() < probe.links() {
            return Err(DeviceError::WrongSize {
                expected: probe.links(),
                got: links.len(),
            });
        }
        // the joints' bounds, as C++'s alignJointsBounds asks them
        let mut limits = Vec::new();
        for (cnt, &(d, a)) in links.iter().enumerate() {
            let mut pd = boards[d].lock();
            let lim = pd
                .device()
                .as_control_limits()
                .ok_or(DeviceError::Unsupported(
                    "cartesiancontrollerserver: an attached device has no IControlLimits",
                ))?;
            limits.push(lim.get_limits(a).map_err(|e| {
                DeviceError::failed(NAME, format!("joint #{cnt}: failed getting limits! ({e})"))
            })?);
        }
        for &(d, a) in &links {
            let mut pd = boards[d].lock();
            if let Some(p) = pd.device().as_position_control() {
                let _ = p.set_ref_acceleration(a, f64::MAX);
            }
        }
        let core = ServerCore::new(cfg.clone(), &limits)?;
        self.stop_thread();
        *self.core.lock() = Some(core);
        let boards = Boards {
            devices: boards,
            links,
        };
        let stop = Arc::new(AtomicBool::new(false));
        let ctx = Loop {
            core: self.core.clone(),
            pending: self.pending.clone(),
            ports,
            boards,
            latest: self.latest.clone(),
            tokens,
            stop: stop.clone(),
            period: cfg.period,
            timeout: cfg.robot_timeout,
            velocity: !cfg.position_control,
        };
        let t = std::thread::Builder::new()
            .name(format!("cartesian {}", cfg.name))
            .spawn(move || ctx.run())
            .map_err(|e| DeviceError::failed(NAME, format!("cannot start its thread: {e}")))?;
        self.thread = Some((stop, t));
        Ok(())
    }

    fn detach_all(&mut self) -> DevResult<()> {
        self.stop_thread();
        if let Some(ports) = &self.ports {
            if let Some(core) = self.core.lock().as_ref() {
                if core.is_connected() {
                    closing_event(&ports.events);
                }
            }
        }
        *self.core.lock() = None;
        Ok(())
    }
}

/// Sleeps until `next`; a late period starts the next one now.
fn sleep_until(next: &mut Instant) {
    let now = Instant::now();
    if *next > now {
        std::thread::sleep(*next - now);
    } else {
        *next = now;
    }
}

fn now_seconds() -> f64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_secs_f64())
        .unwrap_or(0.0)
}

fn closing_event(port: &Arc<Port>) {
    let b = Bottle::new().with("closing").with(now_seconds());
    let port = port.clone();
    runtime::block_on_logged("cartesiancontrollerserver: closing", async move {
        port.write_strict(&b, Some(Stamp::new(0, now_seconds())))
            .await;
    });
}

/// The control thread's context.
struct Loop {
    core: SharedCore,
    pending: Pending,
    ports: Arc<Ports>,
    boards: Boards,
    latest: Arc<Mutex<Option<Bottle>>>,
    tokens: Arc<TokenWatch>,
    stop: Arc<AtomicBool>,
    period: Duration,
    timeout: Duration,
    velocity: bool,
}

impl Loop {
    fn link(&self) -> PortLink {
        PortLink {
            out: self.ports.slv_out.clone(),
            rpc: self.ports.slv_rpc.clone(),
        }
    }

    /// `connectToSolver`: the solver's `/in` exists, the three connections are made.
    fn connect(&self) -> bool {
        let Ok(ns) = yarp_net::network::name_client() else {
            return false;
        };
        let slv = self.core.lock().as_ref().map(|c| c.config().solver.clone());
        let Some(slv) = slv else { return false };
        let ports = self.ports.clone();
        runtime::block_on_within(Duration::from_secs(10), async move {
            let slv = format!("/{slv}");
            if !yarp_net::network::exists(&ns, &format!("{slv}/in"))
                .await
                .unwrap_or(false)
            {
                return false;
            }
            let a = yarp_net::network::connect(
                &ns,
                &format!("{slv}/out"),
                ports.slv_in.name(),
                Some("udp"),
            )
            .await
            .is_ok_and(|(ok, _)| ok);
            let b = ports
                .slv_out
                .connect(&format!("{slv}/in"), Some("udp"))
                .await
                .is_ok();
            let c = ports
                .slv_rpc
                .connect(&format!("{slv}/rpc"), None)
                .await
                .is_ok();
            a && b && c
        })
        .unwrap_or(false)
    }

    fn run(self) {
        let mut next = Instant::now();
        let mut last_try: Option<Instant> = None;
        let mut last_ok = Instant::now();
        let mut reported = false;
        let mut count: i32 = 0;
        let mut events: i32 = 0;
        let mut link = self.link();
        while !self.stop.load(Ordering::SeqCst) {
            next += self.period;
            let connected = self.core.lock().as_ref().is_some_and(|c| c.is_connected());
            if !connected && last_try.is_none_or(|t| t.elapsed() >= Duration::from_secs(1)) {
                last_try = Some(Instant::now());
                if self.connect() {
                    if let Some(c) = self.core.lock().as_mut() {
                        if c.on_connected(&mut link) {
                            tracing::info!("{}: connected to the solver", self.ports.rpc.name());
                        }
                    }
                }
            }
            // as C++: nothing is read or streamed before the solver is there
            if !self.core.lock().as_ref().is_some_and(|c| c.is_connected()) {
                sleep_until(&mut next);
                continue;
            }
            let fb = runtime::device_call(|| self.boards.feedback());
            match fb {
                Ok(fb) => {
                    last_ok = Instant::now();
                    reported = false;
                    let latest = self.latest.lock().take();
                    let now = now_seconds();
                    let out = {
                        let mut core = self.core.lock();
                        let Some(core) = core.as_mut() else { break };
                        let mut out = core.cycle(now, &fb, latest.as_ref(), true, &mut link);
                        let asked = std::mem::take(&mut *self.pending.lock());
                        out.stop |= asked.stop;
                        out.events.splice(0..0, asked.events);
                        (out, core.released())
                    };
                    self.apply(out.0, &out.1, now, &mut count, &mut events);
                }
                Err(e) if !reported && last_ok.elapsed() >= self.timeout => {
                    tracing::error!(
                        "{}: no valid encoders for {:?} ({e})",
                        self.ports.rpc.name(),
                        self.timeout
                    );
                    reported = true;
                }
                Err(_) => {}
            }
            sleep_until(&mut next);
        }
    }

    fn apply(
        &self,
        out: CycleOutput,
        released: &[usize],
        now: f64,
        count: &mut i32,
        events: &mut i32,
    ) {
        if out.events.iter().any(|e| e.name == "motion-onset") {
            self.boards.set_mode(released, self.velocity);
        }
        let sent = match (&out.positions, &out.velocities) {
            (Some(p), _) => self.boards.command(released, p, false),
            (_, Some(v)) => self.boards.command(released, v, true),
            _ => Ok(()),
        };
        if let Err(e) = sent {
            tracing::warn!("{}: commanding the joints: {e}", self.ports.rpc.name());
        }
        if out.stop {
            if self.velocity {
                let _ = self
                    .boards
                    .command(released, &vec![0.0; released.len()], true);
            } else {
                self.boards.stop(released);
            }
        }
        if let Some(t) = out.rx_token {
            self.tokens.send_replace(t);
        }
        let (state, evp) = (self.ports.state.clone(), self.ports.events.clone());
        let state_msg = out.state.filter(|_| state.has_outputs()).map(|x| {
            (
                x.iter().copied().collect::<Bottle>(),
                Stamp::new(*count, now),
            )
        });
        *count = if *count == i32::MAX { 0 } else { *count + 1 };
        let mut event_msgs = Vec::new();
        if evp.has_outputs() {
            for e in &out.events {
                let mut b = Bottle::new().with(e.name).with(e.time);
                if let Some(cp) = e.checkpoint {
                    b.push(cp);
                }
                event_msgs.push((b, Stamp::new(*events, e.time)));
                *events = events.wrapping_add(1);
            }
        }
        if state_msg.is_none() && event_msgs.is_empty() {
            return;
        }
        runtime::block_on_logged("cartesiancontrollerserver: streams", async move {
            if let Some((b, s)) = state_msg {
                state.write_nowait(&b, Some(s));
            }
            for (b, s) in event_msgs {
                evp.write_strict(&b, Some(s)).await;
            }
        });
    }
}

async fn serve_rpc(
    port: Arc<Port>,
    core: SharedCore,
    link: PortLink,
    tokens: Arc<TokenWatch>,
    pending: Pending,
) {
    while let Some(mut msg) = port.read().await {
        let cmd = msg.bottle().unwrap_or_default();
        let mut link = link.clone();
        let core2 = core.clone();
        let pending2 = pending.clone();
        let reply = runtime::device_call(move || {
            let mut out = CycleOutput::default();
            let reply = match core2.lock().as_mut() {
                Some(c) => c.respond(&cmd, &mut link, &mut out),
                None => Reply::Now(nack()),
            };
            defer(&pending2, out);
            reply
        });
        let reply = match reply {
            Reply::Now(b) => b,
            Reply::AfterToken(token) => {
                // as C++: no time limit, the client's own timeout decides
                let mut rx = tokens.subscribe();
                let _ = rx.wait_for(|t| *t >= token).await;
                crate::protocol::ack()
            }
        };
        if msg.wants_reply() {
            msg.reply(reply);
        }
    }
}

async fn serve_commands(port: Arc<Port>, core: SharedCore, link: PortLink, pending: Pending) {
    while let Some(msg) = port.read().await {
        let Ok(b) = msg.bottle() else { continue };
        let mut link = link.clone();
        let (core, pending) = (core.clone(), pending.clone());
        runtime::device_call(move || {
            if let Some(c) = core.lock().as_mut() {
                let out = c.on_command(&b, &mut link);
                defer(&pending, out);
            }
        });
    }
}

async fn keep_latest(port: Arc<Port>, latest: Arc<Mutex<Option<Bottle>>>) {
    while let Some(msg) = port.read().await {
        if let Ok(b) = msg.bottle() {
            *latest.lock() = Some(b);
        }
    }
}
