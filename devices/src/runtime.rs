//! The tokio runtime behind network wrappers.
//!
//! `DeviceDriver::open` is synchronous, as in C++, but wrappers serve ports with tokio.
//! They run on one process-wide runtime so that opening a wrapper works the same from a
//! plain `main`, from a thread, or from inside another runtime (the caller only waits on
//! a channel; the work happens on this runtime's threads).

use std::future::Future;
use std::sync::OnceLock;
use tokio::runtime::{Builder, Handle, Runtime};

fn runtime() -> &'static Runtime {
    static RT: OnceLock<Runtime> = OnceLock::new();
    RT.get_or_init(|| {
        Builder::new_multi_thread()
            .worker_threads(2)
            .thread_name("yarp-devices")
            .enable_all()
            .build()
            .expect("cannot start the device runtime")
    })
}

/// A handle to the device runtime, to spawn serving tasks on.
pub fn handle() -> Handle {
    runtime().handle().clone()
}

/// Runs `fut` on the device runtime and waits for its result (callable from any context).
pub fn block_on<F>(fut: F) -> F::Output
where
    F: Future + Send + 'static,
    F::Output: Send + 'static,
{
    let (tx, rx) = std::sync::mpsc::sync_channel(1);
    runtime().spawn(async move {
        let _ = tx.send(fut.await);
    });
    rx.recv().expect("device runtime task dropped")
}
