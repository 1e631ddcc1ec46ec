//! `analogServer` (C++ `AnalogWrapper`): streams an `IAnalogSensor`'s vector, as the
//! iCub configurations use it for MAIS and strain sensors (`/icub/left_hand/analog:o`).
//!
//! Parameters (C++ 3.x): `period` (ms, required), `name` (the full data port name,
//! required; the removed `deviceId` is refused with a hint, as C++ does), optionally
//! `ports (a b ...)` + `channels N` + one group per port `a wBase wTop base top`, which
//! splits the vector over the ports `<name>/a`, ... Every data port `P` has an RPC port
//! `P/rpc:i` answering `[iana] [cal]`, `[iana] [cal] v...` (or `(v...)`), `[iana] [calc] ch [v]` with the
//! sensor's int32 result, anything else `[fail]`. Messages carry an envelope.

use super::interfaces::{AnalogStatus, IAnalogSensor};
use super::params::{now, positive_ms};
use crate::driver::{DeviceDriver, IWrapper, Params, SharedDevice};
use crate::error::{DevResult, DeviceError};
use crate::runtime;
use parking_lot::Mutex;
use std::sync::Arc;
use std::time::Duration;
use yarp_net::nameserver::NameClient;
use yarp_net::port::{Port, PortError};
use yarp_proto::{Bottle, Property, Stamp, Value, Vocab32};

const NAME: &str = "analogServer";

/// `deviceId` went with C++ YARP 3.
fn removed(_: &yarp_proto::Value) -> Result<(), &'static str> {
    Err("absent (removed in C++ YARP 3; give the full port as `name`, e.g. /icub/left_arm/analog:o)")
}

crate::device_params! {
    /// What `analogServer` reads (C++ `AnalogWrapper::open`): one port `name`, or the
    /// `ports` list with `channels` and, for each port, a line `PORT wBase wTop base top`.
    pub struct AnalogServerParams for "analogServer" {
        /// Refresh period of the broadcasted values
        period: f64 = required; "ms"; check positive_ms,
        /// Removed in C++ YARP 3
        "deviceId" device_id: yarp_proto::Value = optional; check removed,
        /// The port streaming the values (without `ports`)
        name: String = required,
        /// The ports the channels are split over
        ports: Vec<String> = optional,
        /// Number of channels of the device (with `ports`)
        channels: i64 = optional,
    }
}
/// C++ `VOCAB_IANALOG`, `VOCAB_CALIBRATE`, `VOCAB_CALIBRATE_CHANNEL`.
pub(crate) const IANALOG: Vocab32 = Vocab32::new("iana");
pub(crate) const CALIBRATE: Vocab32 = Vocab32::new("cal");
pub(crate) const CALIBRATE_CHANNEL: Vocab32 = Vocab32::new("calc");

/// One data port and the part of the sensor vector it carries.
#[derive(Debug, Clone, PartialEq)]
pub struct AnalogPortEntry {
    pub port_name: String,
    pub offset: usize,
    /// `None`: everything from `offset` on.
    pub length: Option<usize>,
}

impl AnalogPortEntry {
    /// This port's slice of `values`, `None` when the vector is too short.
    pub fn slice<'a>(&self, values: &'a [f64]) -> Option<&'a [f64]> {
        match self.length {
            None => values.get(self.offset..),
            Some(n) => values.get(self.offset..self.offset.checked_add(n)?),
        }
    }
}

