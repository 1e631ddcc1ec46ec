//! `frameGrabber_nws_yarp`: serves a camera on the network as C++ 3.12 does.
//!
//! Parameters: `name` (port prefix, default `/grabber`), `period` (seconds between
//! images, default 0.033), `capabilities` (`COLOR`, the default; `RAW` needs a raw
//! grabber, which no device here has), `no_drop` (wait for slow readers instead of
//! dropping images).
//!
//! Ports: `<name>` streams images (with the device's stamp as envelope, only while
//! something is connected, as C++ skips `getImage` otherwise); `<name>/rpc` answers the
//! frame-grabber RPC protocol of 3.12 ([`super::protocol::handle_rpc`]) and of YARP 4.0
//! ([`super::v4`]), told apart by the request. Each reader gets images in its own
//! generation's header (4.0 dropped `topIsLow`).

use super::image::Image;
use super::protocol::handle_rpc;
use crate::driver::{DeviceDriver, IWrapper, SharedDevice};
use crate::error::{DevResult, DeviceError};
use crate::params::{IntoDefault, ParamType, Params};
use crate::runtime;
use parking_lot::Mutex;
use std::sync::mpsc;
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};
use yarp_net::nameserver::NameClient;
use yarp_net::peer_generation::PeerGenerations;
use yarp_net::port::{Port, PortError};
use yarp_proto::tags::Generation;
use yarp_proto::{Property, Stamp, Value};

const NAME: &str = "frameGrabber_nws_yarp";
/// C++ `DEFAULT_THREAD_PERIOD` of this wrapper.
pub const DEFAULT_PERIOD: f64 = 0.033;

/// `period` as C++ takes it: only a float counts, anything else leaves the default.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FloatPeriod(pub f64);

impl ParamType for FloatPeriod {
    const TYPE: &'static str = "double";
    fn read(p: &Params<'_>, key: &str) -> DevResult<Option<Self>> {
        match p.find(key) {
            Some(Value::Float64(s)) if *s > 0.0 && s.is_finite() => Ok(Some(FloatPeriod(*s))),
            Some(Value::Float64(s)) => Err(p.invalid(key, "a period in seconds greater than 0", s)),
            Some(other) => {
                tracing::info!(
                    "{NAME}: `{key} {other}` is not a float: using {DEFAULT_PERIOD} s, as C++ does"
                );
                Ok(None)
            }
            None => Ok(None),
        }
    }
}

impl IntoDefault<FloatPeriod> for f64 {
    fn into_default(self) -> FloatPeriod {
        FloatPeriod(self)
    }
}

/// Only COLOR streaming is offered.
fn color_only(capabilities: &str) -> Result<(), &'static str> {
    match capabilities {
        "COLOR" => Ok(()),
        _ => Err("COLOR (RAW streaming is not available)"),
    }
}

crate::device_params! {
    /// What `frameGrabber_nws_yarp` reads (C++ `FrameGrabber_nws_yarp_params.md`; C++'s
    /// `no_drop` defaults to true in the table but to false in the code, which we follow).
    pub struct FrameGrabberNwsYarpParams for "frameGrabber_nws_yarp" {
        /// refresh period (in s) of the broadcasted values through yarp ports
        period: FloatPeriod = 0.033; "s",
        /// Prefix name of the ports opened by the FrameGrabber_nws_yarp
        name: String = "/grabber",
        /// two capabilities supported, COLOR and RAW respectively for rgb and raw streaming
        capabilities: String = "COLOR"; check color_only,
        /// if present, use strict policy for sending data
        no_drop: bool = false,
    }
}

/// The device the RPC server talks to (none until attached).
type Target = Arc<Mutex<Option<SharedDevice>>>;

/// The open ports and their serving work.
struct Server {
    image_port: Arc<Port>,
    rpc_port: Arc<Port>,
    rpc_task: tokio::task::JoinHandle<()>,
    target: Target,
    /// The generations of the image readers.
    readers: PeerGenerations,
}

