//! `gazecontrollerclient` (icub-main's `ClientGazeController`): an `iKinGazeCtrl` reached
//! over the network, as [`IGazeControl`].
//!
//! Ports `<local>/rpc`, `xd:o`, `angles:o`, `mono:o`, `stereo:o`, `x:i`, `angles:i`, `q:i`,
//! `events:i`; opening connects the RPC, checks `server_version` (`get info`), then the
//! streams with `carrier`, as C++'s. Commands are sent as C++ sends them: words as strings.

use parking_lot::Mutex;
use std::collections::BTreeSet;
use std::sync::Arc;
use std::time::{Duration, Instant};
use yarp_devices::cartesian_control::CartesianEvent;
use yarp_devices::driver::DeviceDriver;
use yarp_devices::error::{DevResult, DeviceError};
use yarp_devices::gaze_control::IGazeControl;
use yarp_devices::{nwc_ports, runtime};
use yarp_net::port::Port;
use yarp_proto::{Bottle, Property, Value};

use crate::client::{close_all, read_events};
use crate::gaze::core::SERVER_VERSION;
use crate::protocol;

/// The C++ device name.
pub const NAME: &str = "gazecontrollerclient";

/// How long a call waits for the module (a sync look waits for the motion's onset).
const RPC_TIMEOUT: Duration = Duration::from_secs(10);

yarp_devices::device_params! {
    /// What `gazecontrollerclient` reads (icub-main's `ClientGazeController`).
    pub struct GazeControllerClientParams for "gazecontrollerclient" {
        /// Prefix of the client's ports
        "local" local: String = required,
        /// Prefix of the module's ports (its `name`, e.g. /iKinGazeCtrl)
        "remote" remote: String = required,
        /// Carrier of the streaming connections
        "carrier" carrier: String = "udp",
        /// Age after which the fixation point's stream counts as lost
        "timeout" timeout: f64 = 0.1; "s"; check yarp_devices::params::positive,
    }
}

type Latest = Arc<Mutex<Option<(Vec<f64>, f64, Instant)>>>;

struct Link {
    remote: String,
    rpc: Arc<Port>,
    xd: Arc<Port>,
    angles_out: Arc<Port>,
    others: Vec<Arc<Port>>,
    tasks: Vec<tokio::task::JoinHandle<()>>,
    x: Latest,
    angles: Latest,
    received: Arc<Mutex<Vec<CartesianEvent>>>,
    contexts: BTreeSet<i32>,
    timeout: Duration,
}

/// `gazecontrollerclient`.
#[derive(Default)]
pub struct GazeControllerClient {
    link: Option<Link>,
}

fn words(w: &[&str]) -> Bottle {
    w.iter().map(|w| Value::from(*w)).collect()
}

async fn keep_latest(port: Arc<Port>, latest: Latest) {
    while let Some(msg) = port.read().await {
        let Ok(b) = msg.bottle() else { continue };
        if let Some(v) = b.iter().map(Value::as_f64).collect::<Option<Vec<f64>>>() {
            let t = msg.stamp.map_or(0.0, |s| s.time);
            *latest.lock() = Some((v, t, Instant::now()));
        }
    }
}

/// The camera's name as C++ sends it (0: left, anything else right).
fn eye(cam: usize) -> &'static str {
    if cam == 0 {
        "left"
    } else {
        "right"
    }
}

/// `[ack] (x y z)`.
fn point(r: &Bottle) -> DevResult<[f64; 3]> {
    match r.get(1).and_then(protocol::numbers).as_deref() {
        Some([x, y, z, ..]) => Ok([*x, *y, *z]),
        _ => Err(DeviceError::failed(NAME, format!("no point in `{r}`"))),
    }
}

impl GazeControllerClient {
    pub fn new() -> Self {
        Self::default()
    }

    fn link(&mut self) -> DevResult<&mut Link> {
        self.link.as_mut().ok_or(DeviceError::NotOpen)
    }

    fn ack(&mut self, cmd: Bottle) -> DevResult<Bottle> {
        let link = self.link()?;
        let text = cmd.to_string();
        let reply = nwc_ports::call_within(&link.remote, &link.rpc, cmd, RPC_TIMEOUT)?;
        if protocol::is_ack(&reply) {
            Ok(reply)
        } else {
            Err(DeviceError::failed(
                NAME,
                format!("`{text}` answered `{reply}`"),
            ))
        }
    }

    fn number(&mut self, cmd: Bottle) -> DevResult<f64> {
        let r = self.ack(cmd)?;
        r.get(1)
            .and_then(Value::as_f64)
            .ok_or_else(|| DeviceError::failed(NAME, format!("no number in `{r}`")))
    }

    fn stream(&mut self, port: Arc<Port>, b: Bottle) {
        runtime::block_on_logged("gazecontrollerclient: stream", async move {
            port.write_strict(&b, None).await;
        });
    }

