//! `gazecontrollerclient` (icub-main's `ClientGazeController`): an `iKinGazeCtrl` reached
//! over the network, as [`IGazeControl`].
//!
//! Ports `<local>/rpc`, `xd:o`, `angles:o`, `mono:o`, `stereo:o`, `x:i`, `angles:i`, `q:i`,
//! `events:i`; opening connects the RPC, checks `server_version` (`get info`), then the
//! streams with `carrier`, as C++'s. Commands are sent as C++ sends them: words as strings.

use parking_lot::Mutex;
use std::sync::Arc;
use std::time::{Duration, Instant};
use yarp_devices::cartesian_control::CartesianEvent;
use yarp_devices::driver::DeviceDriver;
use yarp_devices::error::{DevResult, DeviceError};
use yarp_devices::gaze_control::IGazeControl;
use yarp_devices::runtime;
use yarp_net::port::Port;
use yarp_proto::{Bottle, Property, Value};

use crate::gaze::core::SERVER_VERSION;
use crate::module_client::ModuleLink;
use crate::protocol;

/// The C++ device name.
pub const NAME: &str = "gazecontrollerclient";

/// The client's ports, in the order they open (the RPC one first).
const PORTS: [&str; 9] = [
    "rpc", "xd:o", "angles:o", "mono:o", "stereo:o", "x:i", "angles:i", "q:i", "events:i",
];
const XD: usize = 1;
const ANGLES_OUT: usize = 2;
const MONO: usize = 3;
const STEREO: usize = 4;
const X_IN: usize = 5;
const ANGLES_IN: usize = 6;
const Q_IN: usize = 7;
const EVENTS: usize = 8;

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

/// The latest fixation point and angles the module streamed.
#[derive(Default)]
struct Streams {
    x: Latest,
    angles: Latest,
}

type Link = ModuleLink<Streams>;

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
        self.link()?.ack(cmd)
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
        let mut link = ModuleLink::open(
            NAME,
            "the prefix of a running iKinGazeCtrl",
            (&p.local, &p.remote),
            &PORTS,
            "rpc",
            Duration::from_secs_f64(p.timeout),
            Streams::default(),
        )?;
        link.spawn(keep_latest(link.port(X_IN), link.streams.x.clone()));
        link.spawn(keep_latest(
            link.port(ANGLES_IN),
            link.streams.angles.clone(),
        ));
        link.read_events(EVENTS);
        self.link = Some(link);
        // C++'s handshake: the server's version, then every stream
        let result = (|| {
            let info = self.ack(words(&["get", "info"]))?;
            let link = self.link()?;
            link.check_version(&info, SERVER_VERSION)?;
            link.connect_streams(
                &p.carrier,
                &[
                    (XD, "xd:i"),
                    (ANGLES_OUT, "angles:i"),
                    (MONO, "mono:i"),
                    (STEREO, "stereo:i"),
                ],
                &[
                    ("x:o", X_IN),
                    ("angles:o", ANGLES_IN),
                    ("q:o", Q_IN),
                    ("events:o", EVENTS),
                ],
            )
        })();
        if result.is_err() {
            let _ = self.close();
        }
        result
    }

    fn close(&mut self) -> DevResult<()> {
        if let Some(link) = self.link.take() {
            // the contexts this client stored go with it, as C++'s close
            let ids: Vec<i32> = link.contexts.iter().copied().collect();
            let delete = (!ids.is_empty()).then(|| words(&["del"]).with(protocol::i32_list(ids)));
            link.close(delete);
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
        let (v, t) = Self::latest(link, &link.streams.x, "getFixationPoint")?;
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
        let (v, _) = Self::latest(link, &link.streams.angles, "getAngles")?;
        match v[..] {
            [a, b, c, ..] => Ok([a, b, c]),
            _ => Err(DeviceError::WrongSize {
                expected: 3,
                got: v.len(),
            }),
        }
    }

    fn look_at_fixation_point(&mut self, x: &[f64; 3]) -> DevResult<()> {
        let port = self.link()?.port(XD);
        self.stream(port, x.iter().copied().collect());
        Ok(())
    }

    fn look_at_fixation_point_sync(&mut self, x: &[f64; 3]) -> DevResult<()> {
        self.ack(words(&["look", "3D"]).with(protocol::f64_list(x)))
            .map(drop)
    }

    fn look_at_abs_angles(&mut self, ang: &[f64; 3]) -> DevResult<()> {
        let port = self.link()?.port(ANGLES_OUT);
        let mut b = Bottle::new().with("abs");
        for a in ang {
            b.push(*a);
        }
        self.stream(port, b);
        Ok(())
    }

    fn look_at_rel_angles(&mut self, ang: &[f64; 3]) -> DevResult<()> {
        let port = self.link()?.port(ANGLES_OUT);
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
        self.link()?.check_context(id)?;
        self.ack(words(&["rest"]).with(Value::Int32(id))).map(drop)
    }

    fn delete_context(&mut self, id: i32) -> DevResult<()> {
        self.link()?.forget_context(id)?;
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
        self.link
            .as_ref()
            .map(Link::take_events)
            .unwrap_or_default()
    }
}
