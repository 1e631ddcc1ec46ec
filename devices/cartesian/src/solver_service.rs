//! The ports and the thread of `iKinCartesianSolver` around a [`SolverCore`]: `/<name>/rpc`
//! (open first, `[nack]` until the solver is up, as C++'s), the robot's parts through
//! `remote_controlboard` (`/<name>/<part>` to `/<robot>/<part>`), then `/<name>/in` and
//! `/<name>/out` opened last, once the first encoders are in, and a solve per period.

use parking_lot::Mutex;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};
use yarp_devices::runtime;
use yarp_devices::PolyDriver;
use yarp_net::port::Port;
use yarp_proto::{Bottle, Property};

use crate::protocol::{nack, word};
use crate::solver::{SolverConfig, SolverCore};

/// Why the solver could not start.
#[derive(Debug, thiserror::Error)]
pub enum SolverError {
    #[error("{port}: {why}")]
    Port { port: String, why: String },
    #[error("the robot's part {part} did not answer within ping_robot_tmo ({tmo} s): {why}")]
    Part { part: String, tmo: f64, why: String },
    #[error(transparent)]
    Config(#[from] crate::solver::SolverConfigError),
    #[error("{0}")]
    Device(#[from] yarp_devices::error::DeviceError),
}

/// A part of the robot: its board's client and whether its joints run backwards in
/// the chain.
struct Part {
    board: PolyDriver,
    reversed: bool,
}

/// A running solver; closes its ports when dropped.
pub struct SolverService {
    name: String,
    core: Arc<Mutex<Option<SolverCore>>>,
    parts: Vec<Part>,
    out: Option<Arc<Port>>,
    ports: Vec<Arc<Port>>,
    tasks: Vec<tokio::task::JoinHandle<()>>,
    closed: Arc<AtomicBool>,
    period: Duration,
}

fn open_port(name: String) -> Result<Arc<Port>, SolverError> {
    let ns = yarp_net::network::name_client().map_err(|e| SolverError::Port {
        port: name.clone(),
        why: format!("no name server: {e}"),
    })?;
    let n = name.clone();
    runtime::block_on_result(async move {
        Port::open(&n, ns)
            .await
            .map(Arc::new)
            .map_err(|e| e.to_string())
    })
    .map_err(|why| SolverError::Port { port: name, why })
}

impl SolverService {
    /// Opens `/<name>/rpc`, waits for the robot's parts (at most `ping_robot_tmo`),
    /// reads their limits and first encoders, then opens `/in` and `/out`.
    pub fn open(cfg: SolverConfig) -> Result<SolverService, SolverError> {
        let name = format!("/{}", cfg.name);
        let core: Arc<Mutex<Option<SolverCore>>> = Arc::new(Mutex::new(None));
        let closed = Arc::new(AtomicBool::new(false));
        let rpc = open_port(format!("{name}/rpc"))?;
        let mut svc = SolverService {
            name: name.clone(),
            core: core.clone(),
            parts: Vec::new(),
            out: None,
            ports: vec![rpc.clone()],
            tasks: vec![runtime::handle().spawn(serve_rpc(rpc, core.clone(), closed.clone()))],
            closed,
            period: cfg.period,
        };
        for (part, reversed) in cfg.parts() {
            let board = wait_part(&cfg, &name, &part)?;
            svc.parts.push(Part { board, reversed });
        }
        let limits = svc.limits(&cfg)?;
        let mut solver = SolverCore::new(cfg, &limits)?;
        // initPos: every encoder read (as C++, waiting as long as it takes), the current
        // pose as the target
        let mut told = Instant::now();
        loop {
            match svc.feedback() {
                Ok(fb) if solver.set_feedback(&fb).is_ok() => break,
                Ok(_) => {}
                Err(e) if told.elapsed() >= Duration::from_secs(5) => {
                    tracing::warn!("{name}: still waiting for the robot's encoders: {e}");
                    told = Instant::now();
                }
                Err(_) => {}
            }
            std::thread::sleep(Duration::from_millis(10));
        }
        solver.init_target();
        *core.lock() = Some(solver);
        let input = open_port(format!("{name}/in"))?;
        let out = open_port(format!("{name}/out"))?;
        svc.tasks
            .push(runtime::handle().spawn(serve_input(input.clone(), core)));
        svc.ports.push(input);
        svc.ports.push(out.clone());
        svc.out = Some(out);
        tracing::info!("{name}: solver up");
        Ok(svc)
    }

    /// The limits of every chain link \[deg\] in chain order (`alignJointsBounds`).
    fn limits(&mut self, cfg: &SolverConfig) -> Result<Vec<(f64, f64)>, SolverError> {
        let n = icub_ikin::Limb::new(cfg.kind, &cfg.limb_type)
            .map(|l| l.chain().n())
            .unwrap_or(0);
        let mut out = Vec::with_capacity(n);
        for p in &mut self.parts {
            let joints = {
                let enc = p
                    .board
                    .device()
                    .as_encoders()
                    .ok_or(yarp_devices::error::DeviceError::NotOpen)?;
                enc.get_axes()?.min(n - out.len())
            };
            let lim = p
                .board
                .device()
                .as_control_limits()
                .ok_or(yarp_devices::error::DeviceError::NotOpen)?;
            for k in 0..joints {
                let j = if p.reversed { joints - k - 1 } else { k };
                out.push(lim.get_limits(j)?);
            }
        }
        Ok(out)
    }

    /// The parts' encoders \[deg\], as the robot orders them.
    fn feedback(&mut self) -> yarp_devices::error::DevResult<Vec<Vec<f64>>> {
        self.parts
            .iter_mut()
            .map(|p| {
                p.board
                    .device()
                    .as_encoders()
                    .ok_or(yarp_devices::error::DeviceError::NotOpen)?
                    .get_encoders()
            })
            .collect()
    }

    /// Whether `[quit]` was asked.
    pub fn is_closed(&self) -> bool {
        self.closed.load(Ordering::SeqCst)
    }

    /// Runs the solver's thread until `[quit]` or `stop`.
    pub fn run(&mut self, stop: &AtomicBool) {
        let mut next = Instant::now();
        let mut warned = false;
        while !self.is_closed() && !stop.load(Ordering::SeqCst) {
            next += self.period;
            let fb = self.feedback();
            let out = {
                let mut core = self.core.lock();
                let Some(core) = core.as_mut() else { break };
                match fb {
                    Ok(fb) => {
                        warned = false;
                        let _ = core.set_feedback(&fb);
                        core.tick()
                    }
                    Err(e) => {
                        if !warned {
                            tracing::warn!("{}: timeout detected on the robot: {e}", self.name);
                            warned = true;
                        }
                        None
                    }
                }
            };
            if let (Some(b), Some(port)) = (out, self.out.clone()) {
                runtime::block_on_logged("iKinCartesianSolver: /out", async move {
                    port.write_strict(&b, None).await;
                });
            }
            let now = Instant::now();
            if next > now {
                std::thread::sleep(next - now);
            } else {
                next = now;
            }
        }
    }
}

impl Drop for SolverService {
    fn drop(&mut self) {
        for t in self.tasks.drain(..) {
            t.abort();
        }
        self.out = None;
        let ports = std::mem::take(&mut self.ports);
        runtime::block_on_logged("iKinCartesianSolver: closing", async move {
            for p in ports {
                if let Ok(p) = Arc::try_unwrap(p) {
                    p.close().await;
                }
            }
        });
    }
}

/// A `remote_controlboard` to `/<robot>/<part>`, retried every second for
/// `ping_robot_tmo` (`waitPart`).
fn wait_part(cfg: &SolverConfig, name: &str, part: &str) -> Result<PolyDriver, SolverError> {
    let text = format!(
        "(device remote_controlboard) (remote /{robot}/{part}) (local {name}/{part}) \
         (robot {robot}) (part {part})",
        robot = cfg.robot
    );
    let prop = Property::from_text(&text);
    let start = Instant::now();
    loop {
        match PolyDriver::open(&prop) {
            Ok(pd) => return Ok(pd),
            Err(e) => {
                let left = cfg.ping_robot_tmo - start.elapsed().as_secs_f64();
                if left <= 0.0 {
                    return Err(SolverError::Part {
                        part: format!("/{}/{part}", cfg.robot),
                        tmo: cfg.ping_robot_tmo,
                        why: e.to_string(),
                    });
                }
                tracing::info!(
                    "{name}: /{}/{part} not yet ({e}): still {left:.1} s to timeout expiry",
                    cfg.robot
                );
                std::thread::sleep(Duration::from_secs(1));
            }
        }
    }
}

async fn serve_rpc(port: Arc<Port>, core: Arc<Mutex<Option<SolverCore>>>, closed: Arc<AtomicBool>) {
    while let Some(mut msg) = port.read().await {
        if closed.load(Ordering::SeqCst) {
            continue; // closed: no reply, as C++'s
        }
        let cmd = msg.bottle().unwrap_or_default();
        let reply = match core.lock().as_mut() {
            Some(c) => c.respond(&cmd),
            None => nack(),
        };
        if crate::protocol::is_word(&cmd, 0, word::QUIT) {
            closed.store(true, Ordering::SeqCst);
        }
        if msg.wants_reply() {
            msg.reply(reply);
        }
    }
}

async fn serve_input(port: Arc<Port>, core: Arc<Mutex<Option<SolverCore>>>) {
    while let Some(msg) = port.read().await {
        match msg.bottle() {
            Ok(b) => {
                if let Some(c) = core.lock().as_mut() {
                    c.on_input(&b);
                }
            }
            Err(e) => tracing::warn!("{}: undecodable target from {}: {e}", port.name(), msg.from),
        }
    }
}

/// Reads the `/out` bottle of a solver: `(x, q, token)`.
pub fn parse_result(b: &Bottle) -> Option<(Vec<f64>, Vec<f64>, Option<f64>)> {
    let x = crate::protocol::find_vector(b, word::X)?;
    let q = crate::protocol::find_vector(b, word::Q)?;
    Some((x, q, crate::protocol::find_number(b, word::TOKEN)))
}
