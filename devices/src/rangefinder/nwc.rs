//! `rangefinder2D_nwc_yarp` (C++ YARP 3.12 `Rangefinder2D_nwc_yarp`): an `IRangefinder2D`
//! read from a `rangefinder2D_nws_yarp`.
//!
//! Parameters as C++: `local` (the port receiving the scans; the RPC port is
//! `<local>/rpc:o`), `remote` (the server's streaming port; its RPC port is
//! `<remote>/rpc:i`), `carrier` (of the stream, default `tcp`). Scans and their time come
//! from the stream (empty before the first one, as C++); the device status is the last
//! scan's (`DEVICE_TIMEOUT` before any); the rest goes through the server's
//! `IRangefinder2DMsgs` service.

use super::protocol::{status_of, LaserScan2D};
use super::{IRangefinder2D, LaserStatus};
use crate::driver::DeviceDriver;
use crate::error::{DevResult, DeviceError};
use crate::nwc_ports::{NwcNames, OpenPorts};
use yarp_proto::{Bottle, Property, Value};

const NAME: &str = "rangefinder2D_nwc_yarp";

crate::device_params! {
    /// What `rangefinder2D_nwc_yarp` reads (C++ `Rangefinder2D_nwc_yarp_params.md`).
    pub struct Rangefinder2DNwcYarpParams for "rangefinder2D_nwc_yarp" {
        /// Full port name opened by the Rangefinder2D_nwc_yarp device.
        local: String = required,
        /// Full port name of the port opened on the server side, to which the Rangefinder2D_nwc_yarp connects to.
        remote: String = required,
        /// The carrier used for the connection with the server.
        carrier: String = "tcp",
    }
}

/// The `rangefinder2D_nwc_yarp` device.
#[derive(Default)]
pub struct Rangefinder2DNwcYarp {
    client: OpenPorts<LaserScan2D>,
}

impl Rangefinder2DNwcYarp {
    pub fn new() -> Self {
        Self::default()
    }

    /// Calls `method` (a thrift name such as `getScanRate_RPC`) with `args`; the fields
    /// after the return code, or the failure.
    fn call(&self, method: &str, args: &[f64]) -> DevResult<Vec<Value>> {
        let client = self.client.get()?;
        let mut cmd = Bottle::new();
        for word in method.split('_') {
            cmd.push(word);
        }
        for &a in args {
            cmd.push(a);
        }
        client.call_returning(cmd, "the remote rangefinder does not implement this")
    }

    fn floats(&self, method: &str, n: usize) -> DevResult<Vec<f64>> {
        let fields = self.call(method, &[])?;
        let nums: Vec<f64> = fields.iter().filter_map(Value::as_f64).collect();
        if nums.len() == n {
            Ok(nums)
        } else {
            Err(DeviceError::failed(
                NAME,
                format!("{method}: malformed reply {fields:?}"),
            ))
        }
    }
}

impl DeviceDriver for Rangefinder2DNwcYarp {
    fn parameters(&self) -> Vec<crate::params::ParamSpec> {
        Rangefinder2DNwcYarpParams::PARAMS.to_vec()
    }

    fn open(&mut self, config: &Property) -> DevResult<()> {
        let Rangefinder2DNwcYarpParams {
            local,
            remote,
            carrier,
        } = Rangefinder2DNwcYarpParams::read(config)?;
        let names = NwcNames {
            rpc: format!("{local}/rpc:o"),
            remote_rpc: format!("{remote}/rpc:i"),
            stream: local,
            remote_stream: remote,
            carrier,
        };
        self.client.open(
            NAME,
            "a running rangefinder2D_nws_yarp port (is the name server running?)",
            names,
            LaserScan2D::from_bottle,
        )
    }

    fn close(&mut self) -> DevResult<()> {
        self.client.close();
        Ok(())
    }

    crate::views!(as_rangefinder_2d);
}

impl IRangefinder2D for Rangefinder2DNwcYarp {
    fn get_raw_data(&mut self) -> DevResult<(Vec<f64>, f64)> {
        let c = self.client.get()?;
        let latest = c.latest();
        Ok(latest
            .as_ref()
            .map_or((Vec::new(), 0.0), |(s, t)| (s.scans.clone(), *t)))
    }
    fn get_device_status(&mut self) -> DevResult<LaserStatus> {
        let c = self.client.get()?;
        let latest = c.latest();
        Ok(latest
            .as_ref()
            .and_then(|(s, _)| status_of(s.status))
            .unwrap_or(LaserStatus::Timeout))
    }
    fn get_distance_range(&mut self) -> DevResult<(f64, f64)> {
        let v = self.floats("getDistanceRange_RPC", 2)?;
        Ok((v[0], v[1]))
    }
    fn set_distance_range(&mut self, min: f64, max: f64) -> DevResult<()> {
        self.call("setDistanceRange_RPC", &[min, max]).map(|_| ())
    }
    fn get_scan_limits(&mut self) -> DevResult<(f64, f64)> {
        let v = self.floats("getScanLimits_RPC", 2)?;
        Ok((v[0], v[1]))
    }
    fn set_scan_limits(&mut self, min: f64, max: f64) -> DevResult<()> {
        self.call("setScanLimits_RPC", &[min, max]).map(|_| ())
    }
    fn get_horizontal_resolution(&mut self) -> DevResult<f64> {
        Ok(self.floats("getHorizontalResolution_RPC", 1)?[0])
    }
    fn set_horizontal_resolution(&mut self, step: f64) -> DevResult<()> {
        self.call("setHorizontalResolution_RPC", &[step])
            .map(|_| ())
    }
    fn get_scan_rate(&mut self) -> DevResult<f64> {
        Ok(self.floats("getScanRate_RPC", 1)?[0])
    }
    fn set_scan_rate(&mut self, rate: f64) -> DevResult<()> {
        self.call("setScanRate_RPC", &[rate]).map(|_| ())
    }
    fn get_device_info(&mut self) -> DevResult<String> {
        let fields = self.call("getDeviceInfo_RPC", &[])?;
        fields
            .first()
            .and_then(Value::as_str)
            .map(str::to_string)
            .ok_or_else(|| DeviceError::failed(NAME, "getDeviceInfo_RPC: malformed reply"))
    }
}
