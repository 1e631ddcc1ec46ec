//! `analogsensorclient` (C++ `AnalogSensorClient`): an `IAnalogSensor` read from a
//! remote `analogServer`.
//!
//! Parameters: `local` (the input port's name; its RPC port is `<local>/rpc:o`),
//! `remote` (the server's data port; its RPC port is `<remote>/rpc:i`), `carrier` of the
//! data connection (default `udp`, as C++). Status as C++: `Error` until a vector
//! arrives, then `Ok` while consecutive envelopes are less than 100 ms apart, else
//! `Timeout`. Calibration requests go over RPC; the reply's int32 is the result.

use super::analog_server::{CALIBRATE, CALIBRATE_CHANNEL, IANALOG};
use super::interfaces::{AnalogStatus, IAnalogSensor};
use crate::driver::DeviceDriver;
use crate::error::{DevResult, DeviceError};
use crate::runtime;
use parking_lot::Mutex;
use std::sync::Arc;
use std::time::Duration;
use yarp_net::port::Port;
use yarp_proto::{Bottle, Property, Stamp, Value};

const NAME: &str = "analogsensorclient";

crate::device_params! {
    /// What `analogsensorclient` reads (C++ `AnalogSensorClient::open`).
    pub struct AnalogSensorClientParams for "analogsensorclient" {
        /// the port opened by this device, receiving the stream
        local: String = required,
        /// the analogServer's stream port
        remote: String = required,
        /// default carrier for streaming robot state
        carrier: String = "udp",
    }
}
/// C++ `ANALOG_TIMEOUT` (ms): older envelopes make the status `Timeout`.
const ANALOG_TIMEOUT_MS: f64 = 100.0;
const RPC_TIMEOUT: Duration = Duration::from_secs(10);

/// The latest vector, its envelope and the derived status.
#[derive(Debug, Clone)]
struct Latest {
    values: Vec<f64>,
    stamp: Option<Stamp>,
    state: AnalogStatus,
}

impl Latest {
    /// C++ `InputPortProcessor::onRead`: the status follows the envelope spacing.
    fn update(&mut self, values: Vec<f64>, stamp: Option<Stamp>) {
        let prev = self.stamp.or(stamp);
        self.state = match (prev, stamp) {
            (Some(a), Some(b)) if 1000.0 * (b.time - a.time) >= ANALOG_TIMEOUT_MS => {
                AnalogStatus::Timeout
            }
            _ => AnalogStatus::Ok,
        };
        self.values = values;
        self.stamp = stamp;
    }
}

struct Ports {
    input: Arc<Port>,
    rpc: Arc<Port>,
    reader: tokio::task::JoinHandle<()>,
}

impl Ports {
    async fn close(self) {
        self.reader.abort();
        let _ = self.reader.await;
        for port in [self.rpc, self.input] {
            if let Ok(p) = Arc::try_unwrap(port) {
                p.close().await;
            }
        }
    }
}

/// The `analogsensorclient` device.
pub struct AnalogSensorClient {
    latest: Arc<Mutex<Latest>>,
    ports: Option<Ports>,
}

impl Default for AnalogSensorClient {
    fn default() -> Self {
        AnalogSensorClient {
            latest: Arc::new(Mutex::new(Latest {
                values: Vec::new(),
                stamp: None,
                state: AnalogStatus::Error,
            })),
            ports: None,
        }
    }
}

async fn read_vectors(port: Arc<Port>, latest: Arc<Mutex<Latest>>) {
    while let Some(msg) = port.read().await {
        let values = msg
            .bottle()
            .ok()
            .and_then(|b| b.iter().map(Value::as_f64).collect::<Option<Vec<f64>>>());
        match values {
            Some(v) => latest.lock().update(v, msg.stamp),
            None => tracing::warn!("{NAME}: not a vector of numbers from {}", msg.from),
        }
    }
}

fn network_error(param: &str, got: String) -> DeviceError {
    DeviceError::BadParam {
        device: NAME.into(),
        param: param.into(),
        expected: "a reachable analogServer port (is it running?)",
        got,
    }
}

impl AnalogSensorClient {
    pub fn new() -> Self {
        Self::default()
    }

    /// The envelope of the latest vector (C++ `getLastInputStamp`).
    pub fn last_input_stamp(&self) -> Option<Stamp> {
        self.latest.lock().stamp
    }

