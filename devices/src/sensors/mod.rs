//! The multiple-analog-sensors family (gyroscopes, accelerometers, magnetometers,
//! orientation, six-axis F/T, skin patches, temperature), the legacy analog sensor, the
//! fake sensor devices and the `multipleanalogsensorsserver` / `multipleanalogsensorsclient`
//! network wrappers.

use crate::driver::Factory;

/// C++ `IThreeAxisGyroscopes`.
pub trait IThreeAxisGyroscopes {}
/// C++ `IThreeAxisLinearAccelerometers`.
pub trait IThreeAxisLinearAccelerometers {}
/// C++ `IThreeAxisMagnetometers`.
pub trait IThreeAxisMagnetometers {}
/// C++ `IOrientationSensors`.
pub trait IOrientationSensors {}
/// C++ `ISixAxisForceTorqueSensors`.
pub trait ISixAxisForceTorqueSensors {}
/// C++ `ISkinPatches`.
pub trait ISkinPatches {}
/// C++ `ITemperatureSensors`.
pub trait ITemperatureSensors {}
/// C++ `IAnalogSensor` (legacy single-vector sensors: strain F/T, skin, ...).
pub trait IAnalogSensor {}

/// Drivers of this family, by C++ name.
pub(crate) const DRIVERS: &[(&str, Factory)] = &[];
