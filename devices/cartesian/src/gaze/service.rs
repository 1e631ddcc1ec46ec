//! The ports and the thread of `iKinGazeCtrl` around a [`GazeCore`]: the head (and torso)
//! through `remote_controlboard` (`/<name>/<head>` to `/<robot>/<head>`), then
//! `/<name>/xd:i`, `angles:i`, `mono:i`, `stereo:i`, `x:o`, `q:o`, `angles:o`, `events:o`
//! and `rpc`, and a control period of 10 ms.

use parking_lot::Mutex;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};
use yarp_devices::error::{DevResult, DeviceError};
use yarp_devices::{runtime, vocabs, PolyDriver};
use yarp_net::port::Port;
use yarp_proto::{Bottle, Property, Stamp, Value};

use super::core::{GazeConfig, GazeCore, GazeEvent, GazeOutput, GazeReply, TS};

/// Why the module could not start.
#[derive(Debug, thiserror::Error)]
pub enum GazeError {
    #[error("{port}: {why}")]
    Port { port: String, why: String },
    #[error("{part}: not up within ping_robot_tmo ({tmo} s): {why}")]
    Part { part: String, tmo: f64, why: String },
    #[error("{0}")]
    Device(#[from] DeviceError),
    #[error("head_version: {0}")]
    Kinematics(#[from] icub_ikin::KinError),
    #[error("imu: {source_port}: {why} (imu::mode off runs without it)")]
    Imu { source_port: String, why: String },
}

type Shared = Arc<Mutex<GazeCore>>;

struct Ports {
    xd: Arc<Port>,
    angles_in: Arc<Port>,
    mono: Arc<Port>,
    stereo: Arc<Port>,
    x: Arc<Port>,
    q: Arc<Port>,
    angles: Arc<Port>,
    events: Arc<Port>,
    rpc: Arc<Port>,
}

/// A running gaze controller; closes its ports when dropped.
pub struct GazeService {
    core: Shared,
    head: PolyDriver,
    torso: Option<PolyDriver>,
    /// The head IMU's `multipleanalogsensorsclient` (`imu::mode on`).
    imu: Option<PolyDriver>,
    ports: Ports,
    tasks: Vec<tokio::task::JoinHandle<()>>,
    /// Motions started so far (sync looks wait for the next).
    onsets: Arc<tokio::sync::watch::Sender<u64>>,
    quit: Arc<AtomicBool>,
    /// Stop commands from `rpc`, applied by the thread.
    stops: Arc<AtomicBool>,
    /// Events of `rpc` commands (a stop's motion-done, suspended, resumed), sent by the thread.
    rpc_events: Arc<Mutex<Vec<GazeEvent>>>,
}

/// Opens `prop`, trying again every second until `ping_robot_tmo` (the robot may still
/// be coming up); the last error after that.
fn open_within(cfg: &GazeConfig, prop: &Property, what: &str) -> Result<PolyDriver, String> {
    let start = Instant::now();
    loop {
        match PolyDriver::open(prop) {
            Ok(pd) => return Ok(pd),
            Err(e) if start.elapsed().as_secs_f64() < cfg.ping_robot_tmo => {
                tracing::info!("/{}: {what} not yet ({e})", cfg.name);
                std::thread::sleep(Duration::from_secs(1));
            }
            Err(e) => return Err(e.to_string()),
        }
    }
}

fn board(cfg: &GazeConfig, part: &str) -> Result<PolyDriver, GazeError> {
    let text = format!(
        "(device remote_controlboard) (remote /{robot}/{part}) (local /{name}/{part}) \
         (writeStrict on)",
        robot = cfg.robot,
        name = cfg.name
    );
    let remote = format!("/{}/{part}", cfg.robot);
    open_within(cfg, &Property::from_text(&text), &remote).map_err(|why| GazeError::Part {
        part: remote.clone(),
        tmo: cfg.ping_robot_tmo,
        why,
    })
}

/// The head IMU as C++ opens it: a `multipleanalogsensorsclient` on
/// `imu::source_port_name` (`/<robot>/head/inertials`), local `/<name>/head/inertials`;
/// C++ does not start without it, nor does this (tried until `ping_robot_tmo`, as the
/// parts are, since the robot's wrappers come up together).
fn imu_client(cfg: &GazeConfig) -> Result<PolyDriver, GazeError> {
    let text = format!(
        "(device multipleanalogsensorsclient) (remote {remote}) (local /{name}/head/inertials) \
         (timeout {tmo})",
        remote = cfg.imu_source,
        name = cfg.name,
        tmo = cfg.imu_timeout
    );
    let error = |why: String| GazeError::Imu {
        source_port: cfg.imu_source.clone(),
        why,
    };
    let mut pd = open_within(cfg, &Property::from_text(&text), &cfg.imu_source).map_err(error)?;
    if pd.device().as_three_axis_gyroscopes().is_none() {
        return Err(error("no IThreeAxisGyroscopes".into()));
    }
    Ok(pd)
}

/// The first gyroscope's reading \[deg/s\] when its status is OK (`get_gyro`).
fn gyro(pd: &mut PolyDriver) -> Option<[f64; 3]> {
    let g = pd.device().as_three_axis_gyroscopes()?;
    if g.get_three_axis_gyroscope_status(0) != yarp_devices::sensors::MasStatus::Ok {
        return None;
    }
    let m = g.get_three_axis_gyroscope_measure(0).ok()?;
    (m.values.len() >= 3).then(|| [m.values[0], m.values[1], m.values[2]])
}

fn encoders(pd: &mut PolyDriver) -> DevResult<Vec<f64>> {
    pd.device()
        .as_encoders()
        .ok_or(DeviceError::NotOpen)?
        .get_encoders()
}

impl GazeService {
    pub fn open(cfg: GazeConfig) -> Result<GazeService, GazeError> {
        let torso = match &cfg.torso {
            Some(t) => match board(&cfg, t) {
                Ok(pd) => Some(pd),
                Err(e) => {
                    tracing::warn!("/{}: no torso ({e}): its joints count as 0", cfg.name);
                    None
                }
            },
            None => None,
        };
        let mut head = board(&cfg, &cfg.head)?;
        let imu = if cfg.imu {
            Some(imu_client(&cfg)?)
        } else {
            tracing::warn!(
                "/{}: imu::mode off: IMU data will be not received/used",
                cfg.name
            );
            None
        };
        let limits = {
            let n = head
                .device()
                .as_encoders()
                .ok_or(DeviceError::NotOpen)?
                .get_axes()?;
            let lim = head
                .device()
                .as_control_limits()
                .ok_or(DeviceError::NotOpen)?;
            (0..n.min(6))
                .map(|j| lim.get_limits(j))
                .collect::<DevResult<Vec<_>>>()?
        };
        if let Some(pc) = head.device().as_position_control() {
            for j in 0..6 {
                let _ = pc.set_ref_acceleration(j, f64::MAX);
            }
        }
        let mut gaze = GazeCore::new(cfg.clone(), &limits)?;
        if let Some((file, context)) = &cfg.cameras {
            match yarp_devices::robotinterface::resource::find_file(file, Some(context))
                .and_then(|f| std::fs::read_to_string(f).ok())
                .and_then(|t| Property::from_config_text(t).ok())
            {
                Some(p) => {
                    let cam = |g: &str| p.find_group(g).and_then(super::kinematics::Camera::from_group);
                    gaze.set_cameras(cam("CAMERA_CALIBRATION_LEFT"), cam("CAMERA_CALIBRATION_RIGHT"));
                }
                None => tracing::warn!(
                    "/{}: cameras file {file} (context {context}) not found: no image-plane targets",
                    cfg.name
                ),
            }
        }
        let core = Arc::new(Mutex::new(gaze));
        let ns = yarp_net::network::name_client().map_err(|e| GazeError::Port {
            port: format!("/{}", cfg.name),
            why: e.to_string(),
        })?;
        let prefix = format!("/{}", cfg.name);
        let names: Vec<String> = [
            "xd:i", "angles:i", "mono:i", "stereo:i", "x:o", "q:o", "angles:o", "events:o", "rpc",
        ]
        .iter()
        .map(|s| format!("{prefix}/{s}"))
        .collect();
        let opened = runtime::block_on_result(async move {
            let mut out = Vec::new();
            for n in names {
                out.push(Arc::new(
                    Port::open(&n, ns.clone())
                        .await
                        .map_err(|e| format!("{n}: {e}"))?,
                ));
            }
            Ok::<_, String>(out)
        })
        .map_err(|why| GazeError::Port {
            port: prefix.clone(),
            why,
        })?;
        let mut it = opened.into_iter();
        let mut next = || it.next().expect("nine ports");
        let ports = Ports {
            xd: next(),
            angles_in: next(),
            mono: next(),
            stereo: next(),
            x: next(),
            q: next(),
            angles: next(),
            events: next(),
            rpc: next(),
        };
        let (onsets, _) = tokio::sync::watch::channel(0u64);
        let onsets = Arc::new(onsets);
        let quit = Arc::new(AtomicBool::new(false));
        let stops = Arc::new(AtomicBool::new(false));
        let rpc_events: Arc<Mutex<Vec<GazeEvent>>> = Arc::default();
        let rt = runtime::handle();
        let tasks = vec![
            rt.spawn(serve_targets(ports.xd.clone(), core.clone(), false)),
            rt.spawn(serve_targets(ports.angles_in.clone(), core.clone(), true)),
            rt.spawn(serve_pixels(ports.mono.clone(), core.clone(), false)),
            rt.spawn(serve_pixels(ports.stereo.clone(), core.clone(), true)),
            rt.spawn(serve_rpc(
                ports.rpc.clone(),
                core.clone(),
                onsets.clone(),
                quit.clone(),
                stops.clone(),
                rpc_events.clone(),
            )),
        ];
        tracing::info!("{prefix}: gaze controller up (head {})", cfg.head_version);
        Ok(GazeService {
            core,
            head,
            torso,
            imu,
            ports,
            tasks,
            onsets,
            quit,
            stops,
            rpc_events,
        })
    }

    /// Whether `[quit]` was asked.
    pub fn is_closed(&self) -> bool {
        self.quit.load(Ordering::SeqCst)
    }

    /// The control thread, until `[quit]` or `stop`.
    pub fn run(&mut self, stop: &AtomicBool) {
        let period = Duration::from_secs_f64(TS);
        let mut next = Instant::now();
        let (mut n_x, mut n_q, mut n_ev) = (0i32, 0i32, 0i32);
        let mut warned = false;
        while !self.is_closed() && !stop.load(Ordering::SeqCst) {
            next += period;
            let torso = match self.torso.as_mut() {
                Some(t) => encoders(t).unwrap_or_else(|_| vec![0.0; 3]),
                None => vec![0.0; 3],
            };
            match encoders(&mut self.head) {
                Ok(head) => {
                    warned = false;
                    let now = now_seconds();
                    let gyro = self.imu.as_mut().and_then(gyro);
                    let out = {
                        let mut core = self.core.lock();
                        core.set_gyro(gyro);
                        core.cycle(now, &torso, &head)
                    };
                    self.apply(out, now, (&mut n_x, &mut n_q, &mut n_ev));
                }
                Err(e) if !warned => {
                    tracing::warn!("/{}: comm-timeout: {e}", self.core.lock().config().name);
                    warned = true;
                }
                Err(_) => {}
            }
            let now = Instant::now();
            if next > now {
                std::thread::sleep(next - now);
            } else {
                next = now;
            }
        }
        let b = Bottle::new().with("closing").with(now_seconds());
        let port = self.ports.events.clone();
        runtime::block_on_logged("iKinGazeCtrl: closing", async move {
            if port.has_outputs() {
                port.write_strict(&b, None).await;
            }
        });
    }

    fn apply(&mut self, mut out: GazeOutput, now: f64, counts: (&mut i32, &mut i32, &mut i32)) {
        out.events
            .extend(std::mem::take(&mut *self.rpc_events.lock()));
        let dev = self.head.device();
        if out.onset || out.modes {
            if let Some(cm) = dev.as_control_mode() {
                for j in 0..3 {
                    let _ = cm.set_control_mode(j, vocabs::CM_POSITION_DIRECT);
                }
                for j in 3..6 {
                    let _ = cm.set_control_mode(j, vocabs::CM_VELOCITY);
                }
            }
            if out.onset {
                self.onsets.send_modify(|n| *n += 1);
            }
        }
        if let Some(neck) = out.neck {
            if let Some(pd) = dev.as_position_direct() {
                let _ = pd.set_positions_group(&[0, 1, 2], &neck);
            }
        }
        let stopped = self.stops.swap(false, Ordering::SeqCst) || out.stop;
        let eyes = if stopped { Some([0.0; 3]) } else { out.eyes };
        if let Some(v) = eyes {
            if let Some(vc) = dev.as_velocity_control() {
                for (j, v) in (3..6).zip(v) {
                    let _ = vc.velocity_move(j, v);
                }
            }
        }
        let (nx, nq, nev) = counts;
        let mut msgs: Vec<(Arc<Port>, Bottle, Stamp)> = Vec::new();
        if let Some(x) = out.x.filter(|_| self.ports.x.has_outputs()) {
            msgs.push((
                self.ports.x.clone(),
                x.iter().copied().collect(),
                Stamp::new(*nx, now),
            ));
        }
        *nx = nx.wrapping_add(1);
        if self.ports.q.has_outputs() {
            msgs.push((
                self.ports.q.clone(),
                out.q.iter().copied().collect(),
                Stamp::new(*nq, now),
            ));
        }
        *nq = nq.wrapping_add(1);
        if let Some(a) = out.angles.filter(|_| self.ports.angles.has_outputs()) {
            msgs.push((
                self.ports.angles.clone(),
                a.iter().copied().collect(),
                Stamp::new(*nx, now),
            ));
        }
        let events = self.ports.events.clone();
        let evs: Vec<(Bottle, Stamp)> = if events.has_outputs() {
            out.events
                .iter()
                .map(|e| {
                    let mut b = Bottle::new().with(e.name).with(now);
                    if let Some(cp) = e.checkpoint {
                        b.push(cp);
                    }
                    *nev = nev.wrapping_add(1);
                    (b, Stamp::new(*nev, now))
                })
                .collect()
        } else {
            Vec::new()
        };
        if msgs.is_empty() && evs.is_empty() {
            return;
        }
        runtime::block_on_logged("iKinGazeCtrl: streams", async move {
            for (p, b, s) in msgs {
                p.write_nowait(&b, Some(s));
            }
            for (b, s) in evs {
                events.write_strict(&b, Some(s)).await;
            }
        });
    }
}

impl Drop for GazeService {
    fn drop(&mut self) {
        for t in self.tasks.drain(..) {
            t.abort();
        }
        let p = &self.ports;
        let ports = vec![
            p.xd.clone(),
            p.angles_in.clone(),
            p.mono.clone(),
            p.stereo.clone(),
            p.x.clone(),
            p.q.clone(),
            p.angles.clone(),
            p.events.clone(),
            p.rpc.clone(),
        ];
        runtime::block_on_logged("iKinGazeCtrl: closing", async move {
            tokio::time::sleep(Duration::from_millis(20)).await;
            for p in ports {
                if let Ok(p) = Arc::try_unwrap(p) {
                    p.close().await;
                }
            }
        });
    }
}

fn now_seconds() -> f64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_secs_f64())
        .unwrap_or(0.0)
}

