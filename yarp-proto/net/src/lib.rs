//! YARP networking on tokio: the thin I/O layer above the sans-I/O `yarp-proto` core.

pub mod nameserver;
pub mod port;
