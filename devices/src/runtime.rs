//! The tokio runtime behind network wrappers.
//!
//! `DeviceDriver::open` is synchronous, as in C++, but wrappers serve ports with tokio.
//! They run on one process-wide runtime so that opening a wrapper works the same from a
//! plain `main`, from a thread, or from inside another runtime (the caller only waits on
//! a channel; the work happens on this runtime's threads).
//!
//! No wait on it is unbounded, and no wait holds one of its workers: a wrapper that
//! serves a client calls its device from a worker, and that device may be a client of a
//! server that stalled; were the worker held, two such calls would stop every wrapper of
//! the process.

use std::future::Future;
use std::sync::OnceLock;
use std::time::Duration;
use tokio::runtime::{Builder, Handle, Runtime, RuntimeFlavor};

/// How long [`block_on`] waits: longer than any network call of a device takes before
/// its own timeout gives up (C++'s clients wait without a bound; a robot process must not).
pub const BLOCK_ON_LIMIT: Duration = Duration::from_secs(60);

/// Work on the device runtime that did not finish within its bound.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[error("the device runtime did not finish a network call within {limit:?}")]
pub struct Stalled {
    pub limit: Duration,
}

impl From<Stalled> for crate::error::DeviceError {
    fn from(s: Stalled) -> Self {
        crate::error::DeviceError::Timeout {
            device: "device runtime".into(),
            command: "a network call".into(),
            after: s.limit,
        }
    }
}

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

/// Runs `fut` on the device runtime and waits for its result, at most [`BLOCK_ON_LIMIT`]
/// (callable from any context).
pub fn block_on<F>(fut: F) -> Result<F::Output, Stalled>
where
    F: Future + Send + 'static,
    F::Output: Send + 'static,
{
    block_on_within(BLOCK_ON_LIMIT, fut)
}

/// [`block_on`] of a fallible future: a stall becomes its error type's.
pub fn block_on_result<F, T, E>(fut: F) -> Result<T, E>
where
    F: Future<Output = Result<T, E>> + Send + 'static,
    T: Send + 'static,
    E: From<Stalled> + Send + 'static,
{
    block_on(fut).unwrap_or_else(|s| Err(s.into()))
}

/// [`block_on`] of work whose only result is done or not (closing ports): a stall is
/// logged, naming `what`.
pub fn block_on_logged<F>(what: &str, fut: F)
where
    F: Future<Output = ()> + Send + 'static,
{
    if let Err(s) = block_on(fut) {
        tracing::warn!("{what}: {s}");
    }
}

impl From<Stalled> for String {
    fn from(s: Stalled) -> String {
        s.to_string()
    }
}

/// As [`block_on`], at most `limit`; `fut` is dropped (cancelled) when it runs over.
pub fn block_on_within<F>(limit: Duration, fut: F) -> Result<F::Output, Stalled>
where
    F: Future + Send + 'static,
    F::Output: Send + 'static,
{
    let (tx, rx) = std::sync::mpsc::sync_channel(1);
    runtime().spawn(async move {
        let _ = tx.send(tokio::time::timeout(limit, fut).await.ok());
    });
    let wait = || {
        // The task answers within `limit`; the margin covers a busy runtime.
        rx.recv_timeout(limit + Duration::from_secs(1))
            .ok()
            .flatten()
    };
    // On a worker (ours, when a wrapper's device is itself a client), the worker's other
    // tasks are handed over while this thread waits.
    device_call(wait).ok_or(Stalled { limit })
}

/// Runs a blocking call into a device from a task of the device runtime without holding
/// its worker (see the module's docs).
pub fn device_call<R>(call: impl FnOnce() -> R) -> R {
    let on_worker =
        Handle::try_current().is_ok_and(|h| h.runtime_flavor() == RuntimeFlavor::MultiThread);
    if on_worker {
        tokio::task::block_in_place(call)
    } else {
        call()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_call_that_runs_over_is_a_stall_not_a_hang() {
        let r = block_on_within(Duration::from_millis(200), std::future::pending::<()>());
        assert_eq!(
            r,
            Err(Stalled {
                limit: Duration::from_millis(200)
            })
        );
        assert_eq!(block_on(async { 7 }), Ok(7));
    }

    #[test]
    fn calls_from_the_runtime_s_own_workers_do_not_starve_it() {
        // Every worker waits on block_on at once: without handing the workers over, the
        // inner futures would never run.
        let (tx, rx) = std::sync::mpsc::channel();
        for _ in 0..4 {
            let tx = tx.clone();
            handle().spawn(async move {
                let r = block_on_within(Duration::from_secs(5), async {
                    tokio::time::sleep(Duration::from_millis(50)).await;
                    1
                });
                let _ = tx.send(r);
            });
        }
        for _ in 0..4 {
            assert_eq!(rx.recv_timeout(Duration::from_secs(10)), Ok(Ok(1)));
        }
    }
}
