//! Shared set-up for the frame-grabber tests against C++ (3.12 and 4.0 alike): our server
//! over our fake, C++'s server over C++'s fake, and C++'s server over C++'s client of
//! another server (C++ has no command-line frame-grabber client).
#![allow(dead_code)]

use std::path::Path;
use yarp_devices::PolyDriver;
use yarp_interop_tests::{cpp_yarpdev, name_client, Reaped};
use yarp_proto::Property;

/// Our `frameGrabber_nws_yarp` named `name` over our `fakeFrameGrabber`, 8x6.
pub fn grabber(name: &str) -> PolyDriver {
    name_client();
    let cfg = format!(
        "device frameGrabber_nws_yarp\nsubdevice fakeFrameGrabber\nname {name}\n\
         width 8\nheight 6\nperiod 0.1\n"
    );
    PolyDriver::open(&Property::from_config_text(cfg).unwrap()).expect("server")
}

/// C++'s `frameGrabber_nws_yarp` (of the peer in `bin`) named `name` over its
/// `fakeFrameGrabber`, 8x6, an image every `period` seconds.
pub fn cpp_grabber(bin: &Path, name: &str, period: &str) -> Reaped {
    cpp_yarpdev(
        bin,
        &[
            "--device",
            "frameGrabber_nws_yarp",
            "--subdevice",
            "fakeFrameGrabber",
            "--name",
            name,
            "--width",
            "8",
            "--height",
            "6",
            "--period",
            period,
        ],
        &format!("{name}/rpc"),
    )
}

/// C++'s `frameGrabber_nws_yarp` named `name` over C++'s `frameGrabber_nwc_yarp` of
/// the server `remote`: each `yarp rpc {name}/rpc` line is a call of the C++ client.
pub fn cpp_client_chain(bin: &Path, name: &str, remote: &str) -> Reaped {
    cpp_yarpdev(
        bin,
        &[
            "--device",
            "frameGrabber_nws_yarp",
            "--subdevice",
            "frameGrabber_nwc_yarp",
            "--remote",
            remote,
            "--local",
            &format!("{name}/client"),
            "--name",
            name,
            "--period",
            "0.1",
        ],
        &format!("{name}/rpc"),
    )
}
