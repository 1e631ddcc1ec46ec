//! The `local` carrier: connections between ports of the same process skip sockets and
//! hand encoded messages straight to the receiving port (C++ YARP's `local` carrier plays
//! the same role). It is also this project's stand-in for `shmem` between ports that share
//! a process; ports in other processes use tcp/fast_tcp (see README).

use super::output::{Job, OutputError, OutputHandle};
use super::{Incoming, Shared, OUTPUT_QUEUE};
use parking_lot::Mutex;
use std::collections::HashMap;
use std::sync::{Arc, OnceLock, Weak};
use tokio::sync::{mpsc, oneshot, Notify};
use yarp_proto::port_admin::Route;

/// Ports of this process by name, for `local` connections.
fn registry() -> &'static Mutex<HashMap<String, Weak<Shared>>> {
    static LOCAL: OnceLock<Mutex<HashMap<String, Weak<Shared>>>> = OnceLock::new();
    LOCAL.get_or_init(|| Mutex::new(HashMap::new()))
}

/// Makes a port reachable by `local` connections.
pub(crate) fn register(shared: &Arc<Shared>) {
    let mut r = registry().lock();
    r.retain(|_, w| w.strong_count() > 0);
    r.insert(shared.name.clone(), Arc::downgrade(shared));
}

/// Forgets a port (only if the entry is this port, not a newer one of the same name).
pub(crate) fn unregister(shared: &Shared) {
    let mut r = registry().lock();
    if let Some(w) = r.get(&shared.name) {
        if std::ptr::eq(w.as_ptr(), shared) || w.strong_count() == 0 {
            r.remove(&shared.name);
        }
    }
}

pub(crate) fn connect(shared: &Arc<Shared>, target: &str) -> Result<OutputHandle, OutputError> {
    let dest = registry()
        .lock()
        .get(target)
        .and_then(Weak::upgrade)
        .ok_or_else(|| {
            OutputError::UnsupportedCarrier(format!("local (no port {target} in this process)"))
        })?;
    let id = dest.next_id();
    let kill = Arc::new(Notify::new());
    dest.lock().inputs.insert(
        id,
        super::input::InputEntry::new(Route::new(&shared.name, target, "local"), kill.clone()),
    );
    let (tx, rx) = mpsc::channel(OUTPUT_QUEUE);
    let task = tokio::spawn(run(
        shared.name.clone(),
        Arc::downgrade(&dest),
        id,
        kill,
        rx,
    ));
    Ok(OutputHandle::new(
        Route::new(&shared.name, target, "local"),
        tx,
        task,
    ))
}

async fn run(
    from: String,
    dest: Weak<Shared>,
    id: u64,
    kill: Arc<Notify>,
    mut rx: mpsc::Receiver<Job>,
) {
    loop {
        let job = tokio::select! {
            _ = kill.notified() => break,
            job = rx.recv() => job,
        };
        let Some(job) = job else { break };
        let Some(shared) = dest.upgrade() else { break };
        match job {
            Job::Data(msg) => {
                let incoming = Incoming {
                    payload: Vec::new(),
                    is_text: false,
                    stamp: msg.stamp(),
                    from: from.clone(),
                    reply: None,
                    decoded: Some(Arc::clone(msg.bottle())),
                };
                if shared.deliver.send(incoming).await.is_err() {
                    break;
                }
            }
            Job::Rpc(msg, reply_tx) => {
                let (tx, rx) = oneshot::channel();
                let incoming = Incoming {
                    payload: Vec::new(),
                    is_text: false,
                    stamp: msg.stamp(),
                    from: from.clone(),
                    reply: Some(tx),
                    decoded: Some(Arc::clone(msg.bottle())),
                };
                if shared.deliver.send(incoming).await.is_err() {
                    break;
                }
                drop(shared);
                // no reply from the owner: an empty Bottle, as over tcp
                let reply = rx.await.map(super::ReplyBody::into_bottle);
                let _ = reply_tx.send(Ok(reply.unwrap_or_default()));
            }
            Job::Close(done) => {
                if let Some(done) = done {
                    let _ = done.send(());
                }
                break;
            }
        }
    }
    if let Some(shared) = dest.upgrade() {
        shared.lock().inputs.remove(&id);
    }
}