impl Server {
    async fn open(name: &str, ns: NameClient, target: Target) -> Result<Server, PortError> {
        let rpc_port = Arc::new(Port::open(&format!("{name}/rpc"), ns.clone()).await?);
        let readers = PeerGenerations::new(ns.clone());
        let image_port = match Port::open(name, ns).await {
            Ok(p) => Arc::new(p),
            Err(e) => {
                if let Ok(p) = Arc::try_unwrap(rpc_port) {
                    p.close().await;
                }
                return Err(e);
            }
        };
        let rpc_task = tokio::spawn(serve_rpc(rpc_port.clone(), target.clone()));
        Ok(Server {
            image_port,
            rpc_port,
            rpc_task,
            target,
            readers,
        })
    }

    async fn close(self) {
        self.rpc_task.abort();
        let _ = self.rpc_task.await;
        for port in [self.rpc_port, self.image_port] {
            if let Ok(p) = Arc::try_unwrap(port) {
                p.close().await;
            }
        }
    }
}

/// A device with no interfaces: what the responders see before anything is attached.
struct Nothing;
impl DeviceDriver for Nothing {
    fn open(&mut self, _: &Property) -> DevResult<()> {
        Ok(())
    }
}

async fn serve_rpc(port: Arc<Port>, target: Target) {
    while let Some(mut msg) = port.read().await {
        let cmd = match msg.bottle() {
            Ok(b) => b,
            Err(e) => {
                tracing::warn!("{NAME}: undecodable RPC message: {e}");
                continue;
            }
        };
        let dev = target.lock().clone();
        let four = super::v4::is_call(&cmd);
        let serve = |d: &mut dyn DeviceDriver| {
            if four {
                Err(super::v4::handle_rpc(&cmd, d))
            } else {
                Ok(handle_rpc(&cmd, d))
            }
        };
        let reply = match dev {
            Some(dev) => crate::runtime::device_call(|| serve(dev.lock().device())),
            None => serve(&mut Nothing),
        };
        if msg.wants_reply() {
            match reply {
                Ok(bottle) => msg.reply(bottle),
                // a 4.0 thrift reply, in the generated writer's own bytes
                Err(bytes) => msg.reply_encoded(bytes),
            }
        }
    }
}

/// The periodic image publisher (C++ `PeriodicThread::run`).
struct Streamer {
    stop: mpsc::Sender<()>,
    thread: JoinHandle<()>,
}

use yarp_proto::stamp::now;

fn stream(
    port: Arc<Port>,
    readers: PeerGenerations,
    dev: SharedDevice,
    period: Duration,
    no_drop: bool,
    stop: mpsc::Receiver<()>,
) {
    let mut own_count: i32 = 0;
    let mut next = Instant::now();
    loop {
        next += period;
        let wait = next.saturating_duration_since(Instant::now());
        match stop.recv_timeout(wait) {
            Err(mpsc::RecvTimeoutError::Timeout) => {}
            _ => return,
        }
        if next < Instant::now() {
            // fell behind (slow device): start counting again from now
            next = Instant::now();
        }
        if !port.has_outputs() {
            continue;
        }
        let got = crate::runtime::device_call(|| {
            let mut pd = dev.lock();
            pd.device()
                .as_frame_grabber_image()
                .map(|fg| (fg.get_image(), fg.last_input_stamp()))
        });
        let (img, stamp) = match got {
            Some((Ok(img), stamp)) => (img, stamp),
            Some((Err(e), _)) => {
                tracing::error!("{NAME}: image not captured (getImage failed: {e})");
                continue;
            }
            None => {
                tracing::error!("{NAME}: image not captured (invalid interface)");
                continue;
            }
        };
        let stamp = stamp.unwrap_or_else(|| {
            let s = Stamp::new(own_count, now());
            own_count = own_count.wrapping_add(1);
            s
        });
        if no_drop {
            crate::wrapper_ports::learn_readers(port.outputs(), &readers);
            let forms = [
                (Arc::new(img.to_bottle()), Generation::V3),
                (Arc::new(img.to_bottle_as(Generation::V4)), Generation::V4),
            ];
            let (port, readers) = (port.clone(), readers.clone());
            runtime::block_on_logged("nws: closing", async move {
                port.write_shared_each(&forms, |to| form_of(&readers, to), Some(stamp))
                    .await;
            });
        } else {
            send_image_nowait(&port, &readers, &img, stamp);
        }
    }
}

