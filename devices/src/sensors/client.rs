//! `multipleanalogsensorsclient`: the sensors of a remote `multipleanalogsensorsserver`,
//! behind the same interfaces.
//!
//! Parameters (C++ 3.12): `remote` and `local` (required port prefixes), `timeout`
//! (s, default 0.02: older measurements make the status `Timeout`), `externalConnection`
//! (default false: skip the RPC connection and metadata; someone else connects the
//! stream) and `carrier` (of the stream connection, default `tcp`).
//!
//! At open it opens `<local>/rpc:i` and `<local>/measures:i`, connects the first to
//! `<remote>/rpc:o` and `<remote>/measures:o` to the second, then asks `getMetadata` once.
//! Names and frames come from that metadata; measurements from the latest message.

use super::family::SensorFamily;
use super::forward::{impl_mas_interfaces, mas_views, FamilySource};
use super::interfaces::*;
use super::params::now;
use super::rpc::GET_METADATA;
use super::wire::{SensorRpcData, SensorStreamingData};
use crate::driver::DeviceDriver;
use crate::error::{DevResult, DeviceError};
use crate::runtime;
use parking_lot::Mutex;
use std::sync::Arc;
use std::time::Duration;
use yarp_net::nameserver::NameClient;
use yarp_net::port::Port;
use yarp_proto::{Bottle, Property};

const NAME: &str = "multipleanalogsensorsclient";

crate::device_params! {
    /// What `multipleanalogsensorsclient` reads (C++ `MultipleAnalogSensorsClient_params.md`).
    pub struct MultipleAnalogSensorsClientParams for "multipleanalogsensorsclient" {
        /// Prefix of the ports to which to connect, opened by MultipleAnalogSensorsServer device.
        remote: String = required,
        /// Port prefix of the ports opened by this device.
        local: String = required,
        /// Timeout after which the device reports an error if no measurement was received.
        timeout: f64 = 0.02; "s",
        /// If set to true, the connection to the rpc port of the MAS server is skipped and it is possible to connect to the data source externally after being opened
        "externalConnection" external_connection: bool = false,
        /// The carier used for the connection with the server.
        carrier: String = "tcp",
    }
}
/// How long open waits for the server's metadata.
const RPC_TIMEOUT: Duration = Duration::from_secs(10);

/// The latest received measurements and the stream's health.
#[derive(Debug)]
struct Received {
    data: SensorStreamingData,
    at: f64,
    status: MasStatus,
}

/// The open ports and the reader task.
struct Connection {
    rpc: Port,
    stream: Arc<Port>,
    reader: tokio::task::JoinHandle<()>,
}

/// The `multipleanalogsensorsclient` device.
pub struct MultipleAnalogSensorsClient {
    metadata: SensorRpcData,
    external: bool,
    timeout: f64,
    received: Arc<Mutex<Received>>,
    connection: Option<Connection>,
}

impl Default for MultipleAnalogSensorsClient {
    fn default() -> Self {
        MultipleAnalogSensorsClient {
            metadata: SensorRpcData::default(),
            external: false,
            timeout: 0.02,
            received: Arc::new(Mutex::new(Received {
                data: SensorStreamingData::default(),
                at: 0.0,
                status: MasStatus::WaitingForFirstRead,
            })),
            connection: None,
        }
    }
}

struct Settings {
    local: String,
    remote: String,
    carrier: String,
    external: bool,
}

fn network_error(param: &str, got: String) -> DeviceError {
    DeviceError::BadParam {
        device: NAME.into(),
        param: param.into(),
        expected: "a reachable multipleanalogsensorsserver (is it running?)",
        got,
    }
}

