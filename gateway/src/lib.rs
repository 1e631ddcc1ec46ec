//! YARP <-> ROS 2 gateway.
//!
//! Not implemented yet; see the project's issue tracker (gateway issue).