/// Serves one analog-server RPC command (C++ `AnalogServerHandler::read`).
pub fn handle_analog_rpc(cmd: &Bottle, sensor: Option<&mut dyn IAnalogSensor>) -> Bottle {
    let fail = || Bottle::new().with(Vocab32::new("fail"));
    let Some(sensor) = sensor else {
        return fail();
    };
    if cmd.get(0).and_then(Value::as_vocab) != Some(IANALOG) {
        return fail();
    }
    let code = |r: DevResult<()>| match r {
        Ok(()) => AnalogStatus::Ok as i32,
        Err(_) => AnalogStatus::Error as i32,
    };
    let int = |i: usize| cmd.get(i).and_then(Value::as_i64);
    let float = |i: usize| cmd.get(i).and_then(Value::as_f64);
    let ret = match (cmd.get(1).and_then(Value::as_vocab), cmd.len()) {
        (Some(CALIBRATE), 2) => code(sensor.calibrate_sensor()),
        // the C++ client sends the values as one list, the C++ server reads them inline
        (Some(CALIBRATE), 3) if cmd[2].is_list() => {
            let list = cmd[2]
                .as_list()
                .map(|l| l.iter().map(Value::as_f64).collect::<Option<Vec<f64>>>());
            match list {
                Some(Some(v)) => code(sensor.calibrate_sensor_with(&v)),
                _ => AnalogStatus::Error as i32,
            }
        }
        (Some(CALIBRATE), _) => match (2..cmd.len()).map(float).collect::<Option<Vec<f64>>>() {
            Some(v) => code(sensor.calibrate_sensor_with(&v)),
            None => AnalogStatus::Error as i32,
        },
        (Some(CALIBRATE_CHANNEL), 3 | 4) => match int(2).and_then(|c| usize::try_from(c).ok()) {
            None => AnalogStatus::Error as i32,
            Some(ch) if cmd.len() == 3 => code(sensor.calibrate_channel(ch)),
            Some(ch) => match float(3) {
                Some(v) => code(sensor.calibrate_channel_with(ch, v)),
                None => AnalogStatus::Error as i32,
            },
        },
        // C++ answers nothing useful for other arities: the initial AS_ERROR
        (Some(CALIBRATE_CHANNEL), _) => AnalogStatus::Error as i32,
        _ => return fail(),
    };
    Bottle::new().with(ret)
}

/// The ports the configuration asks for (C++ `initialize_YARP`).
fn port_entries(p: &Params<'_>, name: &str) -> DevResult<Vec<AnalogPortEntry>> {
    let Some(ports) = p.find("ports") else {
        return Ok(vec![AnalogPortEntry {
            port_name: name.to_string(),
            offset: 0,
            length: None,
        }]);
    };
    let bad = |param: &str, expected: &'static str, got: String| DeviceError::BadParam {
        device: NAME.into(),
        param: param.into(),
        expected,
        got,
    };
    let list = ports
        .as_list()
        .ok_or_else(|| bad("ports", "a list of port names", ports.to_string()))?;
    let channels = p.int("channels")?.ok_or_else(|| p.missing("channels"))?;
    let mut entries = Vec::new();
    let mut sum = 0i64;
    for v in list.iter() {
        let port = v.to_string_bare();
        let group = p.config.find_group(&port).ok_or_else(|| p.missing(&port))?;
        let mut rest: Vec<Value> = group.iter().skip(1).cloned().collect();
        // an XML <elem> may arrive as one text "0 191 0 191": read it as C++ re-parses it
        if let [Value::String(text)] = rest.as_slice() {
            rest = Bottle::from_text(text).into_items();
        }
        let nums: Option<Vec<i64>> = rest
            .iter()
            .map(|v| v.is_int().then(|| v.as_i64()).flatten())
            .collect();
        let &[w_base, w_top, base, top] = nums.as_deref().unwrap_or_default() else {
            return Err(bad(
                &port,
                "four integers: wBase wTop base top",
                group.to_string(),
            ));
        };
        if w_top - w_base != top - base || w_base < 0 || top < base {
            return Err(bad(&port, "ranges of the same size", group.to_string()));
        }
        let n = top - base + 1;
        sum += n;
        entries.push(AnalogPortEntry {
            port_name: format!("{name}/{port}"),
            offset: w_base as usize,
            length: Some(n as usize),
        });
    }
    if sum != channels {
        return Err(bad(
            "channels",
            "the number of channels the ports map",
            format!("{channels} (the ports map {sum})"),
        ));
    }
    Ok(entries)
}

