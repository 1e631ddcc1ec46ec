//! `rgbdSensor_nws_yarp` (C++ YARP 3.12 `RgbdSensor_nws_yarp`): serves an attached
//! `IRGBDSensor` on YARP ports.
//!
//! Parameters as C++: `name` (required port prefix) and `period` (s, default 0.02). The
//! ports open with the device: `<name>/rgbImage:o` (the colour image, with its
//! envelope), `<name>/depthImage:o` (the depth image, `PixelFloat` in meters) and
//! `<name>/rpc:i` (3.12's vocabs, [`super::protocol`], and YARP 4.0's `RGBDSensorMsgs`,
//! [`super::v4`], told apart by the request; 4.0 names the device `RGBDSensor_nws_yarp`,
//! keeping this name as an alias). Each image reader gets its generation's header.
//! Images stream from attach on, while the
//! sensor is `OK_IN_USE`, each only when its time stamp moved forward, as C++ does.
//! The images come from a thread of their own: a camera's `getImages` may block.

use super::protocol::handle_rpc;
use super::RgbdStatus;
use crate::driver::{DeviceDriver, IWrapper, SharedDevice};
use crate::error::{DevResult, DeviceError};
use crate::framegrabber::nws::send_image_nowait;
use crate::wrapper_ports::{Reply, Slot, WrapperPorts};
use std::sync::{mpsc, Arc};
use std::time::{Duration, Instant};
use yarp_net::peer_generation::PeerGenerations;
use yarp_net::port::Port;
use yarp_proto::tags::Generation;
use yarp_proto::{Bottle, Property};

const NAME: &str = "rgbdSensor_nws_yarp";

crate::device_params! {
    /// What `rgbdSensor_nws_yarp` reads (C++ `RgbdSensor_nws_yarp_params.md`).
    pub struct RgbdSensorNwsYarpParams for "rgbdSensor_nws_yarp" {
        /// refresh period of the broadcasted values in s
        period: f64 = 0.02; "s"; check crate::params::positive,
        /// Prefix name of the ports opened by the RGBD wrapper, e.g. /robotName/RGBD
        name: String = required; check crate::params::port_name,
    }
}

struct Streaming {
    stop: mpsc::Sender<()>,
    thread: std::thread::JoinHandle<()>,
}

/// The `rgbdSensor_nws_yarp` device.
#[derive(Default)]
pub struct RgbdSensorNwsYarp {
    name: String,
    period: Duration,
    slot: Slot,
    ports: Option<WrapperPorts>,
    streaming: Option<Streaming>,
}

impl RgbdSensorNwsYarp {
    pub fn new() -> Self {
        Self::default()
    }

    pub fn rgb_port_name(&self) -> String {
        format!("{}/rgbImage:o", self.name)
    }

    pub fn depth_port_name(&self) -> String {
        format!("{}/depthImage:o", self.name)
    }

    pub fn rpc_port_name(&self) -> String {
        format!("{}/rpc:i", self.name)
    }
}

/// Writes the images of one period (C++ `writeData`); `last` holds the times of the
/// images sent before.
fn write_images(
    device: &SharedDevice,
    (rgb, depth): (&Arc<Port>, &Arc<Port>),
    readers: &PeerGenerations,
    last: &mut (f64, f64),
) {
    let got = {
        let mut pd = device.lock();
        let Some(dev) = pd.device().as_rgbd_sensor() else {
            return;
        };
        match dev.sensor_status() {
            RgbdStatus::OkInUse => dev.get_images(),
            RgbdStatus::NotReady => return,
            other => {
                tracing::debug!("{NAME}: sensor status {other:?}");
                return;
            }
        }
    };
    match got {
        Ok(((color, cs), (dimg, ds))) => {
            if cs.time > last.0 {
                last.0 = cs.time;
                if rgb.has_outputs() {
                    send_image_nowait(rgb, readers, &color, cs);
                }
            }
            if ds.time > last.1 {
                last.1 = ds.time;
                if depth.has_outputs() {
                    send_image_nowait(depth, readers, &dimg, ds);
                }
            }
        }
        Err(e) => tracing::error!("{NAME}: image not captured: {e}"),
    }
}

