//! The twelve sensor families of the multiple-analog-sensors protocol, in the order
//! their lists travel (`SensorRPCData` / `SensorStreamingData` fields 1..12).

use super::interfaces::*;
use crate::driver::DeviceDriver;

/// One family of the MAS protocol.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum SensorFamily {
    ThreeAxisGyroscopes,
    ThreeAxisLinearAccelerometers,
    ThreeAxisMagnetometers,
    OrientationSensors,
    TemperatureSensors,
    SixAxisForceTorqueSensors,
    ContactLoadCellArrays,
    EncoderArrays,
    SkinPatches,
    PositionSensors,
    LinearVelocitySensors,
    ThreeAxisAngularAccelerometers,
}

/// How many families travel in every metadata reply and measurement message.
pub const FAMILY_COUNT: usize = 12;

impl SensorFamily {
    /// Every family, in wire order.
    pub const ALL: [SensorFamily; FAMILY_COUNT] = [
        SensorFamily::ThreeAxisGyroscopes,
        SensorFamily::ThreeAxisLinearAccelerometers,
        SensorFamily::ThreeAxisMagnetometers,
        SensorFamily::OrientationSensors,
        SensorFamily::TemperatureSensors,
        SensorFamily::SixAxisForceTorqueSensors,
        SensorFamily::ContactLoadCellArrays,
        SensorFamily::EncoderArrays,
        SensorFamily::SkinPatches,
        SensorFamily::PositionSensors,
        SensorFamily::LinearVelocitySensors,
        SensorFamily::ThreeAxisAngularAccelerometers,
    ];

    /// Position in the wire order.
    pub fn index(self) -> usize {
        self as usize
    }

    /// The C++ tag (`MAS_getTagFromEnum`), e.g. `ThreeAxisGyroscopes`.
    pub fn tag(self) -> &'static str {
        match self {
            SensorFamily::ThreeAxisGyroscopes => "ThreeAxisGyroscopes",
            SensorFamily::ThreeAxisLinearAccelerometers => "ThreeAxisLinearAccelerometers",
            SensorFamily::ThreeAxisMagnetometers => "ThreeAxisMagnetometers",
            SensorFamily::OrientationSensors => "OrientationSensors",
            SensorFamily::TemperatureSensors => "TemperatureSensors",
            SensorFamily::SixAxisForceTorqueSensors => "SixAxisForceTorqueSensors",
            SensorFamily::ContactLoadCellArrays => "ContactLoadCellArrays",
            SensorFamily::EncoderArrays => "EncoderArrays",
            SensorFamily::SkinPatches => "SkinPatches",
            SensorFamily::PositionSensors => "PositionSensors",
            SensorFamily::LinearVelocitySensors => "LinearVelocitySensors",
            SensorFamily::ThreeAxisAngularAccelerometers => "ThreeAxisAngularAccelerometers",
        }
    }

    /// The fixed measurement size, `None` for variable-size families.
    pub fn measure_size(self) -> Option<usize> {
        match self {
            SensorFamily::TemperatureSensors => Some(1),
            SensorFamily::SixAxisForceTorqueSensors => Some(6),
            SensorFamily::ContactLoadCellArrays
            | SensorFamily::EncoderArrays
            | SensorFamily::SkinPatches => None,
            _ => Some(3),
        }
    }
}

/// The device's view of `family`, if it implements that interface (families this
/// crate has no trait for are never implemented).
pub fn access(
    dev: &mut dyn DeviceDriver,
    family: SensorFamily,
) -> Option<Box<dyn SensorFamilyAccess + '_>> {
    Some(match family {
        SensorFamily::ThreeAxisGyroscopes => {
            Box::new(GyroscopesAccess(&*dev.as_three_axis_gyroscopes()?))
        }
        SensorFamily::ThreeAxisLinearAccelerometers => Box::new(AccelerometersAccess(
            &*dev.as_three_axis_linear_accelerometers()?,
        )),
        SensorFamily::ThreeAxisMagnetometers => {
            Box::new(MagnetometersAccess(&*dev.as_three_axis_magnetometers()?))
        }
        SensorFamily::OrientationSensors => {
            Box::new(OrientationAccess(&*dev.as_orientation_sensors()?))
        }
        SensorFamily::TemperatureSensors => {
            Box::new(TemperatureAccess(&*dev.as_temperature_sensors()?))
        }
        SensorFamily::SixAxisForceTorqueSensors => {
            Box::new(ForceTorqueAccess(&*dev.as_six_axis_force_torque_sensors()?))
        }
        SensorFamily::SkinPatches => Box::new(SkinPatchesAccess(&*dev.as_skin_patches()?)),
        SensorFamily::EncoderArrays => Box::new(EncoderArraysAccess(&*dev.as_encoder_arrays()?)),
        _ => return None,
    })
}