    fn latest(link: &Link, latest: &Latest, what: &str) -> DevResult<(Vec<f64>, f64)> {
        match latest.lock().clone() {
            Some((v, t, at)) if at.elapsed() < link.timeout => Ok((v, t)),
            _ => Err(DeviceError::Timeout {
                device: NAME.into(),
                command: format!("{what} ({})", link.remote),
                after: link.timeout,
            }),
        }
    }
}

impl DeviceDriver for GazeControllerClient {
    fn parameters(&self) -> Vec<yarp_devices::params::ParamSpec> {
        GazeControllerClientParams::PARAMS.to_vec()
    }

    fn open(&mut self, config: &Property) -> DevResult<()> {
        let p = GazeControllerClientParams::read(config)?;
        self.close()?;
        let refused = |why: String| DeviceError::BadParam {
            device: NAME.into(),
            param: "remote".into(),
            expected: "the prefix of a running iKinGazeCtrl",
            got: why,
        };
        let ns = yarp_net::network::name_client().map_err(|e| refused(e.to_string()))?;
        let (local, remote) = (p.local.clone(), p.remote.clone());
        let ports = runtime::block_on_result(async move {
            let mut ports = Vec::new();
            for suffix in [
                "rpc", "xd:o", "angles:o", "mono:o", "stereo:o", "x:i", "angles:i", "q:i",
                "events:i",
            ] {
                let name = format!("{local}/{suffix}");
                match Port::open(&name, ns.clone()).await {
                    Ok(port) => ports.push(Arc::new(port)),
                    Err(e) => {
                        close_all(ports).await;
                        return Err(format!("{name}: {e}"));
                    }
                }
            }
            if let Err(e) = ports[0].connect(&format!("{remote}/rpc"), None).await {
                close_all(ports).await;
                return Err(format!("cannot connect to {remote}/rpc: {e}"));
            }
            Ok(ports)
        })
        .map_err(refused)?;
        let [rpc, xd, angles_out, mono, stereo, x_in, angles_in, q_in, events]: [Arc<Port>; 9] =
            ports.try_into().map_err(|_| DeviceError::NotOpen)?;
        let (x, angles): (Latest, Latest) = (Arc::default(), Arc::default());
        let received: Arc<Mutex<Vec<CartesianEvent>>> = Arc::default();
        let rt = runtime::handle();
        let tasks = vec![
            rt.spawn(keep_latest(x_in.clone(), x.clone())),
            rt.spawn(keep_latest(angles_in.clone(), angles.clone())),
            rt.spawn(read_events(events.clone(), received.clone())),
        ];
        self.link = Some(Link {
            remote: p.remote.clone(),
            rpc,
            xd: xd.clone(),
            angles_out: angles_out.clone(),
            others: vec![
                mono.clone(),
                stereo.clone(),
                x_in.clone(),
                angles_in.clone(),
                q_in.clone(),
                events.clone(),
            ],
            tasks,
            x,
            angles,
            received,
            contexts: BTreeSet::new(),
            timeout: Duration::from_secs_f64(p.timeout),
        });
        // C++'s handshake: the server's version, then every stream
        let result = (|| {
            let info = self.ack(words(&["get", "info"]))?;
            let version = info
                .get(1)
                .and_then(Value::as_list)
                .and_then(|l| l.find("server_version"))
                .and_then(|v| v.as_str().map(str::to_string));
            match version {
                Some(v) if v != SERVER_VERSION => {
                    return Err(DeviceError::failed(
                        NAME,
                        format!(
                            "server version {v} not compatible with this client's {SERVER_VERSION}"
                        ),
                    ))
                }
                None => tracing::warn!("{NAME}: {} did not say its server_version", p.remote),
                _ => {}
            }
            let (remote, carrier) = (p.remote.clone(), p.carrier.clone());
            let outs = [
                (xd, "xd:i"),
                (angles_out, "angles:i"),
                (mono, "mono:i"),
                (stereo, "stereo:i"),
            ];
            let ins = [
                ("x:o", x_in.name().to_string()),
                ("angles:o", angles_in.name().to_string()),
                ("q:o", q_in.name().to_string()),
                ("events:o", events.name().to_string()),
            ];
            runtime::block_on_result(async move {
                let ns = yarp_net::network::name_client().map_err(|e| e.to_string())?;
                for (port, to) in outs {
                    port.connect(&format!("{remote}/{to}"), Some(&carrier))
                        .await
                        .map_err(|e| format!("{remote}/{to}: {e}"))?;
                }
                for (from, to) in ins {
                    let from = format!("{remote}/{from}");
                    let (ok, why) = yarp_net::network::connect(&ns, &from, &to, Some(&carrier))
                        .await
                        .map_err(|e| e.to_string())?;
                    if !ok {
                        return Err(format!("{from} -> {to}: {why}"));
                    }
                }
                Ok::<_, String>(())
            })
            .map_err(|e| DeviceError::failed(NAME, e))
        })();
        if result.is_err() {
            let _ = self.close();
        }
        result
    }

