//! icub-main's raw values publisher: a device's raw firmware values (the embObj boards'
//! joint encoders, per joint its primary and secondary encoder's raw value and the primary's
//! diagnostic) served on YARP ports for diagnostics and telemetry, as ergoCub's torso
//! publishes them. The interface is `yarp_devices::raw_values::IRawValuesPublisher`.
//!
//! - [`server`]: `rawValuesPublisherServer`, the network wrapper;
//! - [`client`]: `rawValuesPublisherClient`, its client;
//! - [`remapper`]: `rawValuesPublisherRemapper`, several publishers as one;
//! - [`fake`](fake): `fakeRawValuesPublisher`;
//! - [`wire`]: the thrift messages they exchange.

pub mod client;
pub mod fake;
pub mod remapper;
pub mod server;
pub mod wire;
