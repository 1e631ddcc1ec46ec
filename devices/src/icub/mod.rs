//! The iCub CAN devices of icub-main, over the driver cores of crate `icub_can`:
//!
//! | device | module | interfaces |
//! |--------|--------|------------|
//! | `canmotioncontrol` | [`motion_control`] | encoders, position, velocity, torque, impedance, calibration, PIDs, control/interaction modes, limits, axis info, motor encoders, amplifiers, PWM |
//! | `canBusAnalogSensor`, `canBusFtSensor` | [`analog`] | `IAnalogSensor`, `ISixAxisForceTorqueSensors` (strain) |
//! | `canBusSkin` | [`skin`] | `IAnalogSensor`, `ISkinPatches` |
//! | `canBusInertialMTB` | [`inertial`] | `IAnalogSensor`, accelerometers, gyroscopes |
//! | `canBusVirtualAnalogSensor` | [`virtual_analog`] | `IVirtualAnalogSensor` (joint torques sent as strain messages) |
//! | `xsensmtx` | [`xsensmtx`] | the head's Xsens MTx on a serial port: gyroscope, accelerometer, magnetometer, orientation, `IAnalogSensor` (C++ `IGenericSensor`, 12 channels) |
//! | `parametricCalibrator` | [`calibrator`] | `ICalibrator`, `IRemoteCalibrator` |
//! | `cartesiancontrollerserver` | [`crate::cartesian`] | `IMultipleWrapper` (pose on `state:o`) |
//!
//! Each device reads the parameters of the robots-configuration XML files unchanged; the
//! bus is chosen by `canBackend` (e.g. `udp://127.0.0.1:20000+n`, one port per
//! `CanDeviceNum`), by the `YARP_ICUB_CAN_BACKEND` environment variable, or by
//! `physDevice socketcan` (see [`common::open_bus`]). Board faults are errors or
//! statuses: a silent board fails a call within its timeout, never hangs it.

pub mod analog;
pub mod calibrator;
pub mod common;
pub mod inertial;
pub mod motion_control;
pub mod registry;
pub mod skin;
pub mod virtual_analog;
pub mod xsensmtx;

pub use analog::CanBusAnalogSensor;
pub use calibrator::ParametricCalibrator;
pub use inertial::CanBusInertialMtb;
pub use motion_control::CanMotionControl;
pub use skin::CanBusSkin;
pub use virtual_analog::CanBusVirtualAnalogSensor;
pub use xsensmtx::XsensMtx;

use crate::driver::Factory;

/// The iCub drivers, by C++ name.
pub(crate) const DRIVERS: &[(&str, Factory)] = &[
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
    (xsensmtx::NAME, || Box::new(XsensMtx::new())),
    (crate::cartesian::NAME, || {
        Box::new(crate::cartesian::CartesianControllerServer::new())
    }),
];
