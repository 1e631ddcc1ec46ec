//! The ports of a YARP network client device (`*_nwc_yarp`): a stream port fed by the
//! server's streaming port, keeping the latest message with its envelope time, and an RPC
//! port connected to the server's RPC port, a thrift service. The counterpart of
//! `wrapper_ports` (NWS). The server's YARP generation, asked on opening (as 4.0's clients
//! check the protocol), says how calls are written; replies of either are read.

use crate::error::{DevResult, DeviceError};
use crate::runtime;
use crate::thrift::{self, ReturnValue};
use parking_lot::{Mutex, MutexGuard};
use std::sync::Arc;
use std::time::Duration;
use yarp_net::nameserver::NameClient;
use yarp_net::port::{Port, PortError};
use yarp_proto::tags::Generation;
use yarp_proto::{Bottle, Value};

/// How long an RPC call waits for the server's reply.
pub const RPC_TIMEOUT: Duration = Duration::from_secs(5);

/// The latest stream message and its envelope time (0 without an envelope).
type Latest<T> = Arc<Mutex<Option<(T, f64)>>>;

/// The port names of one client: `stream` receives from `remote_stream`, `rpc` calls
/// `remote_rpc`.
pub struct NwcNames {
    pub stream: String,
    pub remote_stream: String,
    /// Carrier of the stream connection.
    pub carrier: String,
    pub rpc: String,
    pub remote_rpc: String,
}

/// Open client ports (closed by [`NwcPorts::close`]).
pub struct NwcPorts<T> {
    device: &'static str,
    stream: Arc<Port>,
    task: tokio::task::JoinHandle<()>,
    rpc: Arc<Port>,
    /// The server's generation of YARP.
    generation: Generation,
    latest: Latest<T>,
}

/// How a client reads a stream message (a `from_bottle`); its error says what is wrong.
pub type Parse<T, E> = fn(&Bottle) -> Result<T, E>;

async fn receive<T, E: std::fmt::Display>(
    device: &'static str,
    port: Arc<Port>,
    latest: Latest<T>,
    parse: Parse<T, E>,
) {
    while let Some(msg) = port.read().await {
        let parsed = match msg.bottle() {
            Ok(b) => parse(&b).map_err(|e| e.to_string()),
            Err(e) => Err(e.to_string()),
        };
        match parsed {
            Ok(m) => {
                let t = msg.stamp.map_or(0.0, |s| s.time);
                *latest.lock() = Some((m, t));
            }
            Err(e) => tracing::warn!("{device}: ignoring a malformed stream message: {e}"),
        }
    }
}

/// Calls the server at the other end of `rpc` (blocking the caller, at most
/// [`RPC_TIMEOUT`]); a failure names `device` and the request.
pub fn call(device: &str, rpc: &Arc<Port>, cmd: Bottle) -> DevResult<Bottle> {
    call_within(device, rpc, cmd, RPC_TIMEOUT)
}

/// Sends `cmd` to `device`'s server on `rpc` and waits for its reply at most `timeout`
/// (blocking the caller): no reply is a `Timeout`, a broken connection `PeerLost`.
pub fn call_within(
    device: &str,
    rpc: &Arc<Port>,
    cmd: Bottle,
    timeout: Duration,
) -> DevResult<Bottle> {
    let port = rpc.clone();
    let command = cmd.to_string();
    within(
        device,
        &command,
        timeout,
        async move { port.rpc(&cmd).await },
    )
}

/// [`call_within`] for a call already encoded (a thrift call, as YARP 4.0's generated
/// code writes it); `command` names it in errors.
pub fn call_encoded_within(
    device: &str,
    rpc: &Arc<Port>,
    bytes: Vec<u8>,
    command: &str,
    timeout: Duration,
) -> DevResult<Bottle> {
    let port = rpc.clone();
    within(device, command, timeout, async move {
        port.rpc_encoded(bytes).await
    })
}

