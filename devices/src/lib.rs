//! The YARP device framework, wire-compatible with C++ YARP 3.12: the driver traits and
//! factory (`DeviceDriver`, `Registry`, `PolyDriver`), the device interfaces, the fake
//! devices, the network wrappers and clients (NWS/NWC, `analogServer`, ...), the
//! remappers and the robot interface (`yarprobotinterface`'s XML reader and runner).
//!
//! It names no robot's drivers: those live in crates of their own (the iCub's in
//! `icubmod`), which add themselves to the [`Registry`] with their `register` function.
#![forbid(unsafe_code)]

pub mod battery;
pub mod bundler;
pub mod cartesian_control;
pub mod controlboard;
pub mod device_thread;
pub mod driver;
pub mod error;
pub mod fake_motion_control;
pub mod framegrabber;
pub mod frames;
pub mod gaze_control;
pub mod interfaces;
pub mod kind;
pub mod navigation;
pub mod nwc_ports;
pub mod params;
pub mod rangefinder;
pub mod raw_values;
pub mod remapper;
pub mod remote_controlboard;
pub mod rgbd;
pub mod robotinterface;
pub mod runtime;
pub mod sensors;
pub mod test_motor;
pub mod thrift;
pub mod vocabs;
pub mod wrapper_ports;

pub use driver::{
    shared, DeviceDriver, ICalibrator, IMultipleWrapper, IWrapper, Params, PolyDriver, Registry,
    SharedDevice,
};
pub use driver::{DriverEntry, Factory};
pub use error::{DevResult, DeviceError};
pub use fake_motion_control::FakeMotionControl;
pub use interfaces::*;

/// The name this crate's drivers are listed under.
pub const PROVIDER: &str = "yarp-devices";

/// Adds this crate's drivers (fakes, wrappers, clients, remappers) to `registry`; the
/// process-wide table does this itself when first used.
pub fn register(registry: &mut Registry) {
    for family in [
        fake_motion_control::DRIVERS,
        test_motor::DRIVERS,
        controlboard::DRIVERS,
        remote_controlboard::DRIVERS,
        remapper::DRIVERS,
        framegrabber::DRIVERS,
        sensors::DRIVERS,
        bundler::DRIVERS,
        rangefinder::DRIVERS,
        rgbd::DRIVERS,
        battery::DRIVERS,
        navigation::DRIVERS,
    ] {
        registry.add(PROVIDER, family);
    }
}
