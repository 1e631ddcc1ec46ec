//! YARP <-> ROS 2 gateway.
//!
//! Pure logic lives in its own modules and is unit-tested without sockets: the ROS type
//! catalog ([`types`]) with the types read at run time from their definitions
//! ([`msgdef`], [`interfaces`]), REP-2016 hashes ([`hash`]), the generic Bottle layout of
//! any type ([`generic`]), dynamic CDR messages ([`dynmsg`]),
//! Bottle conversions ([`convert`], [`image`], [`mas`]), joint commands ([`joint_command`]), service mapping ([`service`],
//! [`axis_info`]), counters ([`counters`]) and mapping files ([`mapping`]). The tokio/DDS
//! runtime ([`gateway`], over one ros2-client node from [`ros`]) only moves messages.
#![forbid(unsafe_code)]

pub mod action;
pub mod axis_info;
pub mod camera_info;
pub mod convert;
pub mod counters;
pub mod dynmsg;
pub mod gateway;
pub mod generic;
pub mod hash;
pub mod idl;
pub mod image;
pub mod interfaces;
pub mod joint_command;
pub mod mapping;
pub mod mas;
pub mod msgdef;
pub mod pattern;
pub mod robot;
pub mod robot_state;
pub mod ros;
pub mod ros_args;
pub mod security;
pub mod service;
pub mod tf;
pub mod trajectory;
pub mod types;
