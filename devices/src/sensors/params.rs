//! Parameter and clock helpers shared by the sensor devices.

use crate::driver::Params;
use crate::error::{DevResult, DeviceError};

/// Wall-clock time in seconds (C++ `yarp::os::Time::now`).
pub use yarp_proto::stamp::now;

/// A boolean parameter as C++ `Value::asBool` reads it (`true`/`false`, 0/1); a key
/// given without a value (`--constantValue`) counts as true.
pub fn bool_param(p: &Params<'_>, key: &str) -> DevResult<Option<bool>> {
    p.boolean(key)
}

/// A period in milliseconds greater than zero (C++ `int`, floats accepted).
pub fn positive_ms(ms: &f64) -> Result<(), &'static str> {
    match *ms > 0.0 && ms.is_finite() {
        true => Ok(()),
        false => Err("a positive period in ms"),
    }
}

/// A period given in milliseconds (C++ `int`, floats accepted), as seconds.
pub fn period_ms(p: &Params<'_>, key: &str) -> DevResult<Option<f64>> {
    match p.float(key)? {
        None => Ok(None),
        Some(ms) if ms > 0.0 && ms.is_finite() => Ok(Some(ms / 1000.0)),
        Some(ms) => Err(DeviceError::BadParam {
            device: p.device.to_string(),
            param: key.to_string(),
            expected: "a positive period in ms",
            got: ms.to_string(),
        }),
    }
}
