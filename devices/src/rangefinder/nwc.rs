//! `rangefinder2D_nwc_yarp` (C++ YARP 3.12 `Rangefinder2D_nwc_yarp`): an `IRangefinder2D`
//! read from a `rangefinder2D_nws_yarp`.
//!
//! Parameters as C++: `local` (the port receiving the scans; the RPC port is
//! `<local>/rpc:o`), `remote` (the server's streaming port; its RPC port is
//! `<remote>/rpc:i`), `carrier` (of the stream, default `tcp`). Scans and their time come
//! from the stream (empty before the first one, as C++); the device status is the last
//! scan's (`DEVICE_TIMEOUT` before any); the rest goes through the server's
//! `IRangefinder2DMsgs` service.

use super::protocol::{parse_reply, status_of, LaserScan2D, ReturnCode};
use super::{IRangefinder2D, LaserStatus};
use crate::driver::{DeviceDriver, Params};
use crate::error::{DevResult, DeviceError};
use crate::runtime;
use std::sync::{Arc, Mutex};
use std::time::Duration;
use yarp_net::nameserver::NameClient;
use yarp_net::port::Port;
use yarp_proto::{Bottle, Property, Value};

const NAME: &str = "rangefinder2D_nwc_yarp";
const RPC_TIMEOUT: Duration = Duration::from_secs(5);

/// The latest scan and its envelope time.
type Latest = Arc<Mutex<Option<(LaserScan2D, f64)>>>;

struct Client {
    stream: Arc<Port>,
    task: tokio::task::JoinHandle<()>,
    rpc: Arc<Port>,
    latest: Latest,
}

async fn receive(port: Arc<Port>, latest: Latest) {
    while let Some(msg) = port.read().await {
        let scan = msg
            .bottle()
            .map_err(|e| e.to_string())
            .and_then(|b| LaserScan2D::from_bottle(&b).map_err(|e| e.to_string()));
        match scan {
            Ok(s) => {
                let t = msg.stamp.map_or(0.0, |s| s.time);
                *latest.lock().unwrap_or_else(|e| e.into_inner()) = Some((s, t));
            }
            Err(e) => tracing::warn!("{NAME}: ignoring a message that is not a scan: {e}"),
        }
    }
}

async fn close_port(port: Arc<Port>) {
    if let Ok(p) = Arc::try_unwrap(port) {
        p.close().await;
    }
}

impl Client {
    async fn open(
        ns: NameClient,
        local: String,
        remote: String,
        carrier: String,
    ) -> Result<Client, String> {
        let stream = Arc::new(
            Port::open(&local, ns.clone())
                .await
                .map_err(|e| format!("{local}: {e}"))?,
        );
        let connected = match yarp_net::network::connect(&ns, &remote, &local, Some(&carrier)).await
        {
            Ok((true, _)) => Ok(()),
            Ok((false, msg)) => Err(msg),
            Err(e) => Err(e.to_string()),
        };
        if let Err(e) = connected {
            close_port(stream).await;
            return Err(format!("connecting {remote} to {local}: {e}"));
        }
        let rpc_name = format!("{local}/rpc:o");
        let rpc = match Port::open(&rpc_name, ns).await {
            Ok(p) => p,
            Err(e) => {
                close_port(stream).await;
                return Err(format!("{rpc_name}: {e}"));
            }
        };
        let remote_rpc = format!("{remote}/rpc:i");
        if let Err(e) = rpc.connect(&remote_rpc, None).await {
            rpc.close().await;
            close_port(stream).await;
            return Err(format!("connecting {rpc_name} to {remote_rpc}: {e}"));
        }
        let latest = Latest::default();
        let task = tokio::spawn(receive(stream.clone(), latest.clone()));
        Ok(Client {
            stream,
            task,
            rpc: Arc::new(rpc),
            latest,
        })
    }

    async fn close(self) {
        self.task.abort();
        let _ = self.task.await;
        close_port(self.stream).await;
        close_port(self.rpc).await;
    }
}

/// The `rangefinder2D_nwc_yarp` device.
#[derive(Default)]
pub struct Rangefinder2DNwcYarp {
    client: Option<Client>,
}

impl Rangefinder2DNwcYarp {
    pub fn new() -> Self {
        Self::default()
    }

    /// Calls `method` (a thrift name such as `getScanRate_RPC`) with `args`; the fields
    /// after the return code, or the failure.
    fn call(&self, method: &str, args: &[f64]) -> DevResult<Vec<Value>> {
        let port = self
            .client
            .as_ref()
            .ok_or(DeviceError::NotOpen)?
            .rpc
            .clone();
        let mut cmd = Bottle::new();
        for word in method.split('_') {
            cmd.push(word);
        }
        for &a in args {
            cmd.push(a);
        }
        let what = cmd.to_string();
        let reply =
            runtime::block_on(
                async move { tokio::time::timeout(RPC_TIMEOUT, port.rpc(&cmd)).await },
            )
            .map_err(|_| {
                DeviceError::failed(NAME, format!("no reply to {what} in {RPC_TIMEOUT:?}"))
            })?
            .map_err(|e| DeviceError::failed(NAME, format!("{what}: {e}")))?;
        match parse_reply(&reply) {
            Some((0, fields)) => Ok(fields),
            Some((code, _)) if code == ReturnCode::NotImplemented as i32 => Err(
                DeviceError::Unsupported("the remote rangefinder does not implement this"),
            ),
            _ => Err(DeviceError::failed(
                NAME,
                format!("{what} answered {reply}"),
            )),
        }
    }