/// `xd:i` (x y z) or `angles:i` (mode azi ele ver).
async fn serve_targets(port: Arc<Port>, core: Shared, angles: bool) {
    while let Some(msg) = port.read().await {
        let Ok(b) = msg.bottle() else { continue };
        let mut core = core.lock();
        let target = if angles {
            let rel = b.get(0).and_then(Value::as_str) == Some("rel");
            let a: Vec<f64> = b.iter().skip(1).filter_map(Value::as_f64).collect();
            (a.len() >= 3)
                .then(|| core.target_of_angles(rel, [a[0], a[1], a[2]]))
                .flatten()
        } else {
            let v: Vec<f64> = b.iter().filter_map(Value::as_f64).collect();
            (v.len() >= 3).then(|| [v[0], v[1], v[2]])
        };
        if let Some(x) = target {
            core.set_target(x);
        }
    }
}

/// `mono:i` (`[eye u v z]`) and `stereo:i` (`[ul vl ur vr]`, triangulated: C++ servoes
/// the depth with a PID there) in pixels of the calibrated cameras.
async fn serve_pixels(port: Arc<Port>, core: Shared, stereo: bool) {
    let mut said = false;
    while let Some(msg) = port.read().await {
        let Ok(b) = msg.bottle() else { continue };
        let mut core = core.lock();
        let x = if stereo {
            core.target_of_stereo(&b)
        } else {
            core.target_of_mono(&b)
        };
        match x {
            Some(x) => {
                core.set_target(x);
            }
            None if !said => {
                tracing::warn!(
                    "{}: no target from `{b}` (are the cameras calibrated?)",
                    port.name()
                );
                said = true;
            }
            None => {}
        }
    }
}

