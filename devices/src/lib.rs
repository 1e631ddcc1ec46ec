//! YARP device layer: the driver framework (`DeviceDriver`, `Registry`, `PolyDriver`),
//! the motor-control interface traits, the `fakeMotionControl` device and the
//! `controlBoard_nws_yarp` RPC server, wire-compatible with C++ YARP 3.12.

pub mod bundler;
pub mod cartesian;
pub mod controlboard;
pub mod driver;
pub mod error;
pub mod fake_motion_control;
pub mod framegrabber;
pub mod icub;
pub mod interfaces;
pub mod remapper;
pub mod remote_controlboard;
pub mod robotinterface;
pub mod runtime;
pub mod sensors;
pub mod vocabs;

pub use driver::{
    shared, DeviceDriver, ICalibrator, IMultipleWrapper, IWrapper, Params, PolyDriver, Registry,
    SharedDevice,
};
pub use error::{DevResult, DeviceError};
pub use fake_motion_control::FakeMotionControl;
pub use interfaces::*;
