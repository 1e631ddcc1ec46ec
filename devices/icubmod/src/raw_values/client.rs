//! `rawValuesPublisherClient` (icub-main 2.11): an `IRawValuesPublisher` read from a
//! `rawValuesPublisherServer`.
//!
//! Parameters as C++: `remote` (the server's `name`), `local` (the ports' prefix), `carrier`
//! (default `tcp`), `externalConnection` (default false). Ports: `<local>/rawdata:i` reading
//! `<remote>/rawdata:o`, `<local>/rpc:i` calling `<remote>/rpc:o`. The raw values are the
//! last message streamed (none before the first); the metadata is asked of the server at
//! each call, as C++ does. C++ leaves `getKeys` unimplemented (and `getNumberOfKeys` at 1):
//! here both come from the server's metadata.

use super::wire::{decode_data_map, decode_metadata_reply, encode_get_metadata, GET_METADATA};
use std::collections::BTreeMap;
use yarp_devices::driver::DeviceDriver;
use yarp_devices::error::{DevResult, DeviceError};
use yarp_devices::nwc_ports::{NwcNames, NwcPorts, OpenPorts};
use yarp_devices::raw_values::{IRawValuesPublisher, RawValuesKeyMetadata};
use yarp_proto::Property;

pub const NAME: &str = "rawValuesPublisherClient";

/// `externalConnection` must stay off: this client always connects itself.
fn connects_itself(external: &bool) -> Result<(), &'static str> {
    match external {
        false => Ok(()),
        true => {
            Err("false (this client connects its ports itself; C++'s cannot call the server then)")
        }
    }
}

yarp_devices::device_params! {
    /// What `rawValuesPublisherClient` reads (icub-main's `rawValuesPublisherClient_params.md`).
    pub struct RawValuesPublisherClientParams for "rawValuesPublisherClient" {
        /// Prefix of the port names opened by the server
        remote: String = required,
        /// Prefix of the port names opened by this device
        local: String = required,
        /// Whether the connections are left to someone else
        "externalConnection" external_connection: bool = false; check connects_itself,
        /// Carrier of the connections
        carrier: String = "tcp",
    }
}

type Map = BTreeMap<String, Vec<i32>>;

/// The `rawValuesPublisherClient` device.
#[derive(Default)]
pub struct RawValuesPublisherClient {
    client: OpenPorts<Map>,
}

impl RawValuesPublisherClient {
    pub fn new() -> Self {
        Self::default()
    }

    fn client(&self) -> DevResult<&NwcPorts<Map>> {
        self.client.get()
    }
}

impl DeviceDriver for RawValuesPublisherClient {
    fn parameters(&self) -> Vec<yarp_devices::params::ParamSpec> {
        RawValuesPublisherClientParams::PARAMS.to_vec()
    }

    fn open(&mut self, config: &Property) -> DevResult<()> {
        let p = RawValuesPublisherClientParams::read(config)?;
        let names = NwcNames {
            stream: format!("{}/rawdata:i", p.local),
            remote_stream: format!("{}/rawdata:o", p.remote),
            carrier: p.carrier,
            rpc: format!("{}/rpc:i", p.local),
            remote_rpc: format!("{}/rpc:o", p.remote),
        };
        self.client.open(
            NAME,
            "a running rawValuesPublisherServer (is the name server running?)",
            names,
            decode_data_map,
        )
    }

    fn close(&mut self) -> DevResult<()> {
        self.client.close();
        Ok(())
    }

    yarp_devices::views!(as_raw_values_publisher);
}

impl IRawValuesPublisher for RawValuesPublisherClient {
    fn get_raw_data_map(&mut self) -> DevResult<Map> {
        Ok(self
            .client()?
            .latest()
            .as_ref()
            .map(|(m, _)| m.clone())
            .unwrap_or_default())
    }

    fn get_metadata_map(&mut self) -> DevResult<BTreeMap<String, RawValuesKeyMetadata>> {
        let reply = self
            .client()?
            .call_encoded(encode_get_metadata(), GET_METADATA)?;
        decode_metadata_reply(&reply).map_err(|e| DeviceError::failed(NAME, e.to_string()))
    }
}
