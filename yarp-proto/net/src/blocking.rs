//! A blocking facade for simple programs that do not want async code: the same ports,
//! driven by one process-wide tokio runtime (multi-thread, 2 workers).
//!
//! ```no_run
//! use yarp_net::blocking::{Network, Port};
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! let net = Network::from_conf()?;
//! let out = Port::open(&net, "/hello/out")?;
//! net.connect("/hello/out", "/read", None)?;
//! out.write(&yarp_proto::bottle!["hello", 1]);
//! # Ok(()) }
//! ```
//!
//! Calls block the current thread. Called from inside an async runtime they run on a
//! helper thread instead of panicking, but async code should use the async types.

use crate::buffered::{self, Message};
use crate::nameserver::NameClient;
use crate::network::{self, NetworkError};
use crate::port::{self, Incoming, PortError};
use parking_lot::Mutex;
use std::future::Future;
use std::net::SocketAddr;
use std::sync::OnceLock;
use std::time::Duration;
use tokio::runtime::{Builder, Handle, Runtime};
use tokio::time::timeout;
use yarp_proto::{Bottle, Contact, Stamp};

/// How long closing (explicitly or on drop) may take before it is abandoned.
pub const CLOSE_TIMEOUT: Duration = Duration::from_secs(3);

#[derive(Debug, thiserror::Error)]
pub enum Error {
    #[error("cannot start the tokio runtime: {0}")]
    Runtime(std::io::Error),
    #[error(transparent)]
    Network(#[from] NetworkError),
    #[error(transparent)]
    Port(#[from] PortError),
    #[error("no answer within {0:?}")]
    Timeout(Duration),
}

// One runtime for the whole process, never dropped: dropping a runtime from async context
// panics, and ports outlive the `Network` value that opened them.
static RUNTIME: OnceLock<Runtime> = OnceLock::new();
static RUNTIME_INIT: Mutex<()> = Mutex::new(());

fn runtime() -> Result<&'static Runtime, Error> {
    if let Some(rt) = RUNTIME.get() {
        return Ok(rt);
    }
    let _init = RUNTIME_INIT.lock();
    if let Some(rt) = RUNTIME.get() {
        return Ok(rt);
    }
    let rt = Builder::new_multi_thread()
        .worker_threads(2)
        .thread_name("yarp-net")
        .enable_all()
        .build()
        .map_err(Error::Runtime)?;
    Ok(RUNTIME.get_or_init(|| rt))
}

/// Runs `fut` to completion on `rt`. Inside a runtime `block_on` would panic, so there
/// it runs on a scoped helper thread.
fn block<F>(rt: &'static Runtime, fut: F) -> F::Output
where
    F: Future + Send,
    F::Output: Send,
{
    if Handle::try_current().is_err() {
        return rt.block_on(fut);
    }
    std::thread::scope(|s| match s.spawn(|| rt.block_on(fut)).join() {
        Ok(v) => v,
        Err(panic) => std::panic::resume_unwind(panic),
    })
}

/// `close()` (blocking, bounded) and a `Drop` that closes in the background, for a
/// blocking wrapper whose `inner: Option<_>` has an async `close()`.
macro_rules! closes_when_dropped {
    ($ty:ident, $doc:literal) => {
        impl $ty {
            #[doc = $doc]
            pub fn close(mut self) {
                if let Some(inner) = self.inner.take() {
                    block(self.rt, async move {
                        let _ = timeout(CLOSE_TIMEOUT, inner.close()).await;
                    });
                }
            }
        }

        impl Drop for $ty {
            fn drop(&mut self) {
                if let Some(inner) = self.inner.take() {
                    close_on_drop(self.rt, inner.close());
                }
            }
        }
    };
}

/// What the blocking ports share: opening through a [`Network`], the port underneath,
/// its name and contact, connecting and disconnecting.
macro_rules! port_basics {
    ($ty:ident, $inner:path) => {
        impl $ty {
            pub fn open(net: &Network, name: &str) -> Result<$ty, PortError> {
                let inner = block(net.rt, <$inner>::open(name, net.ns.clone()))?;
                Ok($ty {
                    inner: Some(inner),
                    rt: net.rt,
                })
            }

            fn port(&self) -> &$inner {
                // only `close` and `drop` take it, and both consume the value
                self.inner.as_ref().expect("port used after close")
            }

            pub fn name(&self) -> &str {
                self.port().name()
            }

            pub fn contact(&self) -> &Contact {
                self.port().contact()
            }

            pub fn connect(&self, target: &str, carrier: Option<&str>) -> Result<(), PortError> {
                block(self.rt, self.port().connect(target, carrier))
            }

            pub fn disconnect(&self, target: &str) -> bool {
                self.port().disconnect(target)
            }
        }
    };
}

/// Closes in the background without blocking: from a runtime thread we must not wait,
/// elsewhere we wait (bounded) so that the port is unregistered before the program ends.
fn close_on_drop<F>(rt: &'static Runtime, close: F)
where
    F: Future<Output = ()> + Send + 'static,
{
    if Handle::try_current().is_ok() {
        rt.spawn(async move {
            let _ = timeout(CLOSE_TIMEOUT, close).await;
        });
    } else {
        rt.block_on(async move {
            let _ = timeout(CLOSE_TIMEOUT, close).await;
        });
    }
}

/// Access to a name server, and the runtime every blocking port runs on.
#[derive(Debug, Clone)]
pub struct Network {
    rt: &'static Runtime,
    ns: NameClient,
}

impl Network {
    /// Uses the name server named by `yarp.conf`, as C++ `yarp::os::Network`.
    pub fn from_conf() -> Result<Network, Error> {
        Network::with_client(network::name_client()?)
    }

    /// Uses the name server at `addr`.
    pub fn with_name_server(addr: SocketAddr) -> Result<Network, Error> {
        Network::with_client(NameClient::new(addr))
    }

    pub fn with_client(ns: NameClient) -> Result<Network, Error> {
        Ok(Network { rt: runtime()?, ns })
    }

    pub fn name_client(&self) -> &NameClient {
        &self.ns
    }

    /// The runtime the ports run on, for spawning work next to them.
    pub fn handle(&self) -> &Handle {
        self.rt.handle()
    }

    /// Runs any async operation of this crate to completion.
    pub fn block_on<F>(&self, fut: F) -> F::Output
    where
        F: Future + Send,
        F::Output: Send,
    {
        block(self.rt, fut)
    }

    /// Connects `from` to `to` as `yarp connect`: (accepted, the port's message).
    pub fn connect(
        &self,
        from: &str,
        to: &str,
        carrier: Option<&str>,
    ) -> Result<(bool, String), NetworkError> {
        block(self.rt, network::connect(&self.ns, from, to, carrier))
    }

    /// Removes the connection `from` -> `to`, as `yarp disconnect`.
    pub fn disconnect(&self, from: &str, to: &str) -> Result<(bool, String), NetworkError> {
        block(self.rt, network::disconnect(&self.ns, from, to))
    }

    pub fn is_connected(&self, from: &str, to: &str) -> Result<bool, NetworkError> {
        block(self.rt, network::is_connected(&self.ns, from, to))
    }

    /// Whether a port is registered and reachable, as `yarp exists`.
    pub fn exists(&self, port: &str) -> Result<bool, NetworkError> {
        block(self.rt, network::exists(&self.ns, port))
    }
}

/// A blocking [`port::Port`]. Dropping it closes it (best effort, bounded).
pub struct Port {
    inner: Option<port::Port>,
    rt: &'static Runtime,
}

port_basics!(Port, port::Port);

impl Port {
    pub fn outputs(&self) -> Vec<String> {
        self.port().outputs()
    }

    pub fn inputs(&self) -> Vec<String> {
        self.port().inputs()
    }

    /// Sends to every output; returns how many took it.
    pub fn write(&self, b: &Bottle) -> usize {
        block(self.rt, self.port().write(b))
    }

    pub fn write_stamped(&self, b: &Bottle, stamp: Stamp) -> usize {
        block(self.rt, self.port().write_stamped(b, stamp))
    }

    /// Waits for the next message, without limit.
    pub fn read(&self) -> Option<Incoming> {
        block(self.rt, self.port().read())
    }

    /// Waits at most `d` for the next message.
    pub fn read_timeout(&self, d: Duration) -> Option<Incoming> {
        let p = self.port();
        block(
            self.rt,
            async move { timeout(d, p.read()).await.ok().flatten() },
        )
    }

    /// Sends `b` on the first output and waits for the reply, without limit.
    pub fn rpc(&self, b: &Bottle) -> Result<Bottle, PortError> {
        block(self.rt, self.port().rpc(b))
    }

    /// As `rpc`, giving up after `d` (a late reply is then discarded by the connection).
    pub fn rpc_timeout(&self, b: &Bottle, d: Duration) -> Result<Bottle, Error> {
        let p = self.port();
        block(self.rt, async move {
            match timeout(d, p.rpc(b)).await {
                Ok(r) => r.map_err(Error::from),
                Err(_) => Err(Error::Timeout(d)),
            }
        })
    }
}

closes_when_dropped!(
    Port,
    "Unregisters and closes every connection (bounded by [`CLOSE_TIMEOUT`])."
);

/// A blocking [`buffered::BufferedPort`]. Dropping it closes it (best effort, bounded).
pub struct BufferedPort {
    inner: Option<buffered::BufferedPort>,
    rt: &'static Runtime,
}

port_basics!(BufferedPort, buffered::BufferedPort);

impl BufferedPort {
    pub fn set_strict(&self, strict: bool) {
        self.port().set_strict(strict)
    }

    pub fn set_capacity(&self, n: usize) {
        self.port().set_capacity(n)
    }

    pub fn set_auto_envelope(&self, on: bool) {
        self.port().set_auto_envelope(on)
    }

    /// Waits for a message not read before, without limit.
    pub fn read(&self) -> Option<Message> {
        block(self.rt, self.port().read())
    }

    /// Waits at most `d` for a message not read before.
    pub fn read_timeout(&self, d: Duration) -> Option<Message> {
        let p = self.port();
        block(
            self.rt,
            async move { timeout(d, p.read()).await.ok().flatten() },
        )
    }

    pub fn try_read(&self) -> Option<Message> {
        self.port().try_read()
    }

    pub fn pending_count(&self) -> usize {
        self.port().pending_count()
    }

    pub fn dropped_count(&self) -> u64 {
        self.port().dropped_count()
    }

    pub fn last_stamp(&self) -> Option<Stamp> {
        self.port().last_stamp()
    }

    /// Hands every message to `f` on a runtime thread (C++ `useCallback`).
    pub fn on_read<F>(&self, f: F)
    where
        F: FnMut(Message) + Send + 'static,
    {
        self.port().on_read(f)
    }

    /// Queues without waiting; replaces a queued message that has not left yet.
    pub fn write(&self, b: &Bottle) -> bool {
        self.port().write(b)
    }

    pub fn write_stamped(&self, b: &Bottle, stamp: Stamp) -> bool {
        self.port().write_stamped(b, stamp)
    }

    /// Sends after anything queued; returns how many outputs took it.
    pub fn write_strict(&self, b: &Bottle) -> usize {
        block(self.rt, self.port().write_strict(b))
    }

    /// Waits until the queued message (if any) has been handed to the connections.
    pub fn flush(&self) {
        block(self.rt, self.port().flush())
    }

    pub fn rpc(&self, b: &Bottle) -> Result<Bottle, PortError> {
        block(self.rt, self.port().rpc(b))
    }
}

closes_when_dropped!(
    BufferedPort,
    "Sends what is queued, unregisters and closes (bounded by [`CLOSE_TIMEOUT`])."
);

/// A blocking [`buffered::RpcServer`].
pub struct RpcServer {
    inner: Option<buffered::RpcServer>,
    rt: &'static Runtime,
}

impl RpcServer {
    pub fn open(net: &Network, name: &str) -> Result<RpcServer, PortError> {
        let inner = block(net.rt, buffered::RpcServer::open(name, net.ns.clone()))?;
        Ok(RpcServer {
            inner: Some(inner),
            rt: net.rt,
        })
    }

    fn server(&self) -> &buffered::RpcServer {
        // only `close` and `drop` take it, and both consume the value
        self.inner.as_ref().expect("port used after close")
    }

    pub fn name(&self) -> &str {
        self.server().name()
    }

    /// Waits for the next request, without limit; answer with `Message::reply`.
    pub fn read(&self) -> Option<Message> {
        block(self.rt, self.server().read())
    }

    /// Waits at most `d` for the next request.
    pub fn read_timeout(&self, d: Duration) -> Option<Message> {
        let s = self.server();
        block(
            self.rt,
            async move { timeout(d, s.read()).await.ok().flatten() },
        )
    }

    /// Answers requests with `f(request)` on this thread, for ever (the port stays open).
    pub fn serve<F>(&self, f: F)
    where
        F: FnMut(&Bottle) -> Bottle + Send,
    {
        block(self.rt, self.server().serve(f))
    }
}

closes_when_dropped!(
    RpcServer,
    "Stops serving, unregisters and closes (bounded by [`CLOSE_TIMEOUT`])."
);
