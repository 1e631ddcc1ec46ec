//! What the network clients of icub-main's two controller modules share
//! (`cartesiancontrollerclient`, `gazecontrollerclient`): their ports opened and the RPC
//! connected first, the server's `server_version` checked, the streams connected with the
//! client's carrier, calls answered `[ack] ...`, the contexts this client stored (only
//! those may be restored, and they are deleted on closing, as C++), the `events:o`
//! stream, and closing.

use parking_lot::Mutex;
use std::collections::BTreeSet;
use std::future::Future;
use std::sync::Arc;
use std::time::Duration;
use yarp_devices::cartesian_control::CartesianEvent;
use yarp_devices::error::{DevResult, DeviceError};
use yarp_devices::{nwc_ports, runtime};
use yarp_net::port::Port;
use yarp_proto::{Bottle, Value};

/// How long a call waits for the module (a sync go or look waits for the motion too).
const RPC_TIMEOUT: Duration = Duration::from_secs(10);

/// How long closing waits for the module to delete this client's contexts.
const DELETE_TIMEOUT: Duration = Duration::from_secs(1);

/// An open client: its ports (the RPC one first), the tasks reading its streams, and
/// `streams`, what the client keeps of them besides the events.
pub(crate) struct ModuleLink<S> {
    device: &'static str,
    pub remote: String,
    ports: Vec<Arc<Port>>,
    tasks: Vec<tokio::task::JoinHandle<()>>,
    received: Arc<Mutex<Vec<CartesianEvent>>>,
    pub contexts: BTreeSet<i32>,
    /// Age after which a stream counts as lost.
    pub timeout: Duration,
    pub streams: S,
}

impl<S> ModuleLink<S> {
    /// Opens `<local>/<suffix>` for every suffix and connects the first, the RPC port, to
    /// `remote_rpc`; what failed is a `BadParam` on `remote` naming what should run there
    /// (`expected`).
    pub fn open(
        device: &'static str,
        expected: &'static str,
        (local, remote): (&str, &str),
        suffixes: &[&str],
        remote_rpc: &str,
        timeout: Duration,
        streams: S,
    ) -> DevResult<Self> {
        let refused = |why: String| DeviceError::BadParam {
            device: device.into(),
            param: "remote".into(),
            expected,
            got: why,
        };
        let ns = yarp_net::network::name_client().map_err(|e| refused(e.to_string()))?;
        let names: Vec<String> = suffixes.iter().map(|s| format!("{local}/{s}")).collect();
        let remote_rpc = format!("{remote}/{remote_rpc}");
        let ports = runtime::block_on_result(async move {
            let mut ports = Vec::new();
            for name in names {
                match Port::open(&name, ns.clone()).await {
                    Ok(port) => ports.push(Arc::new(port)),
                    Err(e) => {
                        close_all(ports).await;
                        return Err(format!("{name}: {e}"));
                    }
                }
            }
            if let Err(e) = ports[0].connect(&remote_rpc, None).await {
                close_all(ports).await;
                return Err(format!("cannot connect to {remote_rpc}: {e}"));
            }
            Ok(ports)
        })
        .map_err(refused)?;
        Ok(Self {
            device,
            remote: remote.to_string(),
            ports,
            tasks: Vec::new(),
            received: Arc::default(),
            contexts: BTreeSet::new(),
            timeout,
            streams,
        })
    }

    /// Port `i`, in the order of the suffixes it was opened with.
    pub fn port(&self, i: usize) -> Arc<Port> {
        self.ports[i].clone()
    }

    /// Runs `reader` (a stream's reader) until the client closes.
    pub fn spawn(&mut self, reader: impl Future<Output = ()> + Send + 'static) {
        self.tasks.push(runtime::handle().spawn(reader));
    }

    /// Collects the events port `i` receives (the module's `events:o`).
    pub fn read_events(&mut self, i: usize) {
        let (port, received) = (self.port(i), self.received.clone());
        self.spawn(read_events(port, received));
    }

    /// The events received since the last call.
    pub fn take_events(&self) -> Vec<CartesianEvent> {
        std::mem::take(&mut *self.received.lock())
    }

    pub fn call_within(&self, cmd: Bottle, timeout: Duration) -> DevResult<Bottle> {
        nwc_ports::call_within(&self.remote, &self.ports[0], cmd, timeout)
    }

    /// A call whose reply must start with `[ack]`.
    pub fn ack(&self, cmd: Bottle) -> DevResult<Bottle> {
        let text = cmd.to_string();
        let reply = self.call_within(cmd, RPC_TIMEOUT)?;
        if crate::protocol::is_ack(&reply) {
            Ok(reply)
        } else {
            Err(DeviceError::failed(
                self.device,
                format!("`{text}` answered `{reply}`"),
            ))
        }
    }

