//! YARP device layer: drivers, interface families and network wrappers.
//!
//! Not implemented yet; see the project's issue tracker (device layer issue).
