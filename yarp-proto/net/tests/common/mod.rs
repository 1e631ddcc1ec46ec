//! Set-up shared by yarp-net's live tests: an in-process name server on loopback and
//! bounded waits.
#![allow(dead_code)] // each test binary uses its part

use std::time::Duration;
use tokio::time::timeout;
use yarp_net::nameserver::{NameClient, NameServer, ShutdownHandle};

/// The bound of every wait.
pub const T: Duration = Duration::from_secs(20);

/// A name server on a free loopback port, its client and its stop handle.
pub async fn name_server() -> (NameClient, ShutdownHandle) {
    let ns = NameServer::bind("127.0.0.1:0", "127.0.0.1")
        .await
        .expect("bind ns");
    let addr = ns.local_addr();
    let stop = ns.shutdown_handle();
    tokio::spawn(ns.serve());
    (NameClient::new(addr).with_timeout(T), stop)
}

/// Waits (at most [`T`]) until `f` holds, else panics saying `what`.
pub async fn eventually(what: &str, f: impl Fn() -> bool) {
    timeout(T, async {
        while !f() {
            tokio::time::sleep(Duration::from_millis(10)).await;
        }
    })
    .await
    .unwrap_or_else(|_| panic!("{what}"));
}
