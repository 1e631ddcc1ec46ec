//! The frame-grabber family: image interfaces, `fakeFrameGrabber`, and the
//! `frameGrabber_nws_yarp` / `frameGrabber_nwc_yarp` network wrappers.

use crate::driver::Factory;

/// Image acquisition (C++ `IFrameGrabberImage`).
pub trait IFrameGrabberImage {}

/// Camera controls (C++ `IFrameGrabberControls`).
pub trait IFrameGrabberControls {}

/// Drivers of this family, by C++ name.
pub(crate) const DRIVERS: &[(&str, Factory)] = &[];