/// Waits for `call`'s reply at most `timeout` (blocking the caller).
fn within<R: Send + 'static>(
    device: &str,
    command: &str,
    timeout: Duration,
    call: impl std::future::Future<Output = Result<R, PortError>> + Send + 'static,
) -> DevResult<R> {
    // A stall of the runtime itself (its bound is longer) shows as this call's timeout.
    let outcome = runtime::block_on(async move { tokio::time::timeout(timeout, call).await })
        .ok()
        .and_then(Result::ok);
    match outcome {
        Some(Ok(reply)) => Ok(reply),
        Some(Err(e)) => {
            tracing::warn!("{device}: `{command}`: {e}");
            Err(DeviceError::PeerLost {
                device: device.to_string(),
                reason: e.to_string(),
            })
        }
        None => {
            tracing::warn!("{device}: `{command}`: no reply within {timeout:?}");
            Err(DeviceError::Timeout {
                device: device.to_string(),
                command: command.to_string(),
                after: timeout,
            })
        }
    }
}

/// The server's generation, from its `getRemoteProtocolVersion` (which both answer);
/// a protocol other than ours is refused, as 4.0's clients refuse it.
async fn server_generation(rpc: &Port) -> Result<Generation, String> {
    let asked = tokio::time::timeout(
        RPC_TIMEOUT,
        rpc.rpc_encoded(thrift::protocol_version_request()),
    )
    .await
    .map_err(|_| {
        format!(
            "no reply to {} within {RPC_TIMEOUT:?}",
            thrift::GET_PROTOCOL_VERSION
        )
    })?;
    let bytes = match asked {
        Err(PortError::BadReply { bytes, .. }) => bytes,
        Ok(b) => b.encode(),
        Err(e) => return Err(e.to_string()),
    };
    match thrift::protocol_version_of(&bytes) {
        Some((thrift::PROTOCOL, version)) => Ok(thrift::generation_of_version(version)),
        Some((protocol, version)) => Err(format!(
            "invalid communication protocol: the server (YARP {version:?}) speaks {protocol}, this client {}",
            thrift::PROTOCOL
        )),
        None => Err(format!(
            "not a thrift service: {} answered {bytes:?}",
            thrift::GET_PROTOCOL_VERSION
        )),
    }
}

async fn close_port(port: Arc<Port>) {
    if let Ok(p) = Arc::try_unwrap(port) {
        p.close().await;
    }
}

