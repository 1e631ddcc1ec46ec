//! C++ `yarp::dev::IVirtualAnalogSensor` (`yarp/dev/IVirtualAnalogSensor.h`): a sensor
//! whose values are computed elsewhere (e.g. joint torques estimated by
//! wholeBodyDynamics) and pushed *into* the device, which forwards them to the robot —
//! `canBusVirtualAnalogSensor` sends them on CAN as a strain board would.
//!
//! C++ returns `bool` and takes a mutable `Vector`; here the update methods take the
//! values by slice and return `DevResult`.

use crate::error::DevResult;

/// C++ `yarp::dev::VAS_status` (same numeric values).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(i32)]
pub enum VasStatus {
    Ok = 0,
    /// Generic error.
    Error = 1,
    /// Overflow (the last value was out of range and was clamped).
    Overflow = 2,
    Timeout = 3,
}

/// C++ `IVirtualAnalogSensor`.
pub trait IVirtualAnalogSensor {
    /// `getVirtualAnalogSensorStatus(ch)`.
    fn get_virtual_analog_sensor_status(&mut self, ch: usize) -> VasStatus;
    /// `getVirtualAnalogSensorChannels()`: 0 when the device is not usable.
    fn get_virtual_analog_sensor_channels(&mut self) -> usize;
    /// `updateVirtualAnalogSensorMeasure(Vector&)`: sets every channel at once.
    fn update_virtual_analog_sensor_measure(&mut self, measure: &[f64]) -> DevResult<()>;
    /// `updateVirtualAnalogSensorMeasure(int ch, double&)`: sets one channel.
    fn update_virtual_analog_sensor_channel(&mut self, ch: usize, measure: f64) -> DevResult<()>;
}