async fn connect(
    ns: NameClient,
    s: &Settings,
    received: Arc<Mutex<Received>>,
) -> DevResult<(Connection, SensorRpcData)> {
    let local_rpc = format!("{}/rpc:i", s.local);
    let local_stream = format!("{}/measures:i", s.local);
    let remote_rpc = format!("{}/rpc:o", s.remote);
    let remote_stream = format!("{}/measures:o", s.remote);
    let open_err = |name: &str, e: yarp_net::port::PortError| {
        network_error("local", format!("cannot open {name}: {e}"))
    };
    let rpc = Port::open(&local_rpc, ns.clone())
        .await
        .map_err(|e| open_err(&local_rpc, e))?;
    let stream = match Port::open(&local_stream, ns.clone()).await {
        Ok(p) => Arc::new(p),
        Err(e) => {
            rpc.close().await;
            return Err(open_err(&local_stream, e));
        }
    };
    let reader = tokio::spawn(read_stream(stream.clone(), received));
    let conn = Connection {
        rpc,
        stream,
        reader,
    };
    if s.external {
        return Ok((conn, SensorRpcData::default()));
    }
    match handshake(&ns, &conn, s, &remote_rpc, &remote_stream).await {
        Ok(md) => Ok((conn, md)),
        Err(e) => {
            conn.close().await;
            Err(e)
        }
    }
}

/// Connects to the server's ports and fetches the metadata.
async fn handshake(
    ns: &NameClient,
    conn: &Connection,
    s: &Settings,
    remote_rpc: &str,
    remote_stream: &str,
) -> DevResult<SensorRpcData> {
    let fail = |what: &str, e: String| network_error("remote", format!("{what}: {e}"));
    conn.rpc
        .connect(remote_rpc, None)
        .await
        .map_err(|e| fail(remote_rpc, e.to_string()))?;
    let local_stream = conn.stream.name().to_string();
    // as C++ Network::connect: ask whether the connection exists, then add it
    let already = yarp_net::network::is_connected(ns, remote_stream, &local_stream)
        .await
        .unwrap_or(false);
    if !already {
        let (ok, msg) =
            yarp_net::network::connect(ns, remote_stream, &local_stream, Some(&s.carrier))
                .await
                .map_err(|e| fail(remote_stream, e.to_string()))?;
        if !ok {
            return Err(fail(remote_stream, msg));
        }
    }
    let request = Bottle::new().with(GET_METADATA);
    let reply = tokio::time::timeout(RPC_TIMEOUT, conn.rpc.rpc(&request))
        .await
        .map_err(|_| fail(GET_METADATA, "no reply".into()))?
        .map_err(|e| fail(GET_METADATA, e.to_string()))?;
    SensorRpcData::from_bottle(&reply).map_err(|e| fail(GET_METADATA, format!("{e} in {reply}")))
}

async fn read_stream(port: Arc<Port>, received: Arc<Mutex<Received>>) {
    while let Some(msg) = port.read().await {
        let data = msg
            .bottle()
            .map_err(|e| e.to_string())
            .and_then(|b| SensorStreamingData::from_bottle(&b).map_err(|e| e.to_string()));
        match data {
            Ok(data) => {
                let mut r = received.lock();
                r.data = data;
                r.at = now();
                r.status = MasStatus::Ok;
            }
            Err(e) => tracing::warn!("{NAME}: bad measurement message from {}: {e}", msg.from),
        }
    }
}

impl Connection {
    async fn close(self) {
        self.reader.abort();
        let _ = self.reader.await;
        self.rpc.close().await;
        if let Ok(p) = Arc::try_unwrap(self.stream) {
            p.close().await;
        }
    }
}

impl MultipleAnalogSensorsClient {
    pub fn new() -> Self {
        Self::default()
    }

    /// The metadata received at open (empty with `externalConnection`).
    pub fn metadata(&self) -> &SensorRpcData {
        &self.metadata
    }

