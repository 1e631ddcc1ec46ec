//! The sensor interface traits, after C++ `MultipleAnalogSensorsInterfaces.h` and
//! `IAnalogSensor.h`.
//!
//! C++ returns `bool` and fills out-parameters; here methods return `DevResult` with the
//! value. A measurement is a [`SensorMeasurement`] (values + timestamp in seconds).

use crate::error::{DevResult, DeviceError};

/// C++ `yarp::dev::MAS_status` (same numeric values).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(i32)]
pub enum MasStatus {
    Ok = 0,
    Error = 1,
    Overflow = 2,
    Timeout = 3,
    WaitingForFirstRead = 4,
    Unknown = 5,
}

/// One measurement of one sensor: the values and the time (s) they refer to.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct SensorMeasurement {
    pub values: Vec<f64>,
    pub timestamp: f64,
}

impl SensorMeasurement {
    pub fn new(values: Vec<f64>, timestamp: f64) -> Self {
        SensorMeasurement { values, timestamp }
    }
}

/// The error for a sensor index past the end.
pub fn no_sensor(family: &'static str, index: usize, count: usize) -> DeviceError {
    DeviceError::BadParam {
        device: family.to_string(),
        param: "sens_index".into(),
        expected: "an index below the number of sensors",
        got: format!("{index} (nr of sensors: {count})"),
    }
}

/// The uniform view of one sensor family that the network wrappers use.
pub trait SensorFamilyAccess {
    fn count(&self) -> usize;
    fn status(&self, i: usize) -> MasStatus;
    fn name(&self, i: usize) -> DevResult<String>;
    /// Families without frames (skin patches) answer an empty string.
    fn frame_name(&self, i: usize) -> DevResult<String>;
    fn measure(&self, i: usize) -> DevResult<SensorMeasurement>;
}

/// The [`SensorFamilyAccess`] adapter of one MAS interface trait; `$frame` gives the
/// frame name of sensor `$i` of `$dev`.
macro_rules! family_access {
    (
        $trait:ident, $adapter:ident,
        $nr:ident, $status:ident, $name:ident, $measure:ident,
        |$dev:ident, $i:ident| $frame:expr
    ) => {
        pub(crate) struct $adapter<'a>(pub(crate) &'a dyn $trait);

        impl SensorFamilyAccess for $adapter<'_> {
            fn count(&self) -> usize {
                self.0.$nr()
            }
            fn status(&self, i: usize) -> MasStatus {
                self.0.$status(i)
            }
            fn name(&self, i: usize) -> DevResult<String> {
                self.0.$name(i)
            }
            fn frame_name(&self, $i: usize) -> DevResult<String> {
                let $dev = self.0;
                $frame
            }
            fn measure(&self, i: usize) -> DevResult<SensorMeasurement> {
                self.0.$measure(i)
            }
        }
    };
}