/// Sends `img` to each reader of `port` in its generation's header, without waiting
/// for them (from a plain thread; readers new to `readers` are asked first).
pub(crate) fn send_image_nowait(
    port: &Arc<Port>,
    readers: &PeerGenerations,
    img: &Image,
    stamp: Stamp,
) {
    crate::wrapper_ports::learn_readers(port.outputs(), readers);
    let forms = [
        (img.to_bottle(), Generation::V3),
        (img.to_bottle_as(Generation::V4), Generation::V4),
    ];
    port.write_nowait_each(&forms, |to| form_of(readers, to), Some(stamp));
}

/// Which of a message's forms (3.x's, 4.0's) the reader `to` takes, once known.
fn form_of(readers: &PeerGenerations, to: &str) -> Option<usize> {
    readers.known(to).map(|g| match g {
        Generation::V3 => 0,
        Generation::V4 => 1,
    })
}

/// The `frameGrabber_nws_yarp` device.
pub struct FrameGrabberNws {
    name: String,
    period: f64,
    no_drop: bool,
    server: Option<Server>,
    streamer: Option<Streamer>,
}

impl FrameGrabberNws {
    pub fn new() -> FrameGrabberNws {
        FrameGrabberNws {
            name: "/grabber".into(),
            period: DEFAULT_PERIOD,
            no_drop: false,
            server: None,
            streamer: None,
        }
    }

    /// The image port's name.
    pub fn name(&self) -> &str {
        &self.name
    }

    fn stop_streaming(&mut self) {
        if let Some(s) = self.streamer.take() {
            let _ = s.stop.send(());
            let _ = s.thread.join();
        }
    }
}

impl DeviceDriver for FrameGrabberNws {
    fn parameters(&self) -> Vec<crate::params::ParamSpec> {
        FrameGrabberNwsYarpParams::PARAMS.to_vec()
    }

    fn open(&mut self, config: &Property) -> DevResult<()> {
        let p = FrameGrabberNwsYarpParams::read(config)?;
        self.name = p.name;
        self.period = p.period.0;
        self.no_drop = p.no_drop;
        let network = |e: String| DeviceError::BadParam {
            device: NAME.into(),
            param: "name".into(),
            expected: "a port name that can be registered (is the name server running?)",
            got: e,
        };
        let ns = yarp_net::network::name_client().map_err(|e| network(e.to_string()))?;
        let name = self.name.clone();
        let server = runtime::block_on_result(async move {
            Server::open(&name, ns, Target::default())
                .await
                .map_err(|e| format!("{name}: {e}"))
        })
        .map_err(network)?;
        self.close()?;
        self.server = Some(server);
        Ok(())
    }

    fn close(&mut self) -> DevResult<()> {
        self.stop_streaming();
        if let Some(s) = self.server.take() {
            runtime::block_on_logged("nws: closing", s.close());
        }
        Ok(())
    }

    crate::views!(as_wrapper);
}

impl IWrapper for FrameGrabberNws {
    fn attach(&mut self, device: SharedDevice) -> DevResult<()> {
        if self.server.is_none() {
            return Err(DeviceError::NotOpen);
        }
        {
            let mut pd = device.lock();
            if pd.device().as_frame_grabber_image().is_none() {
                return Err(DeviceError::Unsupported(
                    "frameGrabber_nws_yarp: the attached device has no IFrameGrabberImage (capability COLOR)",
                ));
            }
        }
        self.stop_streaming();
        let server = self.server.as_ref().ok_or(DeviceError::NotOpen)?;
        *server.target.lock() = Some(device.clone());
        let (stop, rx) = mpsc::channel();
        let port = server.image_port.clone();
        let readers = server.readers.clone();
        let period = Duration::from_secs_f64(self.period);
        let no_drop = self.no_drop;
        let thread = std::thread::Builder::new()
            .name("frameGrabber_nws".into())
            .spawn(move || stream(port, readers, device, period, no_drop, rx))
            .map_err(|_| DeviceError::Unsupported("cannot start the streaming thread"))?;
        self.streamer = Some(Streamer { stop, thread });
        Ok(())
    }

    fn detach(&mut self) -> DevResult<()> {
        self.stop_streaming();
        if let Some(s) = &self.server {
            *s.target.lock() = None;
        }
        Ok(())
    }
}

impl Default for FrameGrabberNws {
    fn default() -> Self {
        Self::new()
    }
}

impl Drop for FrameGrabberNws {
    fn drop(&mut self) {
        let _ = self.close();
    }
}
