//! YARP networking on tokio: the thin I/O layer above the sans-I/O `yarp-proto` core.

pub mod auth;
pub mod blocking;
pub mod buffered;
pub mod dgram;
pub mod heap;
pub mod nameserver;
pub mod network;
pub mod peer_generation;
pub mod port;
pub mod realtime;
pub mod rpc;
pub mod signals;
