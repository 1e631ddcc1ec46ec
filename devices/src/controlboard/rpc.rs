//! The control-board RPC protocol served on `/<name>/rpc:i` (C++ `RPCMessagesParser`),
//! as a pure function of the command and the device: `handle_rpc`. The methods and their
//! replies are declared in `methods.rs`, their 3.12 encoding in `v3.rs`.
//!
//! Replies: `set` commands answer `[ok]`/`[fail]`; most `get` commands answer
//! `[is] <echoed token> <value> [tsta] <count> <time> [ok]`; commands shorter than two
//! elements answer `[nak]`; anything not understood (or failing) answers `[fail]`.

use super::methods::Request;
use crate::driver::DeviceDriver;
use crate::vocabs::*;
use std::time::{SystemTime, UNIX_EPOCH};
use yarp_proto::{Bottle, Stamp, Vocab32};

/// The control-board protocol version this server speaks (`[get] [prot]`), as C++ 3.12.
pub const PROTOCOL_VERSION_NUMBER: (i32, i32, i32) = (1, 9, 0);

/// The stamp appended to `get` replies; its count increases with each one.
#[derive(Debug, Default, Clone)]
pub struct RpcStamp {
    next: i32,
}

impl RpcStamp {
    pub fn new() -> Self {
        Self::default()
    }
    /// Next stamp with the current wall-clock time.
    pub fn update(&mut self) -> Stamp {
        let t = SystemTime::now()
            .duration_since(UNIX_EPOCH)
            .map(|d| d.as_secs_f64())
            .unwrap_or(0.0);
        let s = Stamp::new(self.next, t);
        self.next = self.next.wrapping_add(1);
        s
    }
}

/// Serves one control-board RPC command against `dev` and returns the reply.
///
/// Malformed commands (wrong arity or types) and commands the device cannot serve get
/// `[fail]` (or `[nak]` when shorter than two elements), as in C++, plus a log line.
pub fn handle_rpc(cmd: &Bottle, dev: &mut dyn DeviceDriver, stamp: &mut RpcStamp) -> Bottle {
    if cmd.len() < 2 {
        tracing::warn!("controlBoard rpc: `{cmd}` is too short: replying [nak]");
        return Bottle::new().with(Vocab32(NAK));
    }
    match Request::from_v3(cmd) {
        Some(req) => req.serve_v3(cmd, dev, stamp),
        None => {
            tracing::warn!("controlBoard rpc: `{cmd}` is no command of the protocol (unknown or malformed): replying [fail]");
            Bottle::new().with(Vocab32(FAILED))
        }
    }
}
