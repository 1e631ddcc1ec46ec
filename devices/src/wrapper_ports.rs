//! The ports of a YARP network wrapper (an `*_nws_yarp` device): its stream ports and its
//! RPC port open together with the device (one refused closes those already open), a
//! task answers the RPC port with whatever device is attached at the time, and all close
//! together. Shared by `rangefinder2D_nws_yarp`, `rgbdSensor_nws_yarp`,
//! `odometry2D_nws_yarp` and `battery_nws_yarp`. Each request is answered in its client's
//! YARP generation, and [`WrapperPorts::peers`] tells the stream tasks their readers'.

use crate::driver::{DeviceDriver, SharedDevice};
use crate::error::{DevResult, DeviceError};
use crate::runtime;
use parking_lot::Mutex;
use std::sync::Arc;
use yarp_net::peer_generation::PeerGenerations;
use yarp_net::port::Port;
use yarp_proto::tags::Generation;
use yarp_proto::Bottle;

/// The device a wrapper serves, shared with its RPC task (`None` while detached).
pub type Slot = Arc<Mutex<Option<SharedDevice>>>;

/// The task a wrapper streams its attached device with; stopping it waits until it has.
#[derive(Default)]
pub struct StreamTask(Option<tokio::task::JoinHandle<()>>);

impl StreamTask {
    /// Starts `stream` in place of the one running.
    pub fn start(&mut self, stream: impl std::future::Future<Output = ()> + Send + 'static) {
        self.stop();
        self.0 = Some(runtime::handle().spawn(stream));
    }

    pub fn stop(&mut self) {
        if let Some(t) = self.0.take() {
            t.abort();
            runtime::block_on_logged("nws: closing", async move {
                let _ = t.await;
            });
        }
    }
}

/// A streaming wrapper's state: its ports while open, the device it serves while
/// attached, and the task streaming that device.
#[derive(Default)]
pub struct Serving {
    slot: Slot,
    ports: Option<WrapperPorts>,
    stream: StreamTask,
}

impl Serving {
    /// [`WrapperPorts::open`], answering with the device attached at the time.
    pub fn open(
        &mut self,
        wrapper: &'static str,
        streams: Vec<String>,
        rpc: String,
        answer: Answer,
        client_port: ClientPort,
    ) -> DevResult<()> {
        let ports = WrapperPorts::open(
            wrapper,
            streams,
            rpc,
            self.slot.clone(),
            answer,
            client_port,
        )?;
        self.ports = Some(ports);
        Ok(())
    }

    /// Serves `device` once `check` accepts it, streaming it with the task `stream` makes
    /// from the ports; the device served before is detached first.
    pub fn attach<F>(
        &mut self,
        device: SharedDevice,
        check: impl FnOnce(&mut dyn DeviceDriver) -> DevResult<()>,
        stream: impl FnOnce(&WrapperPorts, SharedDevice) -> F,
    ) -> DevResult<()>
    where
        F: std::future::Future<Output = ()> + Send + 'static,
    {
        self.detach();
        let Some(ports) = &self.ports else {
            return Err(DeviceError::NotOpen);
        };
        check(device.lock().device())?;
        *self.slot.lock() = Some(device.clone());
        self.stream.start(stream(ports, device));
        Ok(())
    }

    pub fn detach(&mut self) {
        self.stream.stop();
        *self.slot.lock() = None;
    }

    pub fn close(&mut self) {
        self.detach();
        if let Some(p) = self.ports.take() {
            p.close();
        }
    }
}

/// A stream's read errors, logged once per streak of failures rather than every period.
#[derive(Default)]
pub struct FailureStreak(bool);

impl FailureStreak {
    pub fn passed(&mut self) {
        self.0 = false;
    }

    /// `message` is logged if the last read passed.
    pub fn failed(&mut self, message: impl FnOnce() -> String) {
        if !self.0 {
            tracing::error!("{}", message());
        }
        self.0 = true;
    }
}

/// A reply as the wrapper's protocol builds it.
pub enum Reply {
    Bottle(Bottle),
    /// Already-encoded bytes (thrift replies with element-tagged lists).
    Encoded(Vec<u8>),
}

/// Answers one request: the decoded command (empty when undecodable), the attached
/// device, if any, and the generation of YARP the client runs.
pub type Answer = fn(&Bottle, Option<&mut dyn DeviceDriver>, Generation) -> Reply;

