//! robotology/whole-body-estimators' devices, as its `wholeBodyDynamicsDevice` plugin
//! serves them to `yarprobotinterface`:
//!
//! - [`wholebodydynamics`]: joint torques and external wrenches estimated from the
//!   robot's F/T sensors, IMU and encoders on its URDF ([`robot_dynamics`]), sent to the
//!   motor boards (`IVirtualAnalogSensor`) and on ports, with gravity compensation
//!   (`setImpedanceOffset`) for compliant joints.
//!
//! `yarp_devices::Registry::install(whole_body_estimators::register)` adds them to a
//! program's devices.
#![forbid(unsafe_code)]

pub mod wholebodydynamics;

use yarp_devices::{Factory, Registry};

/// The name this crate's drivers are listed under (`yarpdev --list`).
pub const PROVIDER: &str = "whole-body-estimators";

const DRIVERS: &[(&str, Factory)] = &[(wholebodydynamics::NAME, || {
    Box::new(wholebodydynamics::WholeBodyDynamics::new())
})];

/// Adds the drivers to `registry` (`Registry::install(whole_body_estimators::register)`).
pub fn register(registry: &mut Registry) {
    registry.add(PROVIDER, DRIVERS);
}
