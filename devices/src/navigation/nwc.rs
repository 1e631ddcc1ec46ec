//! `odometry2D_nwc_yarp` (C++ YARP 3.12/4.0 `Odometry2D_nwc_yarp`): an `IOdometry2D` read
//! from an `odometry2D_nws_yarp`.
//!
//! Parameters as C++: `local` (the ports are `<local>/odometry:i` and `<local>/rpc`),
//! `remote` (the server's `name`: `<remote>/odometry:o` and `<remote>/rpc`), `carrier` (of
//! the stream, default `tcp`). The odometry is the last one streamed, with its envelope's
//! time (zeros before the first, as C++); `resetOdometry` calls the server.

use super::{IOdometry2D, OdometryData};
use crate::driver::DeviceDriver;
use crate::error::DevResult;
use crate::nwc_ports::{NwcNames, OpenPorts};
use yarp_proto::{Bottle, Property};

const NAME: &str = "odometry2D_nwc_yarp";

crate::device_params! {
    /// What `odometry2D_nwc_yarp` reads (C++ `Odometry2D_nwc_yarp_params.md`).
    pub struct Odometry2DNwcYarpParams for "odometry2D_nwc_yarp" {
        /// Full port name opened by the Rangefinder2D_nwc_yarp device.
        local: String = required,
        /// Full port name of the port opened on the server side, to which the Rangefinder2D_nwc_yarp connects to.
        remote: String = required,
        /// The carrier used for the connection with the server.
        carrier: String = "tcp",
    }
}

/// The `odometry2D_nwc_yarp` device.
#[derive(Default)]
pub struct Odometry2DNwcYarp {
    client: OpenPorts<OdometryData>,
}

impl Odometry2DNwcYarp {
    pub fn new() -> Self {
        Self::default()
    }
}

impl DeviceDriver for Odometry2DNwcYarp {
    fn parameters(&self) -> Vec<crate::params::ParamSpec> {
        Odometry2DNwcYarpParams::PARAMS.to_vec()
    }

    fn open(&mut self, config: &Property) -> DevResult<()> {
        let Odometry2DNwcYarpParams {
            local,
            remote,
            carrier,
        } = Odometry2DNwcYarpParams::read(config)?;
        let names = NwcNames {
            stream: format!("{local}/odometry:i"),
            remote_stream: format!("{remote}/odometry:o"),
            carrier,
            rpc: format!("{local}/rpc"),
            remote_rpc: format!("{remote}/rpc"),
        };
        self.client.open(
            NAME,
            "a running odometry2D_nws_yarp (is the name server running?)",
            names,
            OdometryData::from_bottle,
        )
    }

    fn close(&mut self) -> DevResult<()> {
        self.client.close();
        Ok(())
    }

    crate::views!(as_odometry_2d);
}

impl IOdometry2D for Odometry2DNwcYarp {
    fn get_odometry(&mut self) -> DevResult<(OdometryData, f64)> {
        let c = self.client.get()?;
        let latest = c.latest();
        Ok(latest
            .as_ref()
            .map_or((OdometryData::default(), 0.0), |(d, t)| (*d, *t)))
    }

    fn reset_odometry(&mut self) -> DevResult<()> {
        let c = self.client.get()?;
        let mut cmd = Bottle::new();
        for word in super::protocol::RESET.split('_') {
            cmd.push(word);
        }
        c.call_returning(cmd, "the remote odometry does not implement resetOdometry")
            .map(|_| ())
    }
}