/// The port that tells a client's generation, from the name of its RPC port: a port of
/// the same client other than that one, whose C++ `PortCore` is locked for as long as
/// the call waits for our reply (its admin would not answer before we do). `None`: do
/// not ask (the protocol is the same in both generations, or the client is unknown).
pub type ClientPort = fn(&str) -> Option<String>;

pub struct WrapperPorts {
    /// The stream ports, in the order given to [`WrapperPorts::open`].
    pub streams: Vec<Arc<Port>>,
    /// The generations of the clients and readers.
    pub peers: PeerGenerations,
    rpc: Arc<Port>,
    rpc_task: tokio::task::JoinHandle<()>,
}

impl WrapperPorts {
    /// Opens `streams` and then `rpc` (registered with the name server) and starts
    /// answering `rpc` with `answer`. The error names the port that could not be opened.
    pub fn open(
        wrapper: &'static str,
        streams: Vec<String>,
        rpc: String,
        slot: Slot,
        answer: Answer,
        client_port: ClientPort,
    ) -> DevResult<WrapperPorts> {
        let refused = move |why: String| DeviceError::BadParam {
            device: wrapper.into(),
            param: "name".into(),
            expected: "port names that can be registered",
            got: why,
        };
        let ns =
            yarp_net::network::name_client().map_err(|e| refused(format!("name server: {e}")))?;
        runtime::block_on_result(async move {
            let mut opened = Vec::new();
            for name in streams.iter().chain(std::iter::once(&rpc)) {
                match Port::open(name, ns.clone()).await {
                    Ok(p) => opened.push(Arc::new(p)),
                    Err(e) => {
                        for p in opened {
                            close_port(p).await;
                        }
                        return Err(refused(format!("{name}: {e}")));
                    }
                }
            }
            let rpc = opened.pop().expect("the rpc port was opened last");
            let peers = PeerGenerations::new(ns);
            let rpc_task = tokio::spawn(serve_rpc(
                wrapper,
                rpc.clone(),
                slot,
                (answer, client_port),
                peers.clone(),
            ));
            Ok(WrapperPorts {
                streams: opened,
                peers,
                rpc,
                rpc_task,
            })
        })
    }

    /// Stops answering and closes every port (unregistering them).
    pub fn close(self) {
        runtime::block_on_logged("wrapper_ports: closing", async move {
            self.rpc_task.abort();
            let _ = self.rpc_task.await;
            close_port(self.rpc).await;
            for p in self.streams {
                close_port(p).await;
            }
        });
    }
}

async fn serve_rpc(
    wrapper: &'static str,
    port: Arc<Port>,
    slot: Slot,
    (answer, client_port): (Answer, ClientPort),
    peers: PeerGenerations,
) {
    while let Some(mut msg) = port.read().await {
        let cmd = msg.bottle().unwrap_or_else(|e| {
            tracing::warn!("{wrapper}: undecodable request from {}: {e}", msg.from);
            Bottle::new()
        });
        // a request with 4.0's float tags says it; most hold none and ask the sender
        let generation = match (msg.generation(), client_port(&msg.from)) {
            (Generation::V4, _) => Generation::V4,
            (Generation::V3, Some(port)) => peers.of(&port).await,
            (Generation::V3, None) => Generation::V3,
        };
        let device = slot.lock().clone();
        let reply = match device {
            // the device may itself wait on the network: not on a held worker
            Some(d) => runtime::device_call(|| answer(&cmd, Some(d.lock().device()), generation)),
            None => answer(&cmd, None, generation),
        };
        if msg.wants_reply() {
            match reply {
                Reply::Bottle(b) => msg.reply(b),
                Reply::Encoded(bytes) => msg.reply_encoded(bytes),
            }
        }
    }
}

/// Asks the generation of those of a port's readers (`outputs`) that `readers` does
/// not know yet, from a plain thread (a periodic publisher's); nothing to ask, as on
/// every period but a new reader's first, costs no trip into the runtime.
pub fn learn_readers(outputs: Vec<String>, readers: &PeerGenerations) {
    if readers.knows_all(&outputs) {
        return;
    }
    let readers = readers.clone();
    runtime::block_on_logged("wrapper_ports: closing", async move {
        readers.learn(&outputs).await
    });
}

/// Closes a port once the tasks that shared it are gone.
async fn close_port(port: Arc<Port>) {
    if let Ok(p) = Arc::try_unwrap(port) {
        p.close().await;
    }
}
