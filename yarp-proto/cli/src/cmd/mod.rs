//! One module per `yarp` subcommand.

pub mod bottle;
pub mod latency;
pub mod net;
