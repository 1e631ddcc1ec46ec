//! icub-main's `embObj*` devices: the Ethernet iCub and ergoCub boards, over the embObj
//! protocol of crate `icub_eth`.
//!
//! | device | module | interfaces |
//! |--------|--------|------------|
//! | `embObjMotionControl` | [`motion_control`] | encoders, position, velocity, position direct, torque, current, PWM, impedance, calibration, PIDs, control/interaction modes, limits, axis info, motor encoders, amplifiers, motors (temperature) |
//! | `parametricCalibratorEth` | [`calibrator`] | `ICalibrator`, `IRemoteCalibrator` |
//! | `embObjFTsensor` | [`sensors`] | `ISixAxisForceTorqueSensors`, `IAnalogSensor` (strain) |
//! | `embObjMultipleFTsensors` | [`sensors`] | `ISixAxisForceTorqueSensors`, `ITemperatureSensors` |
//! | `embObjIMU`, `embObjInertials` | [`sensors`] | gyroscopes, accelerometers, magnetometers, orientation |
//! | `embObjMais` | [`sensors`] | `IAnalogSensor` (15 channels) |
//! | `embObjSkin` | [`sensors`] | `IAnalogSensor` (192 taxels per MTB) |
//! | `embObjPOS` | [`sensors`] | `IEncoderArrays` (C++'s hand port mapping) |
//! | `embObjBattery` | [`sensors`] | `IBattery` |
//!
//! Parameters: [`params`] (`PC104`, `ETH_BOARD`, `SERVICE`), [`mc_params`]; the host's
//! socket and the boards: [`manager`]; a device's service on its board: [`service`]; the
//! configuration its `verifyactivate` carries: [`service_config`].

pub mod calibrator;
pub mod config;
pub mod manager;
pub mod mc_params;
pub mod motion_control;
pub mod params;
pub mod sensors;
pub mod service;
pub mod service_config;
pub mod skin_spec;
pub mod tables;

pub use calibrator::ParametricCalibratorEth;
pub use motion_control::EmbObjMotionControl;
pub use sensors::{
    EmbObjBattery, EmbObjFtSensor, EmbObjImu, EmbObjMais, EmbObjMultipleFtSensors, EmbObjPos,
    EmbObjSkin,
};

use yarp_devices::driver::Factory;

/// The embObj drivers, by C++ name.
pub const DRIVERS: &[(&str, Factory)] = &[
    (
        motion_control::NAME,
        || Box::new(EmbObjMotionControl::new()),
    ),
    (
        calibrator::NAME,
        || Box::new(ParametricCalibratorEth::new()),
    ),
    (sensors::FT_SENSOR, || Box::new(EmbObjFtSensor::new())),
    (sensors::MULTIPLE_FT, || {
        Box::new(EmbObjMultipleFtSensors::new())
    }),
    (sensors::IMU, || Box::new(EmbObjImu::new(sensors::IMU))),
    (sensors::INERTIALS, || {
        Box::new(EmbObjImu::new(sensors::INERTIALS))
    }),
    (sensors::MAIS, || Box::new(EmbObjMais::new())),
    (sensors::SKIN, || Box::new(EmbObjSkin::new())),
    (sensors::POS, || Box::new(EmbObjPos::new())),
    (sensors::BATTERY, || Box::new(EmbObjBattery::new())),
];