    /// The stream's status, after the timeout check (C++ `genericGetStatus`).
    pub fn status(&self) -> MasStatus {
        let mut r = self.received.lock();
        if r.status == MasStatus::Ok && now() - r.at > self.timeout {
            tracing::error!(
                "{NAME}: no data received in the last {:.6} seconds, timeout enabled.",
                now() - r.at
            );
            r.status = MasStatus::Timeout;
        }
        r.status
    }

    /// How many sensors of `family` the server has.
    pub fn count(&self, family: SensorFamily) -> usize {
        if !self.external {
            return self.metadata.family(family).len();
        }
        let status = self.status();
        let r = self.received.lock();
        if status == MasStatus::Ok {
            r.data.family(family).len()
        } else {
            0
        }
    }

    fn metadata_of(&self, family: SensorFamily, i: usize) -> DevResult<&super::SensorMetadata> {
        if self.external {
            return Err(DeviceError::Unsupported(
                "sensor metadata: the client was opened with externalConnection",
            ));
        }
        let list = self.metadata.family(family);
        list.get(i)
            .ok_or_else(|| no_sensor(family.tag(), i, list.len()))
    }

    /// The name of sensor `i` of `family`.
    pub fn name(&self, family: SensorFamily, i: usize) -> DevResult<String> {
        self.metadata_of(family, i).map(|m| m.name.clone())
    }

    /// The frame name of sensor `i` of `family`.
    pub fn frame_name(&self, family: SensorFamily, i: usize) -> DevResult<String> {
        self.metadata_of(family, i).map(|m| m.frame_name.clone())
    }

    /// The latest measurement of sensor `i` of `family`.
    pub fn measure(&self, family: SensorFamily, i: usize) -> DevResult<SensorMeasurement> {
        let status = self.status();
        if status != MasStatus::Ok {
            return Err(DeviceError::NotReady(
                "measurement: the stream from the server is not OK (waiting or timed out)",
            ));
        }
        let r = self.received.lock();
        let list = r.data.family(family);
        list.get(i)
            .cloned()
            .ok_or_else(|| no_sensor(family.tag(), i, list.len()))
    }
}

impl DeviceDriver for MultipleAnalogSensorsClient {
    fn parameters(&self) -> Vec<crate::params::ParamSpec> {
        MultipleAnalogSensorsClientParams::PARAMS.to_vec()
    }

    fn open(&mut self, config: &Property) -> DevResult<()> {
        let p = MultipleAnalogSensorsClientParams::read(config)?;
        let settings = Settings {
            remote: p.remote,
            local: p.local,
            carrier: p.carrier,
            external: p.external_connection,
        };
        self.timeout = p.timeout;
        self.close()?;
        let ns = yarp_net::network::name_client()
            .map_err(|e| network_error("local", format!("name server: {e}")))?;
        let received = self.received.clone();
        let external = settings.external;
        let (conn, metadata) =
            runtime::block_on_result(async move { connect(ns, &settings, received).await })?;
        self.connection = Some(conn);
        self.metadata = metadata;
        self.external = external;
        Ok(())
    }

    fn close(&mut self) -> DevResult<()> {
        if let Some(c) = self.connection.take() {
            runtime::block_on_logged("client: closing", c.close());
        }
        Ok(())
    }

    mas_views!();
}

impl FamilySource for MultipleAnalogSensorsClient {
    fn family_count(&self, family: SensorFamily) -> usize {
        self.count(family)
    }
    fn family_status(&self, _family: SensorFamily, _i: usize) -> MasStatus {
        // one stream carries every sensor: they share its status
        self.status()
    }
    fn family_name(&self, family: SensorFamily, i: usize) -> DevResult<String> {
        self.name(family, i)
    }
    fn family_frame_name(&self, family: SensorFamily, i: usize) -> DevResult<String> {
        self.frame_name(family, i)
    }
    fn family_measure(&self, family: SensorFamily, i: usize) -> DevResult<SensorMeasurement> {
        self.measure(family, i)
    }
}

impl_mas_interfaces!(MultipleAnalogSensorsClient);