async fn serve_rpc(
    port: Arc<Port>,
    core: Shared,
    onsets: Arc<tokio::sync::watch::Sender<u64>>,
    quit: Arc<AtomicBool>,
    stops: Arc<AtomicBool>,
    rpc_events: Arc<Mutex<Vec<GazeEvent>>>,
) {
    while let Some(mut msg) = port.read().await {
        let cmd = msg.bottle().unwrap_or_default();
        let mut rx = onsets.subscribe();
        let seen = *rx.borrow_and_update();
        let mut out = GazeOutput::default();
        let reply = core.lock().respond(&cmd, &mut out);
        if out.stop {
            stops.store(true, Ordering::SeqCst);
        }
        rpc_events.lock().extend(out.events);
        let reply = match reply {
            GazeReply::Now(b) => b,
            GazeReply::AfterOnset => {
                // the next period takes the target; a suspended module never does
                let started =
                    tokio::time::timeout(Duration::from_secs(5), rx.wait_for(|n| *n > seen)).await;
                if matches!(started, Ok(Ok(_))) {
                    crate::protocol::ack()
                } else {
                    crate::protocol::nack()
                }
            }
            GazeReply::Quit => {
                quit.store(true, Ordering::SeqCst);
                Bottle::new().with(Value::vocab("bye"))
            }
        };
        if msg.wants_reply() {
            msg.reply(reply);
        }
    }
}
