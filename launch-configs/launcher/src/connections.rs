//! Keeps the configured connections made: each is made once both ports exist, and made
//! again when it disappears (a module restarted).

use crate::config::ConnectionSpec;
use crate::say;
use parking_lot::Mutex;
use serde::Serialize;
use std::sync::Arc;
use std::time::Duration;
use tokio::sync::watch;
use yarp_net::nameserver::NameClient;
use yarp_net::network::{self, NetworkError};

/// Live state of one configured connection.
#[derive(Debug, Clone, Serialize)]
pub struct ConnState {
    pub from: String,
    pub to: String,
    pub carrier: Option<String>,
    pub connected: bool,
    /// How many times the launcher made it.
    pub made: u32,
    /// Why the last attempt did not connect (e.g. a port does not exist yet).
    pub waiting_for: Option<String>,
}

pub type SharedConns = Arc<Mutex<Vec<ConnState>>>;

pub fn shared(specs: &[ConnectionSpec]) -> SharedConns {
    Arc::new(Mutex::new(
        specs
            .iter()
            .map(|c| ConnState {
                from: c.from.clone(),
                to: c.to.clone(),
                carrier: c.carrier.clone(),
                connected: false,
                made: 0,
                waiting_for: Some("not tried yet".into()),
            })
            .collect(),
    ))
}

/// One pass: checks every connection and makes the missing ones.
pub async fn check_once(ns: &NameClient, conns: &SharedConns) {
    let todo: Vec<ConnState> = conns.lock().clone();
    for (i, c) in todo.iter().enumerate() {
        let outcome = ensure(ns, c).await;
        let mut all = conns.lock();
        let Some(s) = all.get_mut(i) else { continue };
        match outcome {
            Ok(made) => {
                if made {
                    s.made += 1;
                    let carrier = c.carrier.as_deref().unwrap_or("default carrier");
                    say(&format!("connected {} -> {} ({carrier})", c.from, c.to));
                }
                s.connected = true;
                s.waiting_for = None;
            }
            Err(why) => {
                s.connected = false;
                s.waiting_for = Some(why);
            }
        }
    }
}

/// Ok(true) when this call made the connection, Ok(false) when it already existed.
async fn ensure(ns: &NameClient, c: &ConnState) -> Result<bool, String> {
    let describe = |e: NetworkError| match e {
        NetworkError::UnknownPort(p) => format!("port {p} does not exist yet"),
        other => other.to_string(),
    };
    match network::connection_carrier(ns, &c.from, &c.to).await {
        Ok(Some(_)) => return Ok(false),
        Ok(None) => {}
        Err(e) => return Err(describe(e)),
    }
    match network::connect(ns, &c.from, &c.to, c.carrier.as_deref()).await {
        Ok((true, _)) => Ok(true),
        Ok((false, msg)) => Err(msg.trim().to_string()),
        Err(e) => Err(describe(e)),
    }
}

/// Checks all connections every `period` until `stop` turns true.
pub async fn maintain(
    ns: NameClient,
    conns: SharedConns,
    period: Duration,
    mut stop: watch::Receiver<bool>,
) {
    if conns.lock().is_empty() {
        return;
    }
    loop {
        if *stop.borrow() {
            return;
        }
        check_once(&ns, &conns).await;
        tokio::select! {
            _ = tokio::time::sleep(period) => {}
            _ = stop.changed() => return,
        }
    }
}
