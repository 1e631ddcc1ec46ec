//! Devices that serve every MAS family from one place (the network client, the
//! remapper) implement [`FamilySource`]; `impl_mas_interfaces!` then gives them all
//! the per-family interface traits, and `mas_views!()` the matching `as_*` methods.

use super::family::SensorFamily;
use super::interfaces::{MasStatus, SensorMeasurement};
use crate::error::DevResult;

/// Per-family access to sensors, the shape every MAS interface shares.
pub trait FamilySource {
    fn family_count(&self, family: SensorFamily) -> usize;
    fn family_status(&self, family: SensorFamily, i: usize) -> MasStatus;
    fn family_name(&self, family: SensorFamily, i: usize) -> DevResult<String>;
    fn family_frame_name(&self, family: SensorFamily, i: usize) -> DevResult<String>;
    fn family_measure(&self, family: SensorFamily, i: usize) -> DevResult<SensorMeasurement>;
    /// The values sensor `i` of a family without frames gives (skin patches, encoder
    /// arrays): by default those of its latest measurement, 0 before the first.
    fn family_size(&self, family: SensorFamily, i: usize) -> usize {
        self.family_measure(family, i).map_or(0, |m| m.values.len())
    }
}

/// Implements the MAS interface traits of the families named (`SensorFamily` variants)
/// for `$ty: FamilySource`:
///
/// ```ignore
/// yarp_devices::mas_interfaces!(EmbObjImu: ThreeAxisGyroscopes, OrientationSensors);
/// ```
#[macro_export]
macro_rules! mas_interfaces {
    ($ty:ty: $($family:ident),+ $(,)?) => {
        $($crate::mas_interfaces!(@one $ty, $family);)+
    };
    (@one $ty:ty, ThreeAxisGyroscopes) => {
        $crate::mas_interfaces!(@framed $ty, IThreeAxisGyroscopes, ThreeAxisGyroscopes, get_nr_of_three_axis_gyroscopes, get_three_axis_gyroscope_status, get_three_axis_gyroscope_name, get_three_axis_gyroscope_frame_name, get_three_axis_gyroscope_measure);
    };
    (@one $ty:ty, ThreeAxisLinearAccelerometers) => {
        $crate::mas_interfaces!(@framed $ty, IThreeAxisLinearAccelerometers, ThreeAxisLinearAccelerometers, get_nr_of_three_axis_linear_accelerometers, get_three_axis_linear_accelerometer_status, get_three_axis_linear_accelerometer_name, get_three_axis_linear_accelerometer_frame_name, get_three_axis_linear_accelerometer_measure);
    };
    (@one $ty:ty, ThreeAxisMagnetometers) => {
        $crate::mas_interfaces!(@framed $ty, IThreeAxisMagnetometers, ThreeAxisMagnetometers, get_nr_of_three_axis_magnetometers, get_three_axis_magnetometer_status, get_three_axis_magnetometer_name, get_three_axis_magnetometer_frame_name, get_three_axis_magnetometer_measure);
    };
    (@one $ty:ty, OrientationSensors) => {
        $crate::mas_interfaces!(@framed $ty, IOrientationSensors, OrientationSensors, get_nr_of_orientation_sensors, get_orientation_sensor_status, get_orientation_sensor_name, get_orientation_sensor_frame_name, get_orientation_sensor_measure_as_roll_pitch_yaw);
    };
    (@one $ty:ty, SixAxisForceTorqueSensors) => {
        $crate::mas_interfaces!(@framed $ty, ISixAxisForceTorqueSensors, SixAxisForceTorqueSensors, get_nr_of_six_axis_force_torque_sensors, get_six_axis_force_torque_sensor_status, get_six_axis_force_torque_sensor_name, get_six_axis_force_torque_sensor_frame_name, get_six_axis_force_torque_sensor_measure);
    };
    (@one $ty:ty, TemperatureSensors) => {
        $crate::mas_interfaces!(@framed $ty, ITemperatureSensors, TemperatureSensors, get_nr_of_temperature_sensors, get_temperature_sensor_status, get_temperature_sensor_name, get_temperature_sensor_frame_name, get_temperature_sensor_measure);
    };
    (@one $ty:ty, SkinPatches) => {
        $crate::mas_interfaces!(@unframed $ty, ISkinPatches, SkinPatches, get_nr_of_skin_patches, get_skin_patch_status, get_skin_patch_name, get_skin_patch_size, get_skin_patch_measure);
    };
    (@one $ty:ty, EncoderArrays) => {
        $crate::mas_interfaces!(@unframed $ty, IEncoderArrays, EncoderArrays, get_nr_of_encoder_arrays, get_encoder_array_status, get_encoder_array_name, get_encoder_array_size, get_encoder_array_measure);
    };
    (@framed $ty:ty, $trait:ident, $family:ident,
     $nr:ident, $status:ident, $name:ident, $frame:ident, $measure:ident) => {
        impl $crate::sensors::interfaces::$trait for $ty {
            $crate::mas_interfaces!(@common $family, $nr, $status, $name, $measure);
            fn $frame(&self, i: usize) -> $crate::error::DevResult<String> {
                $crate::sensors::forward::FamilySource::family_frame_name(
                    self,
                    $crate::sensors::SensorFamily::$family,
                    i,
                )
            }
        }
    };
    (@unframed $ty:ty, $trait:ident, $family:ident,
     $nr:ident, $status:ident, $name:ident, $size:ident, $measure:ident) => {
        impl $crate::sensors::interfaces::$trait for $ty {
            $crate::mas_interfaces!(@common $family, $nr, $status, $name, $measure);
            fn $size(&self, i: usize) -> usize {
                $crate::sensors::forward::FamilySource::family_size(
                    self,
                    $crate::sensors::SensorFamily::$family,
                    i,
                )
            }
        }
    };
    // what every family's trait has: count, status, name, measure
    (@common $family:ident, $nr:ident, $status:ident, $name:ident, $measure:ident) => {
        fn $nr(&self) -> usize {
            $crate::sensors::forward::FamilySource::family_count(
                self,
                $crate::sensors::SensorFamily::$family,
            )
        }
        fn $status(&self, i: usize) -> $crate::sensors::interfaces::MasStatus {
            $crate::sensors::forward::FamilySource::family_status(
                self,
                $crate::sensors::SensorFamily::$family,
                i,
            )
        }
        fn $name(&self, i: usize) -> $crate::error::DevResult<String> {
            $crate::sensors::forward::FamilySource::family_name(
                self,
                $crate::sensors::SensorFamily::$family,
                i,
            )
        }
        fn $measure(
            &self,
            i: usize,
        ) -> $crate::error::DevResult<$crate::sensors::interfaces::SensorMeasurement> {
            $crate::sensors::forward::FamilySource::family_measure(
                self,
                $crate::sensors::SensorFamily::$family,
                i,
            )
        }
    };
}

/// Implements every MAS interface trait for `$ty: FamilySource`.
macro_rules! impl_mas_interfaces {
    ($ty:ty) => {
        $crate::mas_interfaces!($ty: ThreeAxisGyroscopes, ThreeAxisLinearAccelerometers,
            ThreeAxisMagnetometers, OrientationSensors, SixAxisForceTorqueSensors,
            TemperatureSensors, SkinPatches, EncoderArrays);
    };
}

/// The `as_*` methods of `DeviceDriver` for a type given `impl_mas_interfaces!`.
macro_rules! mas_views {
    () => {
        crate::views!(
            as_three_axis_gyroscopes,
            as_three_axis_linear_accelerometers,
            as_three_axis_magnetometers,
            as_orientation_sensors,
            as_six_axis_force_torque_sensors,
            as_temperature_sensors,
            as_skin_patches,
            as_encoder_arrays
        );
    };
}

pub(crate) use impl_mas_interfaces;
pub(crate) use mas_views;