/// The attached sensor, shared by the RPC handlers and the streaming task.
type Attached = Arc<Mutex<Option<SharedDevice>>>;

async fn serve_rpc(port: Arc<Port>, attached: Attached) {
    while let Some(mut msg) = port.read().await {
        let reply = match msg.bottle() {
            Ok(cmd) => {
                let dev = attached.lock().clone();
                match dev {
                    Some(dev) => crate::runtime::device_call(|| {
                        handle_analog_rpc(&cmd, dev.lock().device().as_analog_sensor())
                    }),
                    None => handle_analog_rpc(&cmd, None),
                }
            }
            Err(e) => {
                tracing::warn!("{NAME}: undecodable request from {}: {e}", msg.from);
                Bottle::new().with(Vocab32::new("fail"))
            }
        };
        msg.reply(reply);
    }
}

async fn stream(
    ports: Vec<(AnalogPortEntry, Port)>,
    period: Duration,
    attached: Attached,
    mut stop: tokio::sync::oneshot::Receiver<()>,
) {
    let mut ticker = super::periodic::Ticker::new(period);
    let mut values = Vec::new();
    let mut count: i32 = 0;
    loop {
        tokio::select! {
            _ = &mut stop => break,
            _ = ticker.tick() => {}
        }
        let Some(dev) = attached.lock().clone() else {
            continue;
        };
        if !ports.iter().any(|(_, p)| p.has_outputs()) {
            // nobody listens: keep the sequence going without reading the sensor
            count = count.wrapping_add(1);
            continue;
        }
        let status = crate::runtime::device_call(|| {
            let mut pd = dev.lock();
            match pd.device().as_analog_sensor() {
                Some(s) => s.read(&mut values),
                None => AnalogStatus::Error,
            }
        });
        if status != AnalogStatus::Ok || values.is_empty() {
            tracing::debug!("{NAME}: sensor read gave {status:?}");
            continue;
        }
        let stamp = Stamp::new(count, now());
        count = count.wrapping_add(1);
        for (entry, port) in &ports {
            match entry.slice(&values) {
                Some(part) => {
                    let b: Bottle = part.iter().copied().collect();
                    port.write_nowait(&b, Some(stamp));
                }
                None => tracing::error!(
                    "{NAME}: {} needs {} values, the sensor gave {}",
                    entry.port_name,
                    entry.offset + entry.length.unwrap_or(0),
                    values.len()
                ),
            }
        }
    }
    for (_, port) in ports {
        port.close().await;
    }
}

async fn open_ports(
    entries: &[AnalogPortEntry],
    ns: &NameClient,
    rpc: bool,
) -> Result<Vec<Port>, PortError> {
    let mut ports = Vec::new();
    for e in entries {
        let name = if rpc {
            format!("{}/rpc:i", e.port_name)
        } else {
            e.port_name.clone()
        };
        match Port::open(&name, ns.clone()).await {
            Ok(p) => ports.push(p),
            Err(err) => {
                for p in ports {
                    p.close().await;
                }
                return Err(err);
            }
        }
    }
    Ok(ports)
}

/// The `analogServer` device.
#[derive(Default)]
pub struct AnalogServer {
    entries: Vec<AnalogPortEntry>,
    period: Duration,
    attached: Attached,
    ns: Option<NameClient>,
    rpc: Vec<(Arc<Port>, tokio::task::JoinHandle<()>)>,
    streaming: Option<(
        tokio::sync::oneshot::Sender<()>,
        tokio::task::JoinHandle<()>,
    )>,
}

impl AnalogServer {
    pub fn new() -> Self {
        Self::default()
    }

    /// The data ports and what each carries.
    pub fn ports(&self) -> &[AnalogPortEntry] {
        &self.entries
    }

