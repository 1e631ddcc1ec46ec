//! `yarp-launch`: runs a launch config.

fn main() {}