    /// Sends `[iana] <args...>` and maps the server's int32 result.
    fn calibrate_rpc(&mut self, args: Bottle) -> DevResult<()> {
        let rpc = self.ports.as_ref().ok_or(DeviceError::NotOpen)?.rpc.clone();
        let mut cmd = Bottle::new().with(IANALOG);
        for v in args.into_items() {
            cmd.push(v);
        }
        let command = cmd.to_string();
        let reply = crate::nwc_ports::call_within(NAME, &rpc, cmd, RPC_TIMEOUT)?;
        match reply.get(0) {
            Some(v) if v.is_int() && v.as_i64() == Some(0) => Ok(()),
            _ => Err(DeviceError::Refused {
                device: NAME.to_string(),
                command,
            }),
        }
    }
}

impl DeviceDriver for AnalogSensorClient {
    fn parameters(&self) -> Vec<crate::params::ParamSpec> {
        AnalogSensorClientParams::PARAMS.to_vec()
    }

    fn open(&mut self, config: &Property) -> DevResult<()> {
        let AnalogSensorClientParams {
            local,
            remote,
            carrier,
        } = AnalogSensorClientParams::read(config)?;
        self.close()?;
        let ns = yarp_net::network::name_client()
            .map_err(|e| network_error("local", format!("name server: {e}")))?;
        let latest = self.latest.clone();
        let ports = runtime::block_on_result(async move {
            let input = Arc::new(
                Port::open(&local, ns.clone())
                    .await
                    .map_err(|e| network_error("local", format!("{local}: {e}")))?,
            );
            let reader = tokio::spawn(read_vectors(input.clone(), latest));
            let rpc_name = format!("{local}/rpc:o");
            let rpc = match Port::open(&rpc_name, ns.clone()).await {
                Ok(p) => Arc::new(p),
                Err(e) => {
                    reader.abort();
                    return Err(network_error("local", format!("{rpc_name}: {e}")));
                }
            };
            let ports = Ports { input, rpc, reader };
            let connected = async {
                let (ok, msg) = yarp_net::network::connect(&ns, &remote, &local, Some(&carrier))
                    .await
                    .map_err(|e| format!("{remote}: {e}"))?;
                if !ok {
                    return Err(format!("{remote}: {msg}"));
                }
                ports
                    .rpc
                    .connect(&format!("{remote}/rpc:i"), None)
                    .await
                    .map_err(|e| format!("{remote}/rpc:i: {e}"))
            };
            match connected.await {
                Ok(()) => Ok(ports),
                Err(e) => {
                    ports.close().await;
                    Err(network_error("remote", e))
                }
            }
        })?;
        self.ports = Some(ports);
        Ok(())
    }

    fn close(&mut self) -> DevResult<()> {
        if let Some(p) = self.ports.take() {
            runtime::block_on_logged("analog_client: closing", p.close());
        }
        Ok(())
    }

    crate::views!(as_analog_sensor);
}

impl IAnalogSensor for AnalogSensorClient {
    fn read(&mut self, out: &mut Vec<f64>) -> AnalogStatus {
        let l = self.latest.lock();
        if l.state != AnalogStatus::Error {
            out.clone_from(&l.values);
        }
        l.state
    }
    fn get_state(&mut self, _ch: usize) -> AnalogStatus {
        // C++: "not implemented yet", always OK
        AnalogStatus::Ok
    }
    fn get_channels(&mut self) -> usize {
        let l = self.latest.lock();
        if l.state == AnalogStatus::Error {
            0
        } else {
            l.values.len()
        }
    }
    fn calibrate_sensor(&mut self) -> DevResult<()> {
        self.calibrate_rpc(Bottle::new().with(CALIBRATE))
    }
    fn calibrate_sensor_with(&mut self, values: &[f64]) -> DevResult<()> {
        let list: Bottle = values.iter().copied().collect();
        self.calibrate_rpc(Bottle::new().with(CALIBRATE).with(Value::List(list)))
    }
    fn calibrate_channel(&mut self, ch: usize) -> DevResult<()> {
        self.calibrate_rpc(Bottle::new().with(CALIBRATE_CHANNEL).with(ch as i32))
    }
    fn calibrate_channel_with(&mut self, ch: usize, value: f64) -> DevResult<()> {
        self.calibrate_rpc(
            Bottle::new()
                .with(CALIBRATE_CHANNEL)
                .with(ch as i32)
                .with(value),
        )
    }
}
