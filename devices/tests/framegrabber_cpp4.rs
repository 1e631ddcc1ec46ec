//! The frame grabber against C++ YARP 4.0.0, whose pair speaks the thrift service
//! `FrameGrabberMsgs` and whose images have no `topIsLow`: C++ 4.0's
//! `frameGrabber_nwc_yarp` reads our `frameGrabber_nws_yarp` (through C++'s server over
//! it, `yarp rpc` at it prints what the same chain over C++ 4.0's own server prints, and
//! `yarp read` gets its images), and our `frameGrabber_nwc_yarp` reads C++ 4.0's server.
//! Run under ../shared/netns-run (C++ 4.0: tests/peers/install-cpp-peers.sh yarp4).

use std::time::{Duration, Instant};
use yarp_devices::PolyDriver;
mod framegrabber_common;

use framegrabber_common::{cpp_client_chain, cpp_grabber, grabber};
use yarp_interop_tests::{assert_same_rpc_session, cpp4_devices, name_client};
use yarp_proto::Property;

const WAIT: Duration = Duration::from_secs(10);

/// Calls of every kind: image size, visual parameters, controls, DC1394 (which neither
/// fake has), a setter and its getter, a call with a wrong argument, and 3.12's vocabs
/// (which 4.0's server does not answer).
const SESSION: &[&str] = &[
    "getWidthRPC",
    "getHeightRPC",
    "getRgbWidthRPC",
    "getRgbHeightRPC",
    "getRgbResolutionRPC",
    "getRgbMirroringRPC",
    "setRgbMirroringRPC [ok]",
    "getRgbMirroringRPC",
    "getCameraDescriptionRPC",
    "hasFeatureRPC 1",
    "getFeature1RPC 1",
    "getModeRPC 1",
    "getFPSDC1394RPC",
    "getFormat7WindowDC1394RPC",
];

#[test]
fn cpp_4_frame_grabber_client_reads_ours() {
    let test = "cpp_4_frame_grabber_client_reads_ours";
    let Some(bin) = cpp4_devices(
        test,
        &[
            "frameGrabber_nws_yarp",
            "frameGrabber_nwc_yarp",
            "fakeFrameGrabber",
        ],
    ) else {
        return;
    };
    let mut ours = grabber("/fg4_ours");
    let _chain_ours = cpp_client_chain(&bin, "/fg4_chain_ours", "/fg4_ours");
    let yarp = bin.join("yarp");
    let _cpp = cpp_grabber(&bin, "/fg4_cpp", "0.1");
    let _chain_cpp = cpp_client_chain(&bin, "/fg4_chain_cpp", "/fg4_cpp");
    assert_same_rpc_session(&yarp, SESSION, "/fg4_chain_ours/rpc", "/fg4_chain_cpp/rpc");

    // the C++ 4.0 client's images, republished by C++'s wrapper, are ours (8x6 RGB), in
    // 4.0's header: the quantum alone
    yarp_interop_tests::cpp_read_until(&yarp, "/fg4_rd", "/fg4_chain_ours", |l| {
        l.starts_with("[mat] [rgb] (3 144 8 8 6) {").then_some(())
    });
    eprintln!("interop: C++ 4.0 frameGrabber_nwc_yarp -> our frameGrabber_nws_yarp OK");
    ours.close().unwrap();
}

/// Our `frameGrabber_nwc_yarp` reads C++ 4.0's `frameGrabber_nws_yarp` +
/// `fakeFrameGrabber`: it finds a 4.0 server, streams its images (4.0's header) and
/// calls its `FrameGrabberMsgs`, DC1394 included; with `no_stream`, images over RPC.
#[test]
fn our_frame_grabber_client_reads_cpp_4() {
    let test = "our_frame_grabber_client_reads_cpp_4";
    let Some(bin) = cpp4_devices(test, &["frameGrabber_nws_yarp", "fakeFrameGrabber"]) else {
        return;
    };
    name_client();
    let _cpp = cpp_grabber(&bin, "/fg4r_cpp", "0.05");
    for (local, no_stream) in [("/fg4r_ours", false), ("/fg4r_rpc", true)] {
        let mut client = PolyDriver::open(
            &Property::from_config_text(format!(
                "device frameGrabber_nwc_yarp\nremote /fg4r_cpp\nlocal {local}\nno_stream {no_stream}\n"
            ))
            .unwrap(),
        )
        .expect("our client opens against C++ 4.0");
        let d = client.device();
        let fg = d.as_frame_grabber_image().expect("IFrameGrabberImage");
        let start = Instant::now();
        let img = loop {
            if let Ok(img) = fg.get_image() {
                if img.width() > 0 {
                    break img;
                }
            }
            assert!(start.elapsed() < WAIT, "no image from C++ 4.0 ({local})");
            std::thread::sleep(Duration::from_millis(20));
        };
        assert_eq!((img.width(), img.height()), (8, 6), "{local}");
        assert_eq!((fg.width(), fg.height()), (8, 6), "{local}");
        let vp = fg.rgb_visual_params().expect("IRgbVisualParams");
        assert_eq!(vp.rgb_resolution().unwrap(), (8, 6));
        assert_eq!((vp.rgb_width(), vp.rgb_height()), (8, 6));
        vp.set_rgb_mirroring(true).unwrap();
        assert!(vp.rgb_mirroring().unwrap());
        vp.set_rgb_mirroring(false).unwrap();
        let c = client.device().as_frame_grabber_controls().unwrap();
        assert_eq!(c.camera_description().unwrap().bus_type, 0);
        c.set_feature(1, 0.25).unwrap();
        assert_eq!(c.get_feature(1).unwrap(), 0.25);
        let dc = client.device().as_frame_grabber_controls_dc1394().unwrap();
        assert_eq!(dc.bytes_per_packet().unwrap(), 100);
        dc.set_fps(17).unwrap();
        assert_eq!(dc.fps().unwrap(), 17);
        dc.set_fps(13).unwrap();
        client.close().unwrap();
    }
    eprintln!("interop: our frameGrabber_nwc_yarp -> C++ 4.0 frameGrabber_nws_yarp OK");
}
