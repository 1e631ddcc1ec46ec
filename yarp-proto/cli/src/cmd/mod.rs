//! One module per `yarp` subcommand.

pub mod bottle;
pub mod net;
