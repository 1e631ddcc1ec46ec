//! `rawValuesPublisherServer` (icub-main 2.11): serves one attached `IRawValuesPublisher`.
//!
//! Parameters as C++: `name` (the ports' prefix) and `period` (ms), both required. Ports:
//! `<name>/rawdata:o` streams every key's raw values every period, with an envelope (a
//! cycle whose read fails sends nothing); `<name>/rpc:o` is, despite its name, the server
//! of `getMetadata` (the device's metadata, read once at attach as C++ caches it).

use super::wire::{encode_data_map, handle_rpc};
use std::sync::Arc;
use std::time::Duration;
use yarp_devices::driver::{DeviceDriver, IMultipleWrapper, SharedDevice};
use yarp_devices::error::{DevResult, DeviceError};
use yarp_devices::runtime;
use yarp_devices::sensors::params::now;
use yarp_devices::sensors::periodic::Ticker;
use yarp_devices::wrapper_ports::{Reply, Slot, WrapperPorts};
use yarp_net::port::Port;
use yarp_proto::tags::Generation;
use yarp_proto::{Bottle, Property, Stamp};

pub const NAME: &str = "rawValuesPublisherServer";

yarp_devices::device_params! {
    /// What `rawValuesPublisherServer` reads (icub-main's `rawValuesPublisherServer_params.md`).
    pub struct RawValuesPublisherServerParams for "rawValuesPublisherServer" {
        /// Prefix of the port names opened by the device
        name: String = required; check yarp_devices::params::port_name,
        /// Refresh period of the broadcasted values
        period: i64 = required; "ms"; min 1,
    }
}

/// The `rawValuesPublisherServer` device.
#[derive(Default)]
pub struct RawValuesPublisherServer {
    name: String,
    period: Duration,
    slot: Slot,
    ports: Option<WrapperPorts>,
    stream_task: Option<tokio::task::JoinHandle<()>>,
}

/// The metadata of the attached publisher, asked per request (the same as C++'s cache
/// unless the device changes its keys).
fn answer(cmd: &Bottle, dev: Option<&mut dyn DeviceDriver>, generation: Generation) -> Reply {
    let metadata = || dev?.as_raw_values_publisher()?.get_metadata_map().ok();
    Reply::Encoded(handle_rpc(cmd, metadata, generation))
}

async fn stream(port: Arc<Port>, period: Duration, device: SharedDevice) {
    let mut ticker = Ticker::new(period);
    let mut count: i32 = 0;
    loop {
        ticker.tick().await;
        let map = {
            let mut pd = device.lock();
            pd.device()
                .as_raw_values_publisher()
                .map(|p| p.get_raw_data_map())
        };
        // C++ sends nothing in a cycle whose read fails
        if let Some(Ok(map)) = map {
            port.write_encoded_nowait(encode_data_map(&map), Some(Stamp::new(count, now())));
            count = count.wrapping_add(1);
        }
    }
}

impl RawValuesPublisherServer {
    pub fn new() -> Self {
        Self::default()
    }

    /// `<name>/rawdata:o`.
    pub fn stream_port_name(&self) -> String {
        format!("{}/rawdata:o", self.name)
    }

    fn stop_stream(&mut self) {
        if let Some(t) = self.stream_task.take() {
            t.abort();
            runtime::block_on_logged("rawValuesPublisherServer: detaching", async move {
                let _ = t.await;
            });
        }
    }
}

impl DeviceDriver for RawValuesPublisherServer {
    fn parameters(&self) -> Vec<yarp_devices::params::ParamSpec> {
        RawValuesPublisherServerParams::PARAMS.to_vec()
    }

    fn open(&mut self, config: &Property) -> DevResult<()> {
        let p = RawValuesPublisherServerParams::read(config)?;
        self.name = p.name;
        self.period = Duration::from_millis(u64::try_from(p.period).unwrap_or(1));
        let ports = WrapperPorts::open(
            NAME,
            vec![self.stream_port_name()],
            format!("{}/rpc:o", self.name),
            self.slot.clone(),
            answer,
            // the protocol is the same in both generations
            |_| None,
        )?;
        self.ports = Some(ports);
        Ok(())
    }

    fn close(&mut self) -> DevResult<()> {
        IMultipleWrapper::detach_all(self)?;
        if let Some(p) = self.ports.take() {
            p.close();
        }
        Ok(())
    }

    yarp_devices::views!(as_multiple_wrapper);
}

impl IMultipleWrapper for RawValuesPublisherServer {
    fn attach_all(&mut self, devices: &[(String, SharedDevice)]) -> DevResult<()> {
        let [(_, device)] = devices else {
            return Err(DeviceError::Unsupported(
                "rawValuesPublisherServer attaches exactly one device",
            ));
        };
        self.stop_stream();
        let port = self.ports.as_ref().ok_or(DeviceError::NotOpen)?.streams[0].clone();
        {
            let mut pd = device.lock();
            let publisher =
                pd.device()
                    .as_raw_values_publisher()
                    .ok_or(DeviceError::Unsupported(
                        "rawValuesPublisherServer attaches an IRawValuesPublisher",
                    ))?;
            // C++ refuses the attach when the device has no metadata
            publisher.get_metadata_map().map_err(|e| {
                DeviceError::failed(
                    NAME,
                    format!("cannot read the attached device's metadata: {e}"),
                )
            })?;
        }
        *self.slot.lock() = Some(device.clone());
        self.stream_task = Some(runtime::handle().spawn(stream(port, self.period, device.clone())));
        Ok(())
    }

    fn detach_all(&mut self) -> DevResult<()> {
        self.stop_stream();
        *self.slot.lock() = None;
        Ok(())
    }
}
