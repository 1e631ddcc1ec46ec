//! `icubmod`: the iCub devices of icub-main (`src/libraries/icubmod`), as drivers of the
//! YARP device framework (crate `yarp-devices`). The CAN devices run over the driver cores
//! of crate `icub_can` (the Cartesian controller is crate `icub_cartesian`'s):
//!
//! | device (icub-main directory) | module | interfaces |
//! |------------------------------|--------|------------|
//! | `canmotioncontrol` (`canBusMotionControl`) | [`motion_control`] | encoders, position, velocity, torque, impedance, calibration, PIDs, control/interaction modes, limits, axis info, motor encoders, amplifiers, PWM |
//! | `canBusAnalogSensor`, `canBusFtSensor` | [`analog`] | `IAnalogSensor`, `ISixAxisForceTorqueSensors` (strain) |
//! | `canBusSkin` | [`skin`] | `IAnalogSensor`, `ISkinPatches` |
//! | `canBusInertialMTB` | [`inertial`] | `IAnalogSensor`, accelerometers, gyroscopes |
//! | `canBusVirtualAnalogSensor` | [`virtual_analog`] | `IVirtualAnalogSensor` (joint torques sent as strain messages) |
//! | `xsensmtx`, `xsensmt` | [`xsens`] | Xsens IMUs on a serial port (the iCub head's MTx; an MTi such as the ergoCub waist's): gyroscope, accelerometer, magnetometer, orientation, `IAnalogSensor` (C++ `IGenericSensor`, 12 channels) |
//! | `imuFilter` | [`imu_filter`] | an IMU with its gyro bias removed (`IMultipleWrapper` + the IMU interfaces) |
//! | `skinWrapper` | [`skin_wrapper`] | an `analogServer` per skin part |
//! | `parametricCalibrator` | [`calibrator`] | `ICalibrator`, `IRemoteCalibrator` |
//! //!
//! Programs make them known with [`register`] before opening devices:
//! `yarp_devices::Registry::install(icubmod::register)`.
//!
//! Each device reads the parameters of the robots-configuration XML files unchanged; the
//! bus is chosen by `canBackend` (e.g. `udp://127.0.0.1:20000+n`, one port per
//! `CanDeviceNum`), by the `YARP_ICUB_CAN_BACKEND` environment variable, or by
//! `physDevice socketcan` (see [`common::CanBusParams`]). Board faults are errors or
//! statuses: a silent board fails a call within its timeout, never hangs it.
#![forbid(unsafe_code)]

pub mod analog;
pub mod boards;
pub mod calibrator;
pub mod common;
pub mod eth;
pub mod imu_filter;
pub mod inertial;
pub mod motion_control;
pub mod presence;
pub mod raw_values;
pub mod skin;
pub mod skin_wrapper;
pub mod virtual_analog;
pub mod xsens;

pub use analog::CanBusAnalogSensor;
pub use calibrator::ParametricCalibrator;
pub use imu_filter::ImuFilter;
pub use inertial::CanBusInertialMtb;
pub use motion_control::CanMotionControl;
pub use skin::CanBusSkin;
pub use skin_wrapper::SkinWrapper;
pub use virtual_analog::CanBusVirtualAnalogSensor;
pub use xsens::XsensImu;

use yarp_devices::{Factory, Registry};

/// The name this crate's drivers are listed under (`yarpdev --list`).
pub const PROVIDER: &str = "icubmod";

/// The drivers of this crate, by C++ name.
pub const DRIVERS: &[(&str, Factory)] = &[
    (motion_control::NAME, || Box::new(CanMotionControl::new())),
    ("canBusAnalogSensor", || {
        Box::new(CanBusAnalogSensor::new("canBusAnalogSensor"))
    }),
    ("canBusFtSensor", || {
        Box::new(CanBusAnalogSensor::new("canBusFtSensor"))
    }),
    (skin::NAME, || Box::new(CanBusSkin::new())),
    (inertial::NAME, || Box::new(CanBusInertialMtb::new())),
    (virtual_analog::NAME, || {
        Box::new(CanBusVirtualAnalogSensor::new())
    }),
    (calibrator::NAME, || Box::new(ParametricCalibrator::new())),
    (xsens::MTX_NAME, || Box::new(XsensImu::mtx())),
    (xsens::MT_NAME, || Box::new(XsensImu::mt())),
    ("imuFilter", || Box::new(ImuFilter::new())),
    (raw_values::server::NAME, || {
        Box::new(raw_values::server::RawValuesPublisherServer::new())
    }),
    (raw_values::client::NAME, || {
        Box::new(raw_values::client::RawValuesPublisherClient::new())
    }),
    (raw_values::remapper::NAME, || {
        Box::new(raw_values::remapper::RawValuesPublisherRemapper::new())
    }),
    (raw_values::fake::NAME, || {
        Box::new(raw_values::fake::FakeRawValuesPublisher::new())
    }),
    ("skinWrapper", || Box::new(SkinWrapper::new())),
];

/// Adds the iCub drivers to `registry` (`Registry::install(icubmod::register)`).
pub fn register(registry: &mut Registry) {
    registry.add(PROVIDER, DRIVERS);
    registry.add(PROVIDER, eth::DRIVERS);
}
