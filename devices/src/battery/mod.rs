//! Batteries: the `IBattery` interface (C++ `yarp::dev::IBattery`), `fakeBattery`, the
//! YARP network wrapper `battery_nws_yarp` and its client `battery_nwc_yarp`.

pub mod fake;
pub mod nwc;
pub mod nws;
pub mod protocol;

use crate::driver::Factory;
use crate::error::DevResult;

/// Battery status (C++ `IBattery::Battery_status`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BatteryStatus {
    OkStandby = 0,
    OkInCharge = 1,
    OkInUse = 2,
    GeneralError = 3,
    Timeout = 4,
    LowWarning = 5,
    CriticalWarning = 6,
}

/// A battery (C++ `IBattery`): volts, amperes, charge in percent (0-100), degrees Celsius.
pub trait IBattery {
    fn get_battery_voltage(&mut self) -> DevResult<f64>;
    fn get_battery_current(&mut self) -> DevResult<f64>;
    fn get_battery_charge(&mut self) -> DevResult<f64>;
    fn get_battery_status(&mut self) -> DevResult<BatteryStatus>;
    fn get_battery_temperature(&mut self) -> DevResult<f64>;
    fn get_battery_info(&mut self) -> DevResult<String>;
}

/// Drivers of this family, by C++ name.
pub(crate) const DRIVERS: &[(&str, Factory)] = &[
    ("fakeBattery", || Box::new(fake::FakeBattery::new())),
    ("battery_nws_yarp", || Box::new(nws::BatteryNwsYarp::new())),
    ("battery_nwc_yarp", || Box::new(nwc::BatteryNwcYarp::new())),
];