    /// C++'s check of the module's `get info` reply: a `server_version` other than
    /// `ours` fails; none is only warned about.
    pub fn check_version(&self, info: &Bottle, ours: &str) -> DevResult<()> {
        let version = info
            .get(1)
            .and_then(Value::as_list)
            .and_then(|l| l.find("server_version"))
            .and_then(|v| v.as_str().map(str::to_string));
        match version {
            Some(v) if v != ours => Err(DeviceError::failed(
                self.device,
                format!("server version {v} not compatible with this client's {ours}"),
            )),
            None => {
                let (device, remote) = (self.device, &self.remote);
                tracing::warn!("{device}: {remote} did not say its server_version");
                Ok(())
            }
            _ => Ok(()),
        }
    }

    /// Connects with `carrier` each of our output ports `outs` (by index) to the module's
    /// input of that suffix, and the module's outputs `ins` to each of our inputs.
    pub fn connect_streams(
        &self,
        carrier: &str,
        outs: &[(usize, &str)],
        ins: &[(&str, usize)],
    ) -> DevResult<()> {
        let outs: Vec<_> = outs
            .iter()
            .map(|(i, to)| (self.port(*i), format!("{}/{to}", self.remote)))
            .collect();
        let ins: Vec<_> = ins
            .iter()
            .map(|(from, i)| {
                (
                    format!("{}/{from}", self.remote),
                    self.ports[*i].name().to_string(),
                )
            })
            .collect();
        let carrier = carrier.to_string();
        runtime::block_on_result(async move {
            let ns = yarp_net::network::name_client().map_err(|e| e.to_string())?;
            for (port, to) in outs {
                port.connect(&to, Some(&carrier))
                    .await
                    .map_err(|e| format!("{to}: {e}"))?;
            }
            for (from, to) in ins {
                let (ok, why) = yarp_net::network::connect(&ns, &from, &to, Some(&carrier))
                    .await
                    .map_err(|e| e.to_string())?;
                if !ok {
                    return Err(format!("{from} -> {to}: {why}"));
                }
            }
            Ok::<_, String>(())
        })
        .map_err(|e| DeviceError::failed(self.device, e))
    }

    /// Context `id` may be restored by this client: the module's first (0) or one this
    /// client stored, as C++.
    pub fn check_context(&self, id: i32) -> DevResult<()> {
        if id != 0 && !self.contexts.contains(&id) {
            return Err(self.not_ours(id));
        }
        Ok(())
    }

    /// Forgets context `id`, which this client must have stored.
    pub fn forget_context(&mut self, id: i32) -> DevResult<()> {
        if !self.contexts.remove(&id) {
            return Err(self.not_ours(id));
        }
        Ok(())
    }

    fn not_ours(&self, id: i32) -> DeviceError {
        DeviceError::failed(self.device, format!("context {id} is not this client's"))
    }

    /// Closes the client: `delete` (the module's delete command for this client's
    /// contexts, if any is to be sent) first, then the readers and the ports.
    pub fn close(self, delete: Option<Bottle>) {
        if let Some(cmd) = delete {
            let _ = self.call_within(cmd, DELETE_TIMEOUT);
        }
        for t in &self.tasks {
            t.abort();
        }
        let (ports, tasks) = (self.ports, self.tasks);
        let what = format!("{}: closing", self.device);
        runtime::block_on_logged(&what, async move {
            for t in tasks {
                let _ = t.await;
            }
            close_all(ports).await;
        });
    }
}

/// Closes ports no task holds any more.
async fn close_all(ports: Vec<Arc<Port>>) {
    for p in ports {
        if let Ok(p) = Arc::try_unwrap(p) {
            p.close().await;
        }
    }
}

/// Collects an `events:o` stream (the Cartesian and gaze servers' alike).
async fn read_events(port: Arc<Port>, received: Arc<Mutex<Vec<CartesianEvent>>>) {
    while let Some(msg) = port.read().await {
        let Ok(b) = msg.bottle() else { continue };
        let Some(kind) = b.get(0).and_then(Value::as_str).map(str::to_string) else {
            continue;
        };
        let checkpoint = (kind == "motion-ongoing")
            .then(|| b.get(2).and_then(Value::as_f64))
            .flatten();
        let mut q = received.lock();
        q.push(CartesianEvent {
            kind,
            time: b.get(1).and_then(Value::as_f64).unwrap_or(0.0),
            checkpoint,
        });
        // nobody reading: keep the latest thousand
        if q.len() > 1000 {
            q.remove(0);
        }
    }
}
