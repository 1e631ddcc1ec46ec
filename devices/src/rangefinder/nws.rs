//! `rangefinder2D_nws_yarp` (C++ YARP 3.12 `Rangefinder2D_nws_yarp`): serves an attached
//! `IRangefinder2D` on YARP ports.
//!
//! Parameters as C++: `name` (required: the streaming port itself, e.g.
//! `/ergocub/laser:o`; the RPC port is `<name>/rpc:i`), `period` (s, default 0.02),
//! `frame_id` (accepted, unused as in C++). The ports open with the device; the scan
//! stream starts on attach (a `LaserScan2D` every period, with an envelope); RPC before
//! attach answers `return_value_error_not_ready`.

use super::protocol::{handle_rpc, LaserScan2D};
use crate::driver::{DeviceDriver, IWrapper, SharedDevice};
use crate::error::{DevResult, DeviceError};
use crate::sensors::params::now;
use crate::sensors::periodic::Ticker;
use crate::wrapper_ports::{FailureStreak, Reply, Serving};
use std::sync::Arc;
use std::time::Duration;
use yarp_net::peer_generation::PeerGenerations;
use yarp_net::port::Port;
use yarp_proto::tags::Generation;
use yarp_proto::{Bottle, Property, Stamp};

const NAME: &str = "rangefinder2D_nws_yarp";

crate::device_params! {
    /// What `rangefinder2D_nws_yarp` reads (C++ `Rangefinder2D_nws_yarp_params.md`).
    pub struct Rangefinder2DNwsYarpParams for "rangefinder2D_nws_yarp" {
        /// refresh period of the broadcasted values in s
        period: f64 = 0.02; "s"; check crate::params::positive,
        /// Prefix name of the ports opened by the wrapper, e.g. /robotName/Rangefinder2DSensor
        name: String = required; check crate::params::port_name,
        /// name of the attached frame
        frame_id: String = optional,
    }
}

/// The `rangefinder2D_nws_yarp` device.
#[derive(Default)]
pub struct Rangefinder2DNwsYarp {
    name: String,
    period: Duration,
    serving: Serving,
}

impl Rangefinder2DNwsYarp {
    pub fn new() -> Self {
        Self::default()
    }

    /// The streaming port (`name`).
    pub fn streaming_port_name(&self) -> &str {
        &self.name
    }

    /// The RPC port (`<name>/rpc:i`).
    pub fn rpc_port_name(&self) -> String {
        format!("{}/rpc:i", self.name)
    }
}

/// One scan of the attached device, or why not.
fn read_scan(device: &SharedDevice) -> DevResult<(LaserScan2D, f64)> {
    let mut pd = device.lock();
    let dev = pd
        .device()
        .as_rangefinder_2d()
        .ok_or(DeviceError::Unsupported(
            "the attached device is no IRangefinder2D",
        ))?;
    let (scans, t) = dev.get_raw_data()?;
    let status = dev.get_device_status()?;
    let (range_min, range_max) = dev.get_distance_range()?;
    let (angle_min, angle_max) = dev.get_scan_limits()?;
    let scan = LaserScan2D {
        angle_min,
        angle_max,
        range_min,
        range_max,
        scans,
        status: status as i32,
    };
    Ok((scan, if t.is_nan() { now() } else { t }))
}

async fn stream_scans(
    port: Arc<Port>,
    peers: PeerGenerations,
    period: Duration,
    device: SharedDevice,
) {
    let mut ticker = Ticker::new(period);
    let mut count: i32 = 0;
    let mut failing = FailureStreak::default();
    loop {
        ticker.tick().await;
        if !port.has_outputs() {
            continue;
        }
        match read_scan(&device) {
            Ok((scan, t)) => {
                failing.passed();
                port.write_by_generation(&scan.to_bottle(), &peers, Some(Stamp::new(count, t)))
                    .await;
                count = count.wrapping_add(1);
            }
            Err(e) => failing.failed(|| format!("{NAME}: sensor returned error: {e}")),
        }
    }
}

fn answer(cmd: &Bottle, dev: Option<&mut dyn DeviceDriver>, generation: Generation) -> Reply {
    Reply::Encoded(handle_rpc(
        cmd,
        dev.and_then(|d| d.as_rangefinder_2d()),
        generation,
    ))
}

impl DeviceDriver for Rangefinder2DNwsYarp {
    fn parameters(&self) -> Vec<crate::params::ParamSpec> {
        Rangefinder2DNwsYarpParams::PARAMS.to_vec()
    }

    fn open(&mut self, config: &Property) -> DevResult<()> {
        let p = Rangefinder2DNwsYarpParams::read(config)?;
        self.name = p.name;
        self.period = Duration::from_secs_f64(p.period);
        self.serving.open(
            NAME,
            vec![self.name.clone()],
            self.rpc_port_name(),
            answer,
            // C++'s client reads the scans on `<local>`, calls from `<local>/rpc:o`
            |rpc| rpc.strip_suffix("/rpc:o").map(str::to_string),
        )
    }

    fn close(&mut self) -> DevResult<()> {
        self.serving.close();
        Ok(())
    }

    crate::views!(as_wrapper, as_multiple_wrapper);
}

impl IWrapper for Rangefinder2DNwsYarp {
    fn attach(&mut self, device: SharedDevice) -> DevResult<()> {
        let period = self.period;
        self.serving.attach(
            device,
            |d| {
                // C++ refuses a device that cannot tell its geometry
                let dev = d.as_rangefinder_2d().ok_or(DeviceError::Unsupported(
                    "rangefinder2D_nws_yarp attaches an IRangefinder2D",
                ))?;
                dev.get_distance_range()?;
                dev.get_scan_limits()?;
                dev.get_horizontal_resolution()?;
                Ok(())
            },
            |ports, device| {
                stream_scans(
                    ports.streams[0].clone(),
                    ports.peers.clone(),
                    period,
                    device,
                )
            },
        )
    }

    fn detach(&mut self) -> DevResult<()> {
        self.serving.detach();
        Ok(())
    }
}

crate::one_device_multiple_wrapper!(
    Rangefinder2DNwsYarp,
    "rangefinder2D_nws_yarp attaches exactly one device"
);
