//! `multipleanalogsensorsserver`: serves an attached device's sensors on
//! `/<name>/measures:o` (a measurement message every `period` ms, with an envelope) and
//! answers the metadata service on `/<name>/rpc:o` (the C++ name, although it is an input).
//!
//! Parameters (both required, as C++ 3.12): `name` (port prefix, starting with `/`) and
//! `period` (ms). The ports open when a device is attached, as in C++.

use super::family::{access, SensorFamily};
use super::interfaces::{MasStatus, SensorMeasurement};
use super::params::{now, positive_ms};
use super::rpc::handle_rpc;
use super::wire::{SensorMetadata, SensorRpcData, SensorStreamingData};
use crate::driver::{DeviceDriver, IWrapper, SharedDevice};
use crate::error::{DevResult, DeviceError};
use crate::runtime;
use crate::thrift::fail_reply;
use std::sync::Arc;
use std::time::Duration;
use thiserror::Error;
use yarp_net::nameserver::NameClient;
use yarp_net::peer_generation::PeerGenerations;
use yarp_net::port::{Port, PortError};
use yarp_proto::{Property, Stamp};

const NAME: &str = "multipleanalogsensorsserver";

crate::device_params! {
    /// What `multipleanalogsensorsserver` reads (C++ `MultipleAnalogSensorsServer_params.md`;
    /// the period may have a fraction).
    pub struct MultipleAnalogSensorsServerParams for "multipleanalogsensorsserver" {
        /// Prefix of the port opened by this device
        name: String = required; check crate::params::port_name,
        /// Refresh period of the broadcasted values in ms
        period: f64 = required; "ms"; check positive_ms,
    }
}

/// Why a measurement message could not be made (C++ then sends nothing that period).
#[derive(Debug, Clone, PartialEq, Error)]
pub enum CollectError {
    #[error("sensor {sensor} of type {family} has status {status:?}, no data will be sent")]
    Status {
        family: &'static str,
        sensor: String,
        status: MasStatus,
    },
    #[error("the device no longer offers the {0} interface")]
    Gone(&'static str),
}

/// Reads the metadata of every sensor `dev` offers (C++ `populateAllSensorsMetadata`).
pub fn collect_metadata(dev: &mut dyn DeviceDriver) -> DevResult<SensorRpcData> {
    let mut data = SensorRpcData::default();
    for family in SensorFamily::ALL {
        let Some(view) = access(dev, family) else {
            continue;
        };
        let list = &mut data.families[family.index()];
        for i in 0..view.count() {
            let name = view.name(i)?;
            let frame = match family {
                // C++ sends no frame for these families
                SensorFamily::ContactLoadCellArrays
                | SensorFamily::EncoderArrays
                | SensorFamily::SkinPatches => String::new(),
                _ => view.frame_name(i)?,
            };
            list.push(SensorMetadata::new(name, frame));
        }
    }
    Ok(data)
}

/// Reads one measurement of every sensor listed in `metadata` (C++ `run`). A sensor
/// whose status is not OK cancels the whole message; a failed read leaves NaNs.
pub fn collect_measurements(
    dev: &mut dyn DeviceDriver,
    metadata: &SensorRpcData,
) -> Result<SensorStreamingData, CollectError> {
    let mut data = SensorStreamingData::default();
    for family in SensorFamily::ALL {
        let sensors = metadata.family(family);
        if sensors.is_empty() {
            continue;
        }
        let view = access(dev, family).ok_or(CollectError::Gone(family.tag()))?;
        let out = &mut data.families[family.index()];
        for (i, md) in sensors.iter().enumerate() {
            let status = view.status(i);
            if status != MasStatus::Ok {
                return Err(CollectError::Status {
                    family: family.tag(),
                    sensor: md.name.clone(),
                    status,
                });
            }
            let m = view.measure(i).unwrap_or_else(|_| {
                SensorMeasurement::new(vec![f64::NAN; family.measure_size().unwrap_or(0)], 0.0)
            });
            out.push(m);
        }
    }
    Ok(data)
}

/// The ports and tasks of a server with a device attached.
struct Serving {
    rpc: Arc<Port>,
    stream: Arc<Port>,
    tasks: Vec<tokio::task::JoinHandle<()>>,
}

impl Serving {
    async fn start(
        prefix: &str,
        period: Duration,
        ns: NameClient,
        device: SharedDevice,
        metadata: SensorRpcData,
    ) -> Result<Serving, PortError> {
        let stream = Arc::new(Port::open(&format!("{prefix}/measures:o"), ns.clone()).await?);
        let rpc = match Port::open(&format!("{prefix}/rpc:o"), ns.clone()).await {
            Ok(p) => Arc::new(p),
            Err(e) => {
                close_port(stream).await;
                return Err(e);
            }
        };
        let metadata = Arc::new(metadata);
        // 4.0 renumbered the float tags of the measurements: each reader gets its own
        let peers = PeerGenerations::new(ns);
        let tasks = vec![
            tokio::spawn(serve_rpc(rpc.clone(), metadata.clone(), peers.clone())),
            tokio::spawn(stream_measurements(
                stream.clone(),
                period,
                device,
                metadata,
                peers,
            )),
        ];
        Ok(Serving { rpc, stream, tasks })
    }