/// Declares one MAS interface trait with the C++ method names, plus its
/// [`SensorFamilyAccess`] adapter.
macro_rules! mas_interface {
    (
        $(#[$doc:meta])*
        $trait:ident, $adapter:ident,
        $nr:ident, $status:ident, $name:ident, $frame:ident, $measure:ident
    ) => {
        $(#[$doc])*
        pub trait $trait {
            fn $nr(&self) -> usize;
            fn $status(&self, sens_index: usize) -> MasStatus;
            fn $name(&self, sens_index: usize) -> DevResult<String>;
            fn $frame(&self, sens_index: usize) -> DevResult<String>;
            fn $measure(&self, sens_index: usize) -> DevResult<SensorMeasurement>;
        }

        family_access!($trait, $adapter, $nr, $status, $name, $measure, |dev, i| dev.$frame(i));
    };
}

mas_interface!(
    /// C++ `IThreeAxisGyroscopes`: angular velocity `[x y z]` in deg/s.
    IThreeAxisGyroscopes,
    GyroscopesAccess,
    get_nr_of_three_axis_gyroscopes,
    get_three_axis_gyroscope_status,
    get_three_axis_gyroscope_name,
    get_three_axis_gyroscope_frame_name,
    get_three_axis_gyroscope_measure
);

mas_interface!(
    /// C++ `IThreeAxisLinearAccelerometers`: proper acceleration `[x y z]` in m/s^2.
    IThreeAxisLinearAccelerometers,
    AccelerometersAccess,
    get_nr_of_three_axis_linear_accelerometers,
    get_three_axis_linear_accelerometer_status,
    get_three_axis_linear_accelerometer_name,
    get_three_axis_linear_accelerometer_frame_name,
    get_three_axis_linear_accelerometer_measure
);

mas_interface!(
    /// C++ `IThreeAxisMagnetometers`: magnetic field `[x y z]` in tesla.
    IThreeAxisMagnetometers,
    MagnetometersAccess,
    get_nr_of_three_axis_magnetometers,
    get_three_axis_magnetometer_status,
    get_three_axis_magnetometer_name,
    get_three_axis_magnetometer_frame_name,
    get_three_axis_magnetometer_measure
);

mas_interface!(
    /// C++ `IOrientationSensors`: orientation as roll-pitch-yaw `[r p y]` in degrees
    /// (`getOrientationSensorMeasureAsRollPitchYaw`).
    IOrientationSensors,
    OrientationAccess,
    get_nr_of_orientation_sensors,
    get_orientation_sensor_status,
    get_orientation_sensor_name,
    get_orientation_sensor_frame_name,
    get_orientation_sensor_measure_as_roll_pitch_yaw
);

mas_interface!(
    /// C++ `ISixAxisForceTorqueSensors`: wrench `[fx fy fz tx ty tz]` in N and Nm.
    ISixAxisForceTorqueSensors,
    ForceTorqueAccess,
    get_nr_of_six_axis_force_torque_sensors,
    get_six_axis_force_torque_sensor_status,
    get_six_axis_force_torque_sensor_name,
    get_six_axis_force_torque_sensor_frame_name,
    get_six_axis_force_torque_sensor_measure
);

mas_interface!(
    /// C++ `ITemperatureSensors`: one value in degrees Celsius (the vector form of
    /// `getTemperatureSensorMeasure`; [`temperature_value`] gives the scalar form).
    ITemperatureSensors,
    TemperatureAccess,
    get_nr_of_temperature_sensors,
    get_temperature_sensor_status,
    get_temperature_sensor_name,
    get_temperature_sensor_frame_name,
    get_temperature_sensor_measure
);

/// The scalar form of C++ `getTemperatureSensorMeasure(size_t, double&, double&)`.
pub fn temperature_value(dev: &dyn ITemperatureSensors, i: usize) -> DevResult<(f64, f64)> {
    let m = dev.get_temperature_sensor_measure(i)?;
    let v = m.values.first().copied().ok_or(DeviceError::WrongSize {
        expected: 1,
        got: 0,
    })?;
    Ok((v, m.timestamp))
}

/// Declares one MAS interface trait of a family without frames (C++ gives these a size
/// instead), plus its [`SensorFamilyAccess`] adapter, whose frame names are empty.
macro_rules! mas_interface_without_frames {
    (
        $(#[$doc:meta])*
        $trait:ident, $adapter:ident,
        $nr:ident, $status:ident, $name:ident, $size:ident, $measure:ident
    ) => {
        $(#[$doc])*
        pub trait $trait {
            fn $nr(&self) -> usize;
            fn $status(&self, sens_index: usize) -> MasStatus;
            fn $name(&self, sens_index: usize) -> DevResult<String>;
            fn $size(&self, sens_index: usize) -> usize;
            fn $measure(&self, sens_index: usize) -> DevResult<SensorMeasurement>;
        }

        // C++ fills "" for families without frames
        family_access!($trait, $adapter, $nr, $status, $name, $measure, |_dev, _i| Ok(
            String::new()
        ));
    };
}

mas_interface_without_frames!(
    /// C++ `ISkinPatches`: a patch of taxels, of variable size, without a frame.
    ISkinPatches,
    SkinPatchesAccess,
    get_nr_of_skin_patches,
    get_skin_patch_status,
    get_skin_patch_name,
    get_skin_patch_size,
    get_skin_patch_measure
);

mas_interface_without_frames!(
    /// C++ `IEncoderArrays`: arrays of joint-like positions without a frame (the hands'
    /// position sensors of `embObjPOS`: one angle each, in degrees).
    IEncoderArrays,
    EncoderArraysAccess,
    get_nr_of_encoder_arrays,
    get_encoder_array_status,
    get_encoder_array_name,
    get_encoder_array_size,
    get_encoder_array_measure
);

/// C++ `IAnalogSensor` status codes (`AS_OK` ...).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(i32)]
pub enum AnalogStatus {
    Ok = 0,
    Error = 1,
    Overflow = 2,
    Timeout = 3,
}

/// C++ `IAnalogSensor` (legacy single-vector sensors: strain F/T, MAIS, MTB ...).
pub trait IAnalogSensor {
    /// Fills `out` with the latest reading (resized to the channel count).
    fn read(&mut self, out: &mut Vec<f64>) -> AnalogStatus;
    fn get_state(&mut self, ch: usize) -> AnalogStatus;
    fn get_channels(&mut self) -> usize;
    fn calibrate_sensor(&mut self) -> DevResult<()>;
    /// The variants below default to [`IAnalogSensor::calibrate_sensor`], for sensors
    /// that calibrate only as a whole (or not at all).
    fn calibrate_sensor_with(&mut self, _values: &[f64]) -> DevResult<()> {
        self.calibrate_sensor()
    }
    fn calibrate_channel(&mut self, _ch: usize) -> DevResult<()> {
        self.calibrate_sensor()
    }
    fn calibrate_channel_with(&mut self, _ch: usize, _value: f64) -> DevResult<()> {
        self.calibrate_sensor()
    }
}