    fn floats(&self, method: &str, n: usize) -> DevResult<Vec<f64>> {
        let fields = self.call(method, &[])?;
        let nums: Vec<f64> = fields.iter().filter_map(Value::as_f64).collect();
        if nums.len() == n {
            Ok(nums)
        } else {
            Err(DeviceError::failed(
                NAME,
                format!("{method}: malformed reply {fields:?}"),
            ))
        }
    }
}

impl DeviceDriver for Rangefinder2DNwcYarp {
    fn open(&mut self, config: &Property) -> DevResult<()> {
        let p = Params::new(NAME, config);
        let local = p.string("local")?.ok_or_else(|| p.missing("local"))?;
        let remote = p.string("remote")?.ok_or_else(|| p.missing("remote"))?;
        let carrier = p.string("carrier")?.unwrap_or_else(|| "tcp".into());
        let network = |e: String| DeviceError::BadParam {
            device: NAME.into(),
            param: "remote".into(),
            expected: "a running rangefinder2D_nws_yarp port (is the name server running?)",
            got: e,
        };
        let ns = yarp_net::network::name_client().map_err(|e| network(e.to_string()))?;
        let client =
            runtime::block_on(Client::open(ns, local, remote, carrier)).map_err(network)?;
        self.close()?;
        self.client = Some(client);
        Ok(())
    }

    fn close(&mut self) -> DevResult<()> {
        if let Some(c) = self.client.take() {
            runtime::block_on(c.close());
        }
        Ok(())
    }

    fn as_rangefinder_2d(&mut self) -> Option<&mut dyn IRangefinder2D> {
        Some(self)
    }
}

impl Drop for Rangefinder2DNwcYarp {
    fn drop(&mut self) {
        let _ = self.close();
    }
}

impl IRangefinder2D for Rangefinder2DNwcYarp {
    fn get_raw_data(&mut self) -> DevResult<(Vec<f64>, f64)> {
        let c = self.client.as_ref().ok_or(DeviceError::NotOpen)?;
        let latest = c.latest.lock().unwrap_or_else(|e| e.into_inner());
        Ok(latest
            .as_ref()
            .map_or((Vec::new(), 0.0), |(s, t)| (s.scans.clone(), *t)))
    }
    fn get_device_status(&mut self) -> DevResult<LaserStatus> {
        let c = self.client.as_ref().ok_or(DeviceError::NotOpen)?;
        let latest = c.latest.lock().unwrap_or_else(|e| e.into_inner());
        Ok(latest
            .as_ref()
            .and_then(|(s, _)| status_of(s.status))
            .unwrap_or(LaserStatus::Timeout))
    }
    fn get_distance_range(&mut self) -> DevResult<(f64, f64)> {
        let v = self.floats("getDistanceRange_RPC", 2)?;
        Ok((v[0], v[1]))
    }
    fn set_distance_range(&mut self, min: f64, max: f64) -> DevResult<()> {
        self.call("setDistanceRange_RPC", &[min, max]).map(|_| ())
    }
    fn get_scan_limits(&mut self) -> DevResult<(f64, f64)> {
        let v = self.floats("getScanLimits_RPC", 2)?;
        Ok((v[0], v[1]))
    }
    fn set_scan_limits(&mut self, min: f64, max: f64) -> DevResult<()> {
        self.call("setScanLimits_RPC", &[min, max]).map(|_| ())
    }
    fn get_horizontal_resolution(&mut self) -> DevResult<f64> {
        Ok(self.floats("getHorizontalResolution_RPC", 1)?[0])
    }
    fn set_horizontal_resolution(&mut self, step: f64) -> DevResult<()> {
        self.call("setHorizontalResolution_RPC", &[step])
            .map(|_| ())
    }
    fn get_scan_rate(&mut self) -> DevResult<f64> {
        Ok(self.floats("getScanRate_RPC", 1)?[0])
    }
    fn set_scan_rate(&mut self, rate: f64) -> DevResult<()> {
        self.call("setScanRate_RPC", &[rate]).map(|_| ())
    }
    fn get_device_info(&mut self) -> DevResult<String> {
        let fields = self.call("getDeviceInfo_RPC", &[])?;
        fields
            .first()
            .and_then(Value::as_str)
            .map(str::to_string)
            .ok_or_else(|| DeviceError::failed(NAME, "getDeviceInfo_RPC: malformed reply"))
    }
}
