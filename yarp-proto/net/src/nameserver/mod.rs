//! The YARP name server on tokio ([`NameServer`]) and a client that talks to one the way
//! the C++ library does ([`NameClient`]). The protocol itself (registry, reply bytes,
//! request bytes) lives in [`yarp_proto::nameserver`].

mod client;
pub mod fallback;
pub mod program;
mod server;

pub use client::{NameClient, NameClientError};
pub use server::{NameServer, ServerConfig, ShutdownHandle};
pub use yarp_proto::nameserver::{Registry, RegistryConfig};