    fn close(&mut self) -> DevResult<()> {
        if let Some(link) = self.link.as_ref() {
            if !link.contexts.is_empty() {
                let ids: Vec<i32> = link.contexts.iter().copied().collect();
                let (remote, rpc) = (link.remote.clone(), link.rpc.clone());
                let _ = nwc_ports::call_within(
                    &remote,
                    &rpc,
                    words(&["del"]).with(protocol::i32_list(ids)),
                    Duration::from_secs(1),
                );
            }
        }
        if let Some(link) = self.link.take() {
            for t in &link.tasks {
                t.abort();
            }
            let mut ports = vec![link.rpc, link.xd, link.angles_out];
            ports.extend(link.others);
            let tasks = link.tasks;
            runtime::block_on_logged("gazecontrollerclient: closing", async move {
                for t in tasks {
                    let _ = t.await;
                }
                close_all(ports).await;
            });
        }
        Ok(())
    }

    yarp_devices::views!(as_gaze_control);
}

impl IGazeControl for GazeControllerClient {
    fn set_tracking_mode(&mut self, on: bool) -> DevResult<()> {
        self.ack(words(&["set", "track"]).with(Value::Int32(i32::from(on))))
            .map(drop)
    }

    fn get_tracking_mode(&mut self) -> DevResult<bool> {
        Ok(self.number(words(&["get", "track"]))? > 0.0)
    }

    fn set_stabilization_mode(&mut self, on: bool) -> DevResult<()> {
        self.ack(words(&["set", "stab"]).with(Value::Int32(i32::from(on))))
            .map(drop)
    }

    fn get_stabilization_mode(&mut self) -> DevResult<bool> {
        Ok(self.number(words(&["get", "stab"]))? > 0.0)
    }

    fn set_vor_gain(&mut self, gain: f64) -> DevResult<()> {
        self.ack(words(&["set", "vor"]).with(gain)).map(drop)
    }

    fn get_vor_gain(&mut self) -> DevResult<f64> {
        self.number(words(&["get", "vor"]))
    }

    fn set_ocr_gain(&mut self, gain: f64) -> DevResult<()> {
        self.ack(words(&["set", "ocr"]).with(gain)).map(drop)
    }

    fn get_ocr_gain(&mut self) -> DevResult<f64> {
        self.number(words(&["get", "ocr"]))
    }

    fn get_fixation_point(&mut self) -> DevResult<([f64; 3], f64)> {
        let link = self.link()?;
        let (v, t) = Self::latest(link, &link.x, "getFixationPoint")?;
        match v[..] {
            [a, b, c, ..] => Ok(([a, b, c], t)),
            _ => Err(DeviceError::WrongSize {
                expected: 3,
                got: v.len(),
            }),
        }
    }

    fn get_angles(&mut self) -> DevResult<[f64; 3]> {
        let link = self.link()?;
        let (v, _) = Self::latest(link, &link.angles, "getAngles")?;
        match v[..] {
            [a, b, c, ..] => Ok([a, b, c]),
            _ => Err(DeviceError::WrongSize {
                expected: 3,
                got: v.len(),
            }),
        }
    }

    fn look_at_fixation_point(&mut self, x: &[f64; 3]) -> DevResult<()> {
        let port = self.link()?.xd.clone();
        self.stream(port, x.iter().copied().collect());
        Ok(())
    }

    fn look_at_fixation_point_sync(&mut self, x: &[f64; 3]) -> DevResult<()> {
        self.ack(words(&["look", "3D"]).with(protocol::f64_list(x)))
            .map(drop)
    }

    fn look_at_abs_angles(&mut self, ang: &[f64; 3]) -> DevResult<()> {
        let port = self.link()?.angles_out.clone();
        let mut b = Bottle::new().with("abs");
        for a in ang {
            b.push(*a);
        }
        self.stream(port, b);
        Ok(())
    }

    fn look_at_rel_angles(&mut self, ang: &[f64; 3]) -> DevResult<()> {
        let port = self.link()?.angles_out.clone();
        let mut b = Bottle::new().with("rel");
        for a in ang {
            b.push(*a);
        }
        self.stream(port, b);
        Ok(())
    }

    fn look_at_abs_angles_sync(&mut self, ang: &[f64; 3]) -> DevResult<()> {
        let mut l = Bottle::new().with("abs");
        for a in ang {
            l.push(*a);
        }
        self.ack(words(&["look", "ang"]).with(Value::List(l)))
            .map(drop)
    }

