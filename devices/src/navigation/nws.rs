//! `odometry2D_nws_yarp` (C++ YARP 3.12/4.0 `Odometry2D_nws_yarp`): serves an attached
//! `IOdometry2D` on YARP ports, as R1's base odometry is served.
//!
//! Parameters as C++: `name` (default `/odometry2D_nws_yarp`) and `period` (s, default
//! 0.02). Ports: `<name>/odometry:o` (`OdometryData`), `<name>/odometer:o` and
//! `<name>/velocity:o` (two float64 each, see [`super::protocol`]), every period from
//! attach, all with the same envelope (the odometry's own time, or now when it has none);
//! `<name>/rpc` answers `reset_odometry_RPC`.

use super::protocol::{handle_rpc, odometer, velocity};
use crate::driver::{DeviceDriver, IWrapper, SharedDevice};
use crate::error::{DevResult, DeviceError};
use crate::sensors::params::now;
use crate::sensors::periodic::Ticker;
use crate::wrapper_ports::{Reply, Serving};
use std::sync::Arc;
use std::time::Duration;
use yarp_net::peer_generation::PeerGenerations;
use yarp_net::port::Port;
use yarp_proto::tags::Generation;
use yarp_proto::{Bottle, Property, Stamp};

const NAME: &str = "odometry2D_nws_yarp";

crate::device_params! {
    /// What `odometry2D_nws_yarp` reads (C++ `Odometry2D_nws_yarp_params.md`).
    pub struct Odometry2DNwsYarpParams for "odometry2D_nws_yarp" {
        /// refresh period of the broadcasted values in s
        period: f64 = 0.02; "s"; check crate::params::positive,
        /// The name of the server, used as a prefix for the opened ports
        name: String = "/odometry2D_nws_yarp"; check crate::params::port_name,
    }
}

/// The `odometry2D_nws_yarp` device.
#[derive(Default)]
pub struct Odometry2DNwsYarp {
    name: String,
    period: Duration,
    serving: Serving,
}

impl Odometry2DNwsYarp {
    pub fn new() -> Self {
        Self::default()
    }

    /// The stream ports in the order they are opened: odometer, odometry, velocity.
    fn stream_names(&self) -> Vec<String> {
        ["odometer:o", "odometry:o", "velocity:o"]
            .iter()
            .map(|s| format!("{}/{s}", self.name))
            .collect()
    }
}

async fn stream_odometry(
    ports: [Arc<Port>; 3],
    peers: PeerGenerations,
    period: Duration,
    device: SharedDevice,
) {
    let [odometer_port, odometry_port, velocity_port] = ports;
    let mut ticker = Ticker::new(period);
    let mut count: i32 = 0;
    loop {
        ticker.tick().await;
        let read = {
            let mut pd = device.lock();
            match pd.device().as_odometry_2d() {
                Some(o) => o.get_odometry(),
                None => Err(DeviceError::NoInterface("IOdometry2D")),
            }
        };
        // C++ streams what the device left in its struct even when the call fails
        let (data, t) = match read {
            Ok(r) => r,
            Err(e) => {
                tracing::error!("{NAME}: {e}");
                continue;
            }
        };
        let stamp = Stamp::new(count, if t.is_nan() { now() } else { t });
        count = count.wrapping_add(1);
        for (port, bottle) in [
            (&odometry_port, data.to_bottle()),
            (&odometer_port, odometer(&data)),
            (&velocity_port, velocity(&data)),
        ] {
            if port.has_outputs() {
                port.write_by_generation(&bottle, &peers, Some(stamp)).await;
            }
        }
    }
}

fn answer(cmd: &Bottle, dev: Option<&mut dyn DeviceDriver>, generation: Generation) -> Reply {
    Reply::Encoded(handle_rpc(
        cmd,
        dev.and_then(|d| d.as_odometry_2d()),
        generation,
    ))
}

impl DeviceDriver for Odometry2DNwsYarp {
    fn parameters(&self) -> Vec<crate::params::ParamSpec> {
        Odometry2DNwsYarpParams::PARAMS.to_vec()
    }

    fn open(&mut self, config: &Property) -> DevResult<()> {
        let p = Odometry2DNwsYarpParams::read(config)?;
        self.name = p.name;
        self.period = Duration::from_secs_f64(p.period);
        self.serving.open(
            NAME,
            self.stream_names(),
            format!("{}/rpc", self.name),
            answer,
            // C++'s client reads `<local>/odometry:i`, calls from `<local>/rpc`
            |rpc| Some(format!("{}/odometry:i", rpc.strip_suffix("/rpc")?)),
        )?;
        tracing::info!("{NAME}: Waiting for device to attach");
        Ok(())
    }

    fn close(&mut self) -> DevResult<()> {
        self.serving.close();
        Ok(())
    }

    crate::views!(as_wrapper, as_multiple_wrapper);
}

impl IWrapper for Odometry2DNwsYarp {
    fn attach(&mut self, device: SharedDevice) -> DevResult<()> {
        let period = self.period;
        self.serving.attach(
            device,
            |d| {
                d.as_odometry_2d().map(drop).ok_or(DeviceError::Unsupported(
                    "Subdevice passed to attach method is invalid (no IOdometry2D)",
                ))
            },
            |ports, device| {
                let streams = [0, 1, 2].map(|i| ports.streams[i].clone());
                stream_odometry(streams, ports.peers.clone(), period, device)
            },
        )
    }

    fn detach(&mut self) -> DevResult<()> {
        self.serving.detach();
        Ok(())
    }
}

crate::one_device_multiple_wrapper!(
    Odometry2DNwsYarp,
    "odometry2D_nws_yarp attaches exactly one device"
);