fn stream_images(
    device: SharedDevice,
    (rgb, depth): (Arc<Port>, Arc<Port>),
    readers: PeerGenerations,
    period: Duration,
    stop: mpsc::Receiver<()>,
) {
    let mut last = (0.0, 0.0);
    let mut next = Instant::now();
    loop {
        next += period;
        match stop.recv_timeout(next.saturating_duration_since(Instant::now())) {
            Err(mpsc::RecvTimeoutError::Timeout) => {}
            _ => return,
        }
        if next < Instant::now() {
            // fell behind (slow camera): count again from now
            next = Instant::now();
        }
        if rgb.has_outputs() || depth.has_outputs() {
            write_images(&device, (&rgb, &depth), &readers, &mut last);
        }
    }
}

/// 3.12's vocab protocol, or 4.0's thrift service (each its own request form).
fn answer(cmd: &Bottle, dev: Option<&mut dyn DeviceDriver>, _: Generation) -> Reply {
    if super::v4::is_call(cmd) {
        return Reply::Encoded(super::v4::handle_rpc(cmd, dev));
    }
    Reply::Bottle(handle_rpc(cmd, dev.and_then(|d| d.as_rgbd_sensor())))
}

impl DeviceDriver for RgbdSensorNwsYarp {
    fn parameters(&self) -> Vec<crate::params::ParamSpec> {
        RgbdSensorNwsYarpParams::PARAMS.to_vec()
    }

    fn open(&mut self, config: &Property) -> DevResult<()> {
        let p = RgbdSensorNwsYarpParams::read(config)?;
        self.name = p.name.trim_end_matches('/').to_string();
        self.period = Duration::from_secs_f64(p.period);
        let ports = WrapperPorts::open(
            NAME,
            vec![self.rgb_port_name(), self.depth_port_name()],
            self.rpc_port_name(),
            self.slot.clone(),
            answer,
            |_| None,
        )?;
        self.ports = Some(ports);
        Ok(())
    }

    fn close(&mut self) -> DevResult<()> {
        IWrapper::detach(self)?;
        if let Some(p) = self.ports.take() {
            p.close();
        }
        Ok(())
    }

    crate::views!(as_wrapper, as_multiple_wrapper);
}

impl IWrapper for RgbdSensorNwsYarp {
    fn attach(&mut self, device: SharedDevice) -> DevResult<()> {
        IWrapper::detach(self)?;
        let Some(ports) = &self.ports else {
            return Err(DeviceError::NotOpen);
        };
        {
            let mut pd = device.lock();
            if pd.device().as_rgbd_sensor().is_none() {
                return Err(DeviceError::Unsupported(
                    "rgbdSensor_nws_yarp attaches an IRGBDSensor",
                ));
            }
        }
        *self.slot.lock() = Some(device.clone());
        let (rgb, depth, period) = (
            ports.streams[0].clone(),
            ports.streams[1].clone(),
            self.period,
        );
        let readers = ports.peers.clone();
        let (stop, rx) = mpsc::channel();
        let thread = std::thread::Builder::new()
            .name(NAME.into())
            .spawn(move || stream_images(device, (rgb, depth), readers, period, rx))
            .map_err(|e| DeviceError::BadParam {
                device: NAME.into(),
                param: "period".into(),
                expected: "a thread for the images",
                got: e.to_string(),
            })?;
        self.streaming = Some(Streaming { stop, thread });
        Ok(())
    }

    fn detach(&mut self) -> DevResult<()> {
        if let Some(s) = self.streaming.take() {
            let _ = s.stop.send(());
            let _ = s.thread.join();
        }
        *self.slot.lock() = None;
        Ok(())
    }
}

crate::one_device_multiple_wrapper!(
    RgbdSensorNwsYarp,
    "rgbdSensor_nws_yarp attaches exactly one device"
);