    fn stop_streaming(&mut self) {
        if let Some((stop, task)) = self.streaming.take() {
            let _ = stop.send(());
            let _ = runtime::block_on(async move {
                tokio::time::timeout(Duration::from_secs(5), task).await
            });
        }
    }
}

fn network_error(name: &str, e: impl std::fmt::Display) -> DeviceError {
    DeviceError::BadParam {
        device: NAME.into(),
        param: "name".into(),
        expected: "a port name that can be registered (is the name server running?)",
        got: format!("{name}: {e}"),
    }
}

impl DeviceDriver for AnalogServer {
    fn parameters(&self) -> Vec<crate::params::ParamSpec> {
        AnalogServerParams::PARAMS.to_vec()
    }

    fn open(&mut self, config: &Property) -> DevResult<()> {
        let AnalogServerParams { period, name, .. } = AnalogServerParams::read(config)?;
        let entries = port_entries(&Params::new(NAME, config), &name)?;
        self.close()?;
        let ns = yarp_net::network::name_client().map_err(|e| network_error(&name, e))?;
        let (e2, ns2) = (entries.clone(), ns.clone());
        let rpc_ports = runtime::block_on_result(async move {
            open_ports(&e2, &ns2, true).await.map_err(|e| e.to_string())
        })
        .map_err(|e| network_error(&name, e))?;
        let handle = runtime::handle();
        self.rpc = rpc_ports
            .into_iter()
            .map(|port| {
                let port = Arc::new(port);
                let task = handle.spawn(serve_rpc(port.clone(), self.attached.clone()));
                (port, task)
            })
            .collect();
        self.entries = entries;
        self.period = Duration::from_secs_f64(period / 1000.0);
        self.ns = Some(ns);
        Ok(())
    }

    fn close(&mut self) -> DevResult<()> {
        self.stop_streaming();
        *self.attached.lock() = None;
        let rpc = std::mem::take(&mut self.rpc);
        if !rpc.is_empty() {
            runtime::block_on_logged("analog_server: closing", async move {
                for (port, task) in rpc {
                    task.abort();
                    let _ = task.await;
                    if let Ok(p) = Arc::try_unwrap(port) {
                        p.close().await;
                    }
                }
            });
        }
        Ok(())
    }

    crate::views!(as_wrapper, as_multiple_wrapper);
}

impl IWrapper for AnalogServer {
    fn attach(&mut self, device: SharedDevice) -> DevResult<()> {
        let ns = self.ns.clone().ok_or(DeviceError::NotOpen)?;
        {
            let mut pd = device.lock();
            let sensor = pd
                .device()
                .as_analog_sensor()
                .ok_or(DeviceError::Unsupported(
                    "analogServer: the device is not an IAnalogSensor",
                ))?;
            if sensor.get_channels() == 0 {
                return Err(DeviceError::Unsupported(
                    "analogServer: the sensor has no channels",
                ));
            }
        }
        self.stop_streaming();
        let entries = self.entries.clone();
        let first = entries
            .first()
            .map(|e| e.port_name.clone())
            .unwrap_or_default();
        let data_ports = runtime::block_on_result(async move {
            let ports = open_ports(&entries, &ns, false)
                .await
                .map_err(|e| e.to_string())?;
            Ok::<_, String>(entries.into_iter().zip(ports).collect::<Vec<_>>())
        })
        .map_err(|e| network_error(&first, e))?;
        *self.attached.lock() = Some(device);
        let (tx, rx) = tokio::sync::oneshot::channel();
        let task =
            runtime::handle().spawn(stream(data_ports, self.period, self.attached.clone(), rx));
        self.streaming = Some((tx, task));
        Ok(())
    }

    fn detach(&mut self) -> DevResult<()> {
        self.stop_streaming();
        *self.attached.lock() = None;
        Ok(())
    }
}

crate::one_device_multiple_wrapper!(AnalogServer, "analogServer attaches exactly one device");