impl<T: Send + 'static> NwcPorts<T> {
    /// Opens both ports and connects them; what failed, with the port names, otherwise.
    pub async fn open<E: std::fmt::Display + 'static>(
        device: &'static str,
        ns: NameClient,
        names: NwcNames,
        parse: Parse<T, E>,
    ) -> Result<NwcPorts<T>, String> {
        let NwcNames {
            stream: local,
            remote_stream,
            carrier,
            rpc: rpc_name,
            remote_rpc,
        } = names;
        let stream = Arc::new(
            Port::open(&local, ns.clone())
                .await
                .map_err(|e| format!("{local}: {e}"))?,
        );
        let connected =
            match yarp_net::network::connect(&ns, &remote_stream, &local, Some(&carrier)).await {
                Ok((true, _)) => Ok(()),
                Ok((false, msg)) => Err(msg),
                Err(e) => Err(e.to_string()),
            };
        if let Err(e) = connected {
            close_port(stream).await;
            return Err(format!("connecting {remote_stream} to {local}: {e}"));
        }
        let rpc = match Port::open(&rpc_name, ns).await {
            Ok(p) => p,
            Err(e) => {
                close_port(stream).await;
                return Err(format!("{rpc_name}: {e}"));
            }
        };
        if let Err(e) = rpc.connect(&remote_rpc, None).await {
            rpc.close().await;
            close_port(stream).await;
            return Err(format!("connecting {rpc_name} to {remote_rpc}: {e}"));
        }
        let generation = match server_generation(&rpc).await {
            Ok(g) => g,
            Err(e) => {
                rpc.close().await;
                close_port(stream).await;
                return Err(format!("{remote_rpc}: {e}"));
            }
        };
        let latest = Latest::default();
        let task = tokio::spawn(receive(device, stream.clone(), latest.clone(), parse));
        Ok(NwcPorts {
            device,
            stream,
            task,
            rpc: Arc::new(rpc),
            generation,
            latest,
        })
    }

    /// The latest stream message, if one came.
    pub fn latest(&self) -> MutexGuard<'_, Option<(T, f64)>> {
        self.latest.lock()
    }

    /// Calls a thrift method of the server whose reply is a `yarp::dev::ReturnValue`
    /// followed by the `return_*` struct's fields: those fields when the code is OK;
    /// `Unsupported(unsupported)` when the server does not implement it, `NotReady` when
    /// it is not ready, `Refused` when the method failed there; a reply that is no
    /// `ReturnValue` is a failure naming the request and the reply.
    pub fn call_returning(&self, cmd: Bottle, unsupported: &'static str) -> DevResult<Vec<Value>> {
        let command = cmd.to_string();
        let port = self.rpc.clone();
        let bytes = cmd.encode_as(self.generation);
        let reply = within(self.device, &command, RPC_TIMEOUT, async move {
            match port.rpc_encoded(bytes).await {
                Ok(b) => Ok(Ok(b)),
                // a setter's reply is its ReturnValue alone, in 3.12 no Bottle
                Err(PortError::BadReply { error, bytes }) => match ReturnValue::from_bare(&bytes) {
                    Some(r) => Ok(Err(r)),
                    None => Err(PortError::BadReply { error, bytes }),
                },
                Err(e) => Err(e),
            }
        })?;
        let parsed = match &reply {
            Err(bare) => Some((*bare, Vec::new())),
            Ok(b) => thrift::parse_reply(b),
        };
        match parsed {
            Some((ReturnValue::Ok, fields)) => Ok(fields),
            Some((ReturnValue::NotImplemented, _)) => Err(DeviceError::Unsupported(unsupported)),
            Some((ReturnValue::NotReady, _)) => {
                Err(DeviceError::NotReady("the server is not ready"))
            }
            Some(_) => Err(DeviceError::Refused {
                device: self.device.to_string(),
                command,
            }),
            None => Err(DeviceError::failed(
                self.device,
                format!("{command} answered {reply:?}"),
            )),
        }
    }

    /// Calls the server with a call already encoded (a thrift call as C++'s generated code
    /// writes it); its reply, whatever it holds. `command` names it in errors.
    pub fn call_encoded(&self, bytes: Vec<u8>, command: &str) -> DevResult<Bottle> {
        call_encoded_within(self.device, &self.rpc, bytes, command, RPC_TIMEOUT)
    }

    /// Opens the ports from a device's `open` (blocking): a failure is a `BadParam` on
    /// `remote` naming what should be running there (`expected`).
    pub fn open_for_device<E: std::fmt::Display + 'static>(
        device: &'static str,
        expected: &'static str,
        names: NwcNames,
        parse: Parse<T, E>,
    ) -> DevResult<NwcPorts<T>> {
        let network = |got: String| DeviceError::BadParam {
            device: device.into(),
            param: "remote".into(),
            expected,
            got,
        };
        let ns = yarp_net::network::name_client().map_err(|e| network(e.to_string()))?;
        runtime::block_on_result(Self::open(device, ns, names, parse)).map_err(network)
    }

    /// Closes the ports from a device's `close` (blocking).
    pub fn close_for_device(self) {
        runtime::block_on_logged("nwc_ports: closing", self.close());
    }

    pub async fn close(self) {
        self.task.abort();
        let _ = self.task.await;
        close_port(self.stream).await;
        close_port(self.rpc).await;
    }
}

/// A client device's ports while it is open: opening again replaces them; closing or
/// dropping the device closes them.
pub struct OpenPorts<T: Send + 'static>(Option<NwcPorts<T>>);

impl<T: Send + 'static> Default for OpenPorts<T> {
    fn default() -> Self {
        Self(None)
    }
}

impl<T: Send + 'static> OpenPorts<T> {
    /// [`NwcPorts::open_for_device`], in place of the ports open now.
    pub fn open<E: std::fmt::Display + 'static>(
        &mut self,
        device: &'static str,
        expected: &'static str,
        names: NwcNames,
        parse: Parse<T, E>,
    ) -> DevResult<()> {
        let ports = NwcPorts::open_for_device(device, expected, names, parse)?;
        self.close();
        self.0 = Some(ports);
        Ok(())
    }

    pub fn get(&self) -> DevResult<&NwcPorts<T>> {
        self.0.as_ref().ok_or(DeviceError::NotOpen)
    }

    pub fn close(&mut self) {
        if let Some(p) = self.0.take() {
            p.close_for_device();
        }
    }
}

impl<T: Send + 'static> Drop for OpenPorts<T> {
    fn drop(&mut self) {
        self.close();
    }
}
