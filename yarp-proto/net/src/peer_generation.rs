//! Which generation of YARP (3.x or 4.0) runs the process behind a port.
//!
//! A device server must answer each client in its own generation's layout (4.0 renumbered
//! the float tags and re-laid `yarp::dev::ReturnValue`), but many of its requests, such
//! as an argument-less `getScanLimits RPC`, are the same bytes in both. The port's admin
//! tells them apart: C++ YARP 3.x answers ROS's `getPid` (`1 "" <pid>`), while 4.0 took
//! ROS out of its ports and answers it `[fail]`. Our own ports answer as 3.x does (and our
//! clients read either generation's replies).

use crate::nameserver::NameClient;
use crate::network::{admin_command, NetworkError};
use parking_lot::Mutex;
use std::collections::{HashMap, HashSet};
use std::sync::Arc;
use std::time::Duration;
use yarp_proto::tags::Generation;
use yarp_proto::{Bottle, Contact, Value};

/// How long a probe may take before the port is taken for a 3.x one.
pub const PROBE_TIMEOUT: Duration = Duration::from_secs(2);

/// The generation of the process whose port is at `contact`, asked of its admin.
pub async fn probe(contact: &Contact) -> Result<Generation, NetworkError> {
    let reply = tokio::time::timeout(
        PROBE_TIMEOUT,
        admin_command(contact, &Bottle::new().with("getPid")),
    )
    .await
    .map_err(|_| NetworkError::Timeout(contact.name.clone()))??;
    Ok(generation_of_pid_reply(&reply))
}

/// 3.x's `getPid` reply is `1 "" <pid>`; anything else (4.0's `[fail] "send [help]..."`)
/// is 4.0's.
pub fn generation_of_pid_reply(reply: &Bottle) -> Generation {
    match (reply.get(0), reply.get(2)) {
        (Some(Value::Int32(1)), Some(Value::Int32(_))) => Generation::V3,
        _ => Generation::V4,
    }
}

/// The generations of the peers of one server, learnt once per port registration (a
/// client restarted under the same name, maybe of the other generation, is asked again).
#[derive(Clone)]
pub struct PeerGenerations {
    ns: NameClient,
    known: Arc<Mutex<HashMap<String, (Contact, Generation)>>>,
    asking: Arc<Mutex<HashSet<String>>>,
    /// Where background probes run: the runtime it was made on (callers of
    /// [`PeerGenerations::known`] may be plain threads).
    rt: Option<tokio::runtime::Handle>,
}

impl PeerGenerations {
    /// Made on a tokio runtime, where its background probes will run.
    pub fn new(ns: NameClient) -> PeerGenerations {
        PeerGenerations {
            ns,
            known: Arc::default(),
            asking: Arc::default(),
            rt: tokio::runtime::Handle::try_current().ok(),
        }
    }

    /// The generation of `port`'s process (3.x when it cannot be told: an unregistered
    /// port, a dead or silent admin).
    pub async fn of(&self, port: &str) -> Generation {
        let Ok(Some(contact)) = self.ns.query(port).await else {
            // not registered (an anonymous or in-process reader): taken for 3.x, and
            // asked again if it registers
            self.known
                .lock()
                .insert(port.to_string(), (Contact::default(), Generation::V3));
            return Generation::V3;
        };
        if let Some((c, g)) = self.known.lock().get(port) {
            if same_registration(c, &contact) {
                return *g;
            }
        }
        let g = probe(&contact).await.unwrap_or_else(|e| {
            tracing::debug!("cannot tell the YARP generation of {port}: {e}");
            Generation::V3
        });
        self.known.lock().insert(port.to_string(), (contact, g));
        g
    }

    /// What is known of `port` now, without waiting; when nothing is, it is asked in the
    /// background (on the current tokio runtime) and a later call knows.
    pub fn known(&self, port: &str) -> Option<Generation> {
        if let Some((_, g)) = self.known.lock().get(port) {
            return Some(*g);
        }
        if self.asking.lock().insert(port.to_string()) {
            if let Some(rt) = self
                .rt
                .clone()
                .or_else(|| tokio::runtime::Handle::try_current().ok())
            {
                let this = self.clone();
                let port = port.to_string();
                rt.spawn(async move {
                    this.of(&port).await;
                    this.asking.lock().remove(&port);
                });
            } else {
                self.asking.lock().remove(port);
            }
        }
        None
    }

    /// Asks about those of `ports` not known yet, so that a new reader gets even the
    /// first message in its own form (a silent one is taken for 3.x after
    /// [`PROBE_TIMEOUT`], once).
    pub async fn learn(&self, ports: &[String]) {
        for port in ports {
            if !self.knows(port) {
                self.of(port).await;
            }
        }
    }

    /// Whether every one of `ports` is known: a periodic writer outside the runtime
    /// checks this before it enters the runtime to [`PeerGenerations::learn`].
    pub fn knows_all(&self, ports: &[String]) -> bool {
        ports.iter().all(|p| self.knows(p))
    }

    fn knows(&self, port: &str) -> bool {
        self.known.lock().contains_key(port)
    }
}

fn same_registration(a: &Contact, b: &Contact) -> bool {
    a.host == b.host && a.port == b.port
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pid_replies() {
        let v3 = Bottle::from_text("1 \"\" 4242");
        assert_eq!(generation_of_pid_reply(&v3), Generation::V3);
        let v4 = Bottle::from_text("[fail] \"send [help] for list of valid commands\"");
        assert_eq!(generation_of_pid_reply(&v4), Generation::V4);
        assert_eq!(generation_of_pid_reply(&Bottle::new()), Generation::V4);
    }
}
