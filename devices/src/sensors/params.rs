//! Parameter and clock helpers shared by the sensor devices.

/// Wall-clock time in seconds (C++ `yarp::os::Time::now`).
pub use yarp_proto::stamp::now;

/// A period in milliseconds greater than zero (C++ `int`, floats accepted).
pub fn positive_ms(ms: &f64) -> Result<(), &'static str> {
    match *ms > 0.0 && ms.is_finite() {
        true => Ok(()),
        false => Err("a positive period in ms"),
    }
}