    fn get_2d_pixel(&mut self, cam: usize, x: &[f64; 3]) -> DevResult<[f64; 2]> {
        let mut l = Bottle::new().with(eye(cam));
        for v in x {
            l.push(*v);
        }
        let r = self.ack(words(&["get", "2D"]).with(Value::List(l)))?;
        match r.get(1).and_then(protocol::numbers).as_deref() {
            Some([u, v, ..]) => Ok([*u, *v]),
            _ => Err(DeviceError::failed(NAME, format!("no pixel in `{r}`"))),
        }
    }

    fn get_3d_point(&mut self, cam: usize, px: &[f64; 2], z: f64) -> DevResult<[f64; 3]> {
        let l = Bottle::new().with(eye(cam)).with(px[0]).with(px[1]).with(z);
        let r = self.ack(words(&["get", "3D", "mono"]).with(Value::List(l)))?;
        point(&r)
    }

    fn triangulate_3d_point(&mut self, pl: &[f64; 2], pr: &[f64; 2]) -> DevResult<[f64; 3]> {
        let l = protocol::f64_list(&[pl[0], pl[1], pr[0], pr[1]]);
        let r = self.ack(words(&["get", "3D", "stereo"]).with(l))?;
        point(&r)
    }

    fn look_at_mono_pixel_sync(&mut self, cam: usize, px: &[f64; 2], z: f64) -> DevResult<()> {
        let l = Bottle::new().with(eye(cam)).with(px[0]).with(px[1]).with(z);
        self.ack(words(&["look", "mono"]).with(Value::List(l)))
            .map(drop)
    }

    fn look_at_stereo_pixels_sync(&mut self, pl: &[f64; 2], pr: &[f64; 2]) -> DevResult<()> {
        let l = protocol::f64_list(&[pl[0], pl[1], pr[0], pr[1]]);
        self.ack(words(&["look", "stereo"]).with(l)).map(drop)
    }

    fn get_neck_traj_time(&mut self) -> DevResult<f64> {
        self.number(words(&["get", "Tneck"]))
    }

    fn set_neck_traj_time(&mut self, t: f64) -> DevResult<()> {
        self.ack(words(&["set", "Tneck"]).with(t)).map(drop)
    }

    fn get_eyes_traj_time(&mut self) -> DevResult<f64> {
        self.number(words(&["get", "Teyes"]))
    }

    fn set_eyes_traj_time(&mut self, t: f64) -> DevResult<()> {
        self.ack(words(&["set", "Teyes"]).with(t)).map(drop)
    }

    fn get_joints_desired(&mut self) -> DevResult<Vec<f64>> {
        let r = self.ack(words(&["get", "des"]))?;
        r.get(1)
            .and_then(protocol::numbers)
            .ok_or_else(|| DeviceError::failed(NAME, format!("no list in `{r}`")))
    }

    fn check_motion_done(&mut self) -> DevResult<bool> {
        Ok(self.number(words(&["get", "done"]))? > 0.0)
    }

    fn wait_motion_done(&mut self, period: f64, timeout: f64) -> DevResult<bool> {
        let start = Instant::now();
        loop {
            std::thread::sleep(Duration::from_secs_f64(period.max(0.0)));
            if self.check_motion_done()? {
                return Ok(true);
            }
            if timeout > 0.0 && start.elapsed().as_secs_f64() > timeout {
                return Ok(false);
            }
        }
    }

    fn stop_control(&mut self) -> DevResult<()> {
        self.ack(words(&["stop"])).map(drop)
    }

    fn store_context(&mut self) -> DevResult<i32> {
        let id = self.number(words(&["stor"]))? as i32;
        self.link()?.contexts.insert(id);
        Ok(id)
    }

    fn restore_context(&mut self, id: i32) -> DevResult<()> {
        if id != 0 && !self.link()?.contexts.contains(&id) {
            return Err(DeviceError::failed(
                NAME,
                format!("context {id} is not this client's"),
            ));
        }
        self.ack(words(&["rest"]).with(Value::Int32(id))).map(drop)
    }

    fn delete_context(&mut self, id: i32) -> DevResult<()> {
        if !self.link()?.contexts.remove(&id) {
            return Err(DeviceError::failed(
                NAME,
                format!("context {id} is not this client's"),
            ));
        }
        self.ack(words(&["del"]).with(protocol::i32_list([id])))
            .map(drop)
    }

    fn get_info(&mut self) -> DevResult<Bottle> {
        let r = self.ack(words(&["get", "info"]))?;
        r.get(1)
            .and_then(Value::as_list)
            .cloned()
            .ok_or_else(|| DeviceError::failed(NAME, format!("unexpected reply `{r}`")))
    }

    fn take_events(&mut self) -> Vec<CartesianEvent> {
        match self.link.as_ref() {
            Some(l) => std::mem::take(&mut *l.received.lock()),
            None => Vec::new(),
        }
    }
}
