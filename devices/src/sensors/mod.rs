//! The sensor families: the multiple-analog-sensors interfaces (gyroscopes,
//! accelerometers, magnetometers, orientation, six-axis F/T, temperature, skin patches)
//! and the legacy `IAnalogSensor`, with their devices under the C++ names:
//!
//! - fakes: `fakeIMU`, `fakeFTs` (six-axis F/T + temperature), `fakeAnalogSensor`;
//! - MAS wrappers: `multipleanalogsensorsserver` (`/<name>/measures:o` stream and the
//!   thrift metadata service on `/<name>/rpc:o`), `multipleanalogsensorsclient`,
//!   `multipleanalogsensorsremapper`;
//! - legacy wrappers: `analogServer`, `analogsensorclient`;
//! - `virtualAnalogServer` (torques from a port into `IVirtualAnalogSensor` devices).
//!
//! (icub-main's `skinWrapper` and `imuFilter` are in crate `icubmod`.)
//!
//! Protocol logic is pure (`wire`, `rpc`, `server::collect_*`, `analog_server::
//! handle_analog_rpc`); the devices are thin tokio layers over `yarp-net` ports.

use crate::driver::Factory;

pub mod analog_client;
pub mod analog_server;
pub mod bno055;
pub mod client;
pub mod fake_analog;
pub mod fake_fts;
pub mod fake_imu;
pub mod family;
pub mod forward;
pub mod interfaces;
pub mod params;
pub mod periodic;
pub mod remapper;
pub mod rpc;
pub mod server;
pub mod virtual_analog;
pub mod virtual_analog_server;
pub mod wire;

pub use analog_client::AnalogSensorClient;
pub use analog_server::AnalogServer;
pub use client::MultipleAnalogSensorsClient;
pub use fake_analog::FakeAnalogSensor;
pub use fake_fts::FakeFts;
pub use fake_imu::FakeImu;
pub use family::SensorFamily;
pub use interfaces::*;
pub use remapper::MultipleAnalogSensorsRemapper;
pub use server::MultipleAnalogSensorsServer;
pub use virtual_analog::{IVirtualAnalogSensor, VasStatus};
pub use virtual_analog_server::VirtualAnalogServer;
pub use wire::{SensorMetadata, SensorRpcData, SensorStreamingData};

/// Drivers of this family, by C++ name.
pub(crate) const DRIVERS: &[(&str, Factory)] = &[
    ("fakeIMU", || Box::new(FakeImu::new())),
    ("imuBosch_BNO055", || Box::new(bno055::BoschImu::new())),
    ("fakeFTs", || Box::new(FakeFts::new())),
    ("fakeAnalogSensor", || Box::new(FakeAnalogSensor::new())),
    ("analogServer", || Box::new(AnalogServer::new())),
    ("analogsensorclient", || Box::new(AnalogSensorClient::new())),
    ("virtualAnalogServer", || {
        Box::new(VirtualAnalogServer::new())
    }),
    ("multipleanalogsensorsserver", || {
        Box::new(MultipleAnalogSensorsServer::new())
    }),
    ("multipleanalogsensorsremapper", || {
        Box::new(MultipleAnalogSensorsRemapper::new())
    }),
    ("multipleanalogsensorsclient", || {
        Box::new(MultipleAnalogSensorsClient::new())
    }),
];
