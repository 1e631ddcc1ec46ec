//! The frame-grabber family: image interfaces, `fakeFrameGrabber`, and the
//! `frameGrabber_nws_yarp` / `frameGrabber_nwc_yarp` network wrappers.
//!
//! * [`image`]: `yarp::sig::Image` and its exact wire format (pure encode/decode), from
//!   `yarp_proto::image`, re-exported here.
//! * [`protocol`]: the frame-grabber RPC protocol (`[fgi]`, `[fgc]`, `[visr]`...) as a
//!   pure function over a device.
//! * [`interfaces`]: the interfaces a camera offers.
//! * [`fake`]: `fakeFrameGrabber` (test patterns).
//! * [`nws`] / [`nwc`]: the network server and client.

pub mod fake;
pub mod interfaces;
pub use yarp_proto::image;
pub mod nwc;
pub mod nws;
pub mod protocol;
pub mod v4;

use crate::driver::Factory;
pub use image::{decode_image, encode_image, Image, ImageError, PixelCode};
pub use interfaces::*;

/// Drivers of this family, by C++ name.
pub(crate) const DRIVERS: &[(&str, Factory)] = &[
    ("fakeFrameGrabber", || {
        Box::new(fake::FakeFrameGrabber::new())
    }),
    ("frameGrabber_nws_yarp", || {
        Box::new(nws::FrameGrabberNws::new())
    }),
    ("frameGrabber_nwc_yarp", || {
        Box::new(nwc::FrameGrabberNwc::new())
    }),
];
