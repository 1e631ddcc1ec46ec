//! `battery_nwc_yarp` (C++ YARP 3.12 `Battery_nwc_yarp`): an `IBattery` read from a
//! `battery_nws_yarp`.
//!
//! Parameters as C++: `local` (the ports are `<local>/data:i` and `<local>/rpc:o`),
//! `remote` (the server's `name`: its ports are `<remote>/data:o` and `<remote>/rpc:i`),
//! `carrier` (of the stream, default `tcp`). Charge, voltage, current, temperature and
//! status are the last `BatteryData` streamed (the thrift defaults before the first: zeros
//! and `BATTERY_GENERAL_ERROR`, as C++); the info comes from the server's
//! `getBatteryInfoRPC`.

use super::protocol::BatteryData;
use super::{BatteryStatus, IBattery};
use crate::driver::DeviceDriver;
use crate::error::{DevResult, DeviceError};
use crate::nwc_ports::{NwcNames, OpenPorts};
use yarp_proto::{Bottle, Property, Value};

const NAME: &str = "battery_nwc_yarp";

crate::device_params! {
    /// What `battery_nwc_yarp` reads (C++ `Battery_nwc_yarp_params.md`).
    pub struct BatteryNwcYarpParams for "battery_nwc_yarp" {
        /// Full port name opened by the batteryClient device.
        local: String = required,
        /// Full port name of the port opened on the server side, to which the batteryClient connects to.
        remote: String = required,
        /// The carrier used for the connection with the server.
        carrier: String = "tcp",
    }
}

/// C++'s `IBattery::Battery_status` from the streamed int32 (unknown codes are errors).
fn status_of(code: i32) -> BatteryStatus {
    match code {
        0 => BatteryStatus::OkStandby,
        1 => BatteryStatus::OkInCharge,
        2 => BatteryStatus::OkInUse,
        4 => BatteryStatus::Timeout,
        5 => BatteryStatus::LowWarning,
        6 => BatteryStatus::CriticalWarning,
        _ => BatteryStatus::GeneralError,
    }
}

/// The `battery_nwc_yarp` device.
#[derive(Default)]
pub struct BatteryNwcYarp {
    client: OpenPorts<BatteryData>,
}

impl BatteryNwcYarp {
    pub fn new() -> Self {
        Self::default()
    }

    /// The last data streamed, or the thrift defaults before any.
    fn last(&self) -> DevResult<BatteryData> {
        let c = self.client.get()?;
        let latest = c.latest();
        Ok(latest.as_ref().map_or(
            BatteryData {
                charge: 0.0,
                voltage: 0.0,
                current: 0.0,
                temperature: 0.0,
                status: BatteryStatus::GeneralError as i32,
            },
            |(d, _)| d.clone(),
        ))
    }
}

impl DeviceDriver for BatteryNwcYarp {
    fn parameters(&self) -> Vec<crate::params::ParamSpec> {
        BatteryNwcYarpParams::PARAMS.to_vec()
    }

    fn open(&mut self, config: &Property) -> DevResult<()> {
        let BatteryNwcYarpParams {
            local,
            remote,
            carrier,
        } = BatteryNwcYarpParams::read(config)?;
        let names = NwcNames {
            stream: format!("{local}/data:i"),
            remote_stream: format!("{remote}/data:o"),
            carrier,
            rpc: format!("{local}/rpc:o"),
            remote_rpc: format!("{remote}/rpc:i"),
        };
        self.client.open(
            NAME,
            "a running battery_nws_yarp (is the name server running?)",
            names,
            BatteryData::from_bottle,
        )
    }

    fn close(&mut self) -> DevResult<()> {
        self.client.close();
        Ok(())
    }

    crate::views!(as_battery);
}

impl IBattery for BatteryNwcYarp {
    fn get_battery_voltage(&mut self) -> DevResult<f64> {
        Ok(self.last()?.voltage)
    }
    fn get_battery_current(&mut self) -> DevResult<f64> {
        Ok(self.last()?.current)
    }
    fn get_battery_charge(&mut self) -> DevResult<f64> {
        Ok(self.last()?.charge)
    }
    fn get_battery_status(&mut self) -> DevResult<BatteryStatus> {
        Ok(status_of(self.last()?.status))
    }
    fn get_battery_temperature(&mut self) -> DevResult<f64> {
        Ok(self.last()?.temperature)
    }
    fn get_battery_info(&mut self) -> DevResult<String> {
        let c = self.client.get()?;
        let fields = c.call_returning(
            Bottle::new().with("getBatteryInfoRPC"),
            "the remote battery does not implement getBatteryInfo",
        )?;
        fields
            .first()
            .and_then(Value::as_str)
            .map(str::to_string)
            .ok_or_else(|| {
                DeviceError::failed(NAME, format!("getBatteryInfoRPC answered {fields:?}"))
            })
    }
}