    async fn stop(self) {
        for t in &self.tasks {
            t.abort();
        }
        for t in self.tasks {
            let _ = t.await;
        }
        close_port(self.rpc).await;
        close_port(self.stream).await;
    }
}

/// Closes a port once the tasks that shared it are gone (unregistering it).
async fn close_port(port: Arc<Port>) {
    if let Ok(p) = Arc::try_unwrap(port) {
        p.close().await;
    }
}

async fn serve_rpc(port: Arc<Port>, metadata: Arc<SensorRpcData>, peers: PeerGenerations) {
    while let Some(mut msg) = port.read().await {
        let reply = match msg.bottle() {
            // its replies hold no floats: the same bytes for both generations but
            // `getRemoteProtocolVersion`'s, which says the caller's YARP version (asked of
            // the C++ client's `<local>/measures:i`: its `<local>/rpc:i` waits on us)
            Ok(cmd) => {
                let client = msg
                    .from
                    .strip_suffix("/rpc:i")
                    .map(|local| format!("{local}/measures:i"))
                    .filter(|_| crate::thrift::is_protocol_version_request(&cmd));
                let generation = match client {
                    Some(port) => peers.of(&port).await,
                    None => yarp_proto::tags::Generation::V3,
                };
                handle_rpc(&cmd, &metadata, generation)
            }
            Err(e) => {
                tracing::warn!("{NAME}: undecodable request from {}: {e}", msg.from);
                fail_reply()
            }
        };
        if msg.wants_reply() {
            // the exact bytes of C++'s WireWriter, which tags list elements one by one
            msg.reply_encoded(reply);
        }
    }
}

async fn stream_measurements(
    port: Arc<Port>,
    period: Duration,
    device: SharedDevice,
    metadata: Arc<SensorRpcData>,
    peers: PeerGenerations,
) {
    let mut ticker = super::periodic::Ticker::new(period);
    let mut count: i32 = 0;
    let mut failing = crate::wrapper_ports::FailureStreak::default();
    loop {
        ticker.tick().await;
        if !port.has_outputs() {
            // nobody listens: keep the sequence going without reading the sensors
            count = count.wrapping_add(1);
            continue;
        }
        let data = crate::runtime::device_call(|| {
            let mut pd = device.lock();
            collect_measurements(pd.device(), &metadata)
        });
        match data {
            Ok(data) => {
                failing.passed();
                let stamp = Stamp::new(count, now());
                count = count.wrapping_add(1);
                port.write_by_generation(&data.to_bottle(), &peers, Some(stamp))
                    .await;
            }
            Err(e) => failing.failed(|| format!("{NAME}: {e}")),
        }
    }
}

/// The `multipleanalogsensorsserver` device.
#[derive(Default)]
pub struct MultipleAnalogSensorsServer {
    name: String,
    period: Duration,
    serving: Option<Serving>,
}

impl MultipleAnalogSensorsServer {
    pub fn new() -> Self {
        Self::default()
    }

    /// The measurement port's name (`/<name>/measures:o`).
    pub fn streaming_port_name(&self) -> String {
        format!("{}/measures:o", self.name)
    }

    /// The metadata RPC port's name (`/<name>/rpc:o`).
    pub fn rpc_port_name(&self) -> String {
        format!("{}/rpc:o", self.name)
    }

    fn network_error(&self, e: impl std::fmt::Display) -> DeviceError {
        DeviceError::BadParam {
            device: NAME.into(),
            param: "name".into(),
            expected: "a port prefix that can be registered (is the name server running?)",
            got: format!("{}: {e}", self.name),
        }
    }
}

impl DeviceDriver for MultipleAnalogSensorsServer {
    fn parameters(&self) -> Vec<crate::params::ParamSpec> {
        MultipleAnalogSensorsServerParams::PARAMS.to_vec()
    }

    fn open(&mut self, config: &Property) -> DevResult<()> {
        let p = MultipleAnalogSensorsServerParams::read(config)?;
        self.name = p.name.trim_end_matches('/').to_string();
        self.period = Duration::from_secs_f64(p.period / 1000.0);
        Ok(())
    }

    fn close(&mut self) -> DevResult<()> {
        IWrapper::detach(self)
    }

    crate::views!(as_wrapper, as_multiple_wrapper);
}

impl IWrapper for MultipleAnalogSensorsServer {
    fn attach(&mut self, device: SharedDevice) -> DevResult<()> {
        if self.name.is_empty() {
            return Err(DeviceError::NotOpen);
        }
        IWrapper::detach(self)?;
        let metadata = {
            let mut pd = device.lock();
            collect_metadata(pd.device())?
        };
        let ns = yarp_net::network::name_client().map_err(|e| self.network_error(e))?;
        let (prefix, period) = (self.name.clone(), self.period);
        let serving = runtime::block_on_result(async move {
            Serving::start(&prefix, period, ns, device, metadata)
                .await
                .map_err(|e| e.to_string())
        })
        .map_err(|e| self.network_error(e))?;
        self.serving = Some(serving);
        Ok(())
    }

    fn detach(&mut self) -> DevResult<()> {
        if let Some(s) = self.serving.take() {
            runtime::block_on_logged("server: closing", s.stop());
        }
        Ok(())
    }
}

crate::one_device_multiple_wrapper!(
    MultipleAnalogSensorsServer,
    "multipleanalogsensorsserver attaches exactly one device (join several with multipleanalogsensorsremapper)"
);
