//! The frame grabber against C++ YARP 4.0.0, whose pair speaks the thrift service
//! `FrameGrabberMsgs` and whose images have no `topIsLow`: C++ 4.0's
//! `frameGrabber_nwc_yarp` reads our `frameGrabber_nws_yarp` (through C++'s server over
//! it, `yarp rpc` at it prints what the same chain over C++ 4.0's own server prints, and
//! `yarp read` gets its images), and our `frameGrabber_nwc_yarp` reads C++ 4.0's server.
//! Run under ../shared/netns-run (C++ 4.0: tests/peers/install-cpp-peers.sh yarp4).

use std::io::{BufRead, BufReader};
use std::process::Stdio;
use std::time::{Duration, Instant};
use yarp_devices::PolyDriver;
use yarp_interop_tests::{cpp4_devices, cpp_command, cpp_rpc_output, cpp_yarpdev, name_client};
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

fn grabber(name: &str) -> PolyDriver {
    name_client();
    let cfg = format!(
        "device frameGrabber_nws_yarp\nsubdevice fakeFrameGrabber\nname {name}\n\
         width 8\nheight 6\nperiod 0.1\n"
    );
    PolyDriver::open(&Property::from_config_text(cfg).unwrap()).expect("server")
}

/// The `Response: ...` lines of a `yarp rpc` session.
fn responses(out: &str) -> Vec<String> {
    out.lines()
        .filter_map(|l| l.strip_prefix("Response: "))
        .map(str::to_string)
        .collect()
}

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
    let input: String = SESSION.iter().map(|t| format!("{t}\n")).collect();
    let chain = |name: &str, remote: &str| {
        cpp_yarpdev(
            &bin,
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
    };
    let mut ours = grabber("/fg4_ours");
    let _chain_ours = chain("/fg4_chain_ours", "/fg4_ours");
    let yarp = bin.join("yarp");
    let over_ours = responses(&cpp_rpc_output(&yarp, "/fg4_chain_ours/rpc", &input));
    let _cpp = cpp_yarpdev(
        &bin,
        &[
            "--device",
            "frameGrabber_nws_yarp",
            "--subdevice",
            "fakeFrameGrabber",
            "--name",
            "/fg4_cpp",
            "--width",
            "8",
            "--height",
            "6",
            "--period",
            "0.1",
        ],
        "/fg4_cpp/rpc",
    );
    let _chain_cpp = chain("/fg4_chain_cpp", "/fg4_cpp");
    let over_cpp = responses(&cpp_rpc_output(&yarp, "/fg4_chain_cpp/rpc", &input));
    assert_eq!(
        over_cpp.len(),
        SESSION.len(),
        "C++ reference: {over_cpp:#?}"
    );
    let mut bad = Vec::new();
    for ((text, o), c) in SESSION.iter().zip(&over_ours).zip(&over_cpp) {
        let verdict = if o == c { "ok" } else { "DIFFERS" };
        eprintln!("{verdict:7} {text:32} {o}   | C++: {c}");
        if o != c {
            bad.push(format!("`{text}`: over ours {o:?}, over C++ {c:?}"));
        }
    }
    assert_eq!(
        over_cpp.len(),
        SESSION.len(),
        "C++ reference: {over_cpp:#?}"
    );
    assert_eq!(over_ours.len(), SESSION.len(), "over ours: {over_ours:#?}");
    assert!(
        bad.is_empty(),
        "{} rows differ:\n{}",
        bad.len(),
        bad.join("\n")
    );

    // the C++ 4.0 client's images, republished by C++'s wrapper, are ours (8x6 RGB), in
    // 4.0's header: the quantum alone
    let mut reader = yarp_interop_tests::Reaped(
        cpp_command(&yarp)
            .args(["read", "/fg4_rd", "/fg4_chain_ours"])
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .expect("C++ yarp read"),
    );
    let stdout = reader.0.stdout.take().unwrap();
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        for line in BufReader::new(stdout).lines().map_while(Result::ok) {
            if tx.send(line).is_err() {
                break;
            }
        }
    });
    let start = Instant::now();
    loop {
        assert!(start.elapsed() < WAIT, "no image from the C++ 4.0 chain");
        let Ok(line) = rx.recv_timeout(WAIT) else {
            continue;
        };
        if line.starts_with("[mat] [rgb] (3 144 8 8 6) {") {
            break;
        }
    }
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
    let _cpp = cpp_yarpdev(
        &bin,
        &[
            "--device",
            "frameGrabber_nws_yarp",
            "--subdevice",
            "fakeFrameGrabber",
            "--name",
            "/fg4r_cpp",
            "--width",
            "8",
            "--height",
            "6",
            "--period",
            "0.05",
        ],
        "/fg4r_cpp/rpc",
    );
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
