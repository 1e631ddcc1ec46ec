//! `fakeBattery` (C++ `FakeBattery`): a battery that drains while current flows out.
//!
//! Parameters as in C++ 3.12: `period` (0.02 s), `charge` (50 %), `voltage` (30 V),
//! `current` (3 A), `temperature` (20 C), `info` (`Fake battery system v2.0`). Every
//! period the charge moves by 0.001 % against the current's sign; the status follows
//! from current and charge (C++ `updateStatus`). C++'s `rpc_port_name` control port
//! (a thrift service to set the values) is not served here.

use super::{BatteryStatus, IBattery};
use crate::driver::DeviceDriver;
use crate::error::{DevResult, DeviceError};
use std::time::Instant;
use yarp_proto::Property;

crate::device_params! {
    /// What `fakeBattery` reads (C++ `FakeBattery_params.md`; its rpc port is not opened
    /// here, where a battery_nws_yarp serves the device).
    pub struct FakeBatteryParams for "fakeBattery" {
        /// thread period
        period: f64 = 0.02; "s"; check crate::params::positive,
        /// Initial charge
        charge: f64 = 50.0; "%",
        /// Initial voltage
        voltage: f64 = 30.0; "V",
        /// Initial current
        current: f64 = 3.0; "A",
        /// Initial temperature
        temperature: f64 = 20.0; "C",
        /// Initial battery information
        info: String = "Fake battery system v2.0",
        /// Full rpc port name (accepted, not opened)
        rpc_port_name: String = "/fakeBattery/rpc",
    }
}

pub struct FakeBattery {
    period: f64,
    charge: f64,
    voltage: f64,
    current: f64,
    temperature: f64,
    info: String,
    opened: Option<Instant>,
}

impl Default for FakeBattery {
    fn default() -> Self {
        Self::new()
    }
}

/// C++ `updateStatus`.
pub fn status_of(current: f64, charge: f64) -> BatteryStatus {
    if current > 0.1 {
        if charge > 15.0 {
            BatteryStatus::OkInUse
        } else if charge > 5.0 {
            BatteryStatus::LowWarning
        } else {
            BatteryStatus::CriticalWarning
        }
    } else if current > -0.1 {
        BatteryStatus::OkStandby
    } else {
        BatteryStatus::OkInCharge
    }
}

impl FakeBattery {
    pub fn new() -> FakeBattery {
        FakeBattery {
            period: 0.02,
            charge: 50.0,
            voltage: 30.0,
            current: 3.0,
            temperature: 20.0,
            info: "Fake battery system v2.0".into(),
            opened: None,
        }
    }

    /// The charge now: the initial one moved by 0.001 % per elapsed period.
    fn charge_now(&self) -> DevResult<f64> {
        let opened = self.opened.ok_or(DeviceError::NotOpen)?;
        let periods = (opened.elapsed().as_secs_f64() / self.period).floor();
        let step = if self.current > 0.1 {
            -0.001
        } else if self.current < -0.1 {
            0.001
        } else {
            0.0
        };
        Ok((self.charge + step * periods).clamp(0.0, 100.0))
    }
}

impl DeviceDriver for FakeBattery {
    fn parameters(&self) -> Vec<crate::params::ParamSpec> {
        FakeBatteryParams::PARAMS.to_vec()
    }

    fn open(&mut self, config: &Property) -> DevResult<()> {
        let p = FakeBatteryParams::read(config)?;
        self.period = p.period;
        self.charge = p.charge.clamp(0.0, 100.0);
        self.voltage = p.voltage;
        self.current = p.current;
        self.temperature = p.temperature;
        self.info = p.info;
        self.opened = Some(Instant::now());
        Ok(())
    }

    fn close(&mut self) -> DevResult<()> {
        self.opened = None;
        Ok(())
    }

    crate::views!(as_battery);
}

impl IBattery for FakeBattery {
    fn get_battery_voltage(&mut self) -> DevResult<f64> {
        Ok(self.voltage)
    }
    fn get_battery_current(&mut self) -> DevResult<f64> {
        Ok(self.current)
    }
    fn get_battery_charge(&mut self) -> DevResult<f64> {
        self.charge_now()
    }
    fn get_battery_status(&mut self) -> DevResult<BatteryStatus> {
        Ok(status_of(self.current, self.charge_now()?))
    }
    fn get_battery_temperature(&mut self) -> DevResult<f64> {
        Ok(self.temperature)
    }
    fn get_battery_info(&mut self) -> DevResult<String> {
        Ok(self.info.clone())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn values_and_status() {
        let mut b = FakeBattery::new();
        b.open(&Property::from_config_text("voltage 24.5\ncharge 10\ninfo \"pack A\"").unwrap())
            .unwrap();
        assert_eq!(b.get_battery_voltage().unwrap(), 24.5);
        assert_eq!(b.get_battery_info().unwrap(), "pack A");
        let c = b.get_battery_charge().unwrap();
        assert!(c <= 10.0 && c > 9.9, "{c}");
        assert_eq!(b.get_battery_status().unwrap(), BatteryStatus::LowWarning);
        assert_eq!(status_of(-1.0, 50.0), BatteryStatus::OkInCharge);
        assert_eq!(status_of(0.0, 50.0), BatteryStatus::OkStandby);
        assert_eq!(status_of(1.0, 3.0), BatteryStatus::CriticalWarning);
    }
}
