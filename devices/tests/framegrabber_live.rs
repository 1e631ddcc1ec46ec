//! frameGrabber_nws_yarp / frameGrabber_nwc_yarp over real sockets (run under netns-run),
//! with an in-process name server announced through a private yarp.conf. Every wait
//! is bounded.

use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio::net::{TcpListener, TcpStream};
use yarp_devices::framegrabber::nwc::FrameGrabberNwc;
use yarp_devices::framegrabber::{decode_image, Image, PixelCode};
use yarp_devices::{runtime, DeviceDriver, PolyDriver};
use yarp_interop_tests::{name_client, name_server, wait_for, T};
use yarp_proto::nameserver::RegisterRequest;
use yarp_proto::{bottle, Property};

fn open(cfg: &str) -> PolyDriver {
    name_server();
    PolyDriver::open(&Property::from_config_text(cfg).unwrap()).expect("open device")
}

/// FNV-1a, enough to tell two frames apart.
fn checksum(data: &[u8]) -> u64 {
    data.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
    })
}

/// The fake's `grid` frame with the blue line on `row`.
fn grid(width: usize, height: usize, row: usize) -> Image {
    let mut img = Image::new(PixelCode::RGB, width, height).unwrap();
    for y in 0..height {
        for x in 0..width {
            let r = (0.5 + 255.0 * x as f64 / (width - 1) as f64) as u8;
            let g = (0.5 + 255.0 * y as f64 / (height - 1) as f64) as u8;
            let b = if y == row { 255 } else { 0 };
            img.pixel_mut(x, y).copy_from_slice(&[r, g, b]);
        }
    }
    img
}

#[test]
fn nwc_gets_intact_640x480_frames_and_remote_controls() {
    let mut server = open(
        "device frameGrabber_nws_yarp\nsubdevice fakeFrameGrabber\nname /cam\n\
         width 640\nheight 480\nmode grid\nperiod 0.03\n",
    );
    let mut client = open("device frameGrabber_nwc_yarp\nremote /cam\nlocal /camclient\n");
    let fg = client
        .device()
        .as_frame_grabber_image()
        .expect("image interface");
    let img = wait_for("a streamed image", || fg.get_image().ok());
    // the server's port streams to the client over fast_tcp, as with the C++ client
    let ns = name_client();
    let carrier = runtime::block_on(async move {
        yarp_net::network::connection_carrier(&ns, "/cam", "/camclient").await
    })
    .expect("the device runtime");
    assert_eq!(carrier.unwrap().as_deref(), Some("fast_tcp"));
    assert_eq!((img.width(), img.height()), (640, 480));
    assert_eq!(img.pixel_code(), PixelCode::RGB);
    assert_eq!(img.data().len(), 640 * 480 * 3);
    let row = (0..480)
        .find(|&y| img.pixel(0, y)[2] == 255)
        .expect("the blue line");
    let want = grid(640, 480, row);
    assert_eq!(
        checksum(img.data()),
        checksum(want.data()),
        "frame corrupted"
    );
    assert_eq!(img.data(), want.data());
    assert_eq!((fg.width(), fg.height()), (640, 480));
    let s1 = fg.last_input_stamp().expect("envelope");
    let s2 = wait_for("a later frame", || {
        fg.get_image().ok()?;
        fg.last_input_stamp().filter(|s| s.count > s1.count)
    });
    assert!(s2.time >= s1.time);
    assert!(
        ((s2.time * 1000.0).fract() - 0.42).abs() < 1e-3,
        "{}",
        s2.time
    );

    let vp = fg.rgb_visual_params().expect("visual params");
    assert_eq!((vp.rgb_width(), vp.rgb_height()), (640, 480));
    assert_eq!(vp.rgb_resolution().unwrap(), (640, 480));
    assert_eq!(vp.rgb_fov().unwrap(), (1.0, 2.0));
    assert_eq!(vp.rgb_supported_configurations().unwrap().len(), 3);
    let intr = vp.rgb_intrinsic_param().unwrap();
    assert_eq!(
        intr.find("focalLengthX").and_then(|v| v.as_f64()),
        Some(4.0)
    );
    assert!(!vp.rgb_mirroring().unwrap());
    vp.set_rgb_mirroring(true).unwrap();
    assert!(vp.rgb_mirroring().unwrap());

    let c = client
        .device()
        .as_frame_grabber_controls()
        .expect("controls");
    assert!(!c.has_feature(0).unwrap());
    c.set_feature(0, 0.25).unwrap();
    assert_eq!(c.get_feature(0).unwrap(), 0.25);
    c.set_feature2(3, 0.5, 0.75).unwrap();
    assert_eq!(c.camera_description().unwrap().bus_type, 0);
    c.set_mode(0, 2).unwrap();
    assert_eq!(c.get_mode(0).unwrap(), 2);

    client.close().unwrap();
    server.close().unwrap();
}

#[test]
fn nwc_without_stream_uses_rpc_and_ignores_garbage() {
    let mut server = open(
        "device frameGrabber_nws_yarp\nsubdevice fakeFrameGrabber\nname /cam2\n\
         width 16\nheight 12\nperiod 0.02\n",
    );
    // a client over RPC only
    let mut rpc_only =
        open("device frameGrabber_nwc_yarp\nremote /cam2\nlocal /cam2rpc\nno_stream 1\n");
    let fg = rpc_only.device().as_frame_grabber_image().unwrap();
    assert_eq!((fg.width(), fg.height()), (16, 12));
    let img = fg.get_image().unwrap();
    assert_eq!((img.width(), img.height()), (16, 12));
    rpc_only.close().unwrap();

    // a streaming client that also receives junk on its image port
    let mut nwc = FrameGrabberNwc::new();
    nwc.open(&Property::from_config_text("remote /cam2\nlocal /cam2s\n").unwrap())
        .unwrap();
    let ns = name_client();
    let junk = runtime::block_on(async move {
        let p = yarp_net::port::Port::open("/junk", ns).await.unwrap();
        p.connect("/cam2s", None).await.unwrap();
        p.write(&bottle!["not", "an", "image", 42]).await;
        p
    })
    .expect("the device runtime");
    wait_for("the junk to be rejected", || {
        (nwc.rejected_messages() > 0).then_some(())
    });
    let fg = nwc.as_frame_grabber_image().unwrap();
    let img = wait_for("an image after the junk", || fg.get_image().ok());
    assert_eq!(img.width(), 16);
    runtime::block_on(junk.close()).expect("the device runtime");
    nwc.close().unwrap();
    server.close().unwrap();
}

async fn read_exact(s: &mut TcpStream, n: usize) -> Vec<u8> {
    let mut buf = vec![0u8; n];
    tokio::time::timeout(T, s.read_exact(&mut buf))
        .await
        .expect("timed out reading")
        .expect("read");
    buf
}

fn le32(b: &[u8]) -> i32 {
    i32::from_le_bytes([b[0], b[1], b[2], b[3]])
}

/// One tcp-family message: (port command block, payload), acked as C++ readers do.
async fn read_message(s: &mut TcpStream) -> (Vec<u8>, Vec<u8>) {
    let num = read_exact(s, 8).await;
    assert_eq!(hex::encode(&num), "59410a0000005250", "index marker");
    let head = read_exact(s, 10).await;
    assert_eq!(
        &head[1..],
        &[1, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff]
    );
    let n = head[0] as usize;
    let lens = read_exact(s, 4 * n + 4).await;
    assert_eq!(le32(&lens[4 * n..]), 0, "reply length slot");
    let mut body = Vec::new();
    for k in 0..n {
        let len = le32(&lens[4 * k..]) as usize;
        body.extend(read_exact(s, len).await);
    }
    s.write_all(&hex::decode("5941000000005250").unwrap())
        .await
        .unwrap();
    let text_len = le32(&body) as usize;
    assert_eq!(&body[4..8], &[b'~', 0, 0, 1], "text port command");
    let cmd = body[..8 + text_len].to_vec();
    (cmd, body[8 + text_len..].to_vec())
}

/// The recorded C++ session (fg-001, fg-002): `yarp connect /grabber /cap/img` to a raw
/// receiver, then image messages with envelopes.
#[test]
fn raw_receiver_sees_the_cpp_framing() {
    let mut server = open(
        "device frameGrabber_nws_yarp\nsubdevice fakeFrameGrabber\nname /grabber\n\
         width 8\nheight 6\nperiod 0.1\n",
    );
    let ns = name_client();
    let (cmds, payloads, hello) = runtime::block_on(async move {
        let listener = TcpListener::bind("127.0.0.1:0").await.unwrap();
        let port = listener.local_addr().unwrap().port();
        let req = RegisterRequest::explicit("/cap/img", "tcp", "127.0.0.1", port);
        ns.register_port(&req, &["127.0.0.1"], 1).await.unwrap();
        let ns2 = ns.clone();
        let connect = tokio::spawn(async move {
            yarp_net::network::connect(&ns2, "/grabber", "/cap/img", None).await
        });
        let (mut s, _) = tokio::time::timeout(T, listener.accept())
            .await
            .expect("no connection")
            .unwrap();
        let mut hello = read_exact(&mut s, 12).await;
        let name_len = le32(&hello[8..]) as usize;
        hello.extend(read_exact(&mut s, name_len).await);
        let reply = [&b"YA"[..], &i32::from(port).to_le_bytes(), b"RP"].concat();
        s.write_all(&reply).await.unwrap();
        let (ok, msg) = connect.await.unwrap().unwrap();
        assert!(ok, "{msg}");
        let mut cmds = Vec::new();
        let mut payloads = Vec::new();
        for _ in 0..3 {
            let (c, p) = read_message(&mut s).await;
            cmds.push(c);
            payloads.push(p);
        }
        (cmds, payloads, hello)
    })
    .expect("the device runtime");
    assert_eq!(
        hex::encode(&hello),
        "5941e41e00005250090000002f6772616262657200"
    );
    let recorded_header = "0001000004000000090000006d6174000900000072676200010100000500000003000000900000000800010008000000060000000c00000090000000";
    for (k, (cmd, payload)) in cmds.iter().zip(&payloads).enumerate() {
        let text = std::str::from_utf8(&cmd[8..cmd.len() - 1]).unwrap();
        let mut parts = text.split(' ');
        assert_eq!(parts.next(), Some("D"));
        assert_eq!(parts.next(), Some(k.to_string().as_str()), "envelope count");
        let t: f64 = parts.next().unwrap().parse().unwrap();
        assert!(((t * 1000.0).fract() - 0.42).abs() < 1e-3, "{text}");
        assert_eq!(hex::encode(&payload[..60]), recorded_header);
        let img = decode_image(payload).unwrap();
        let red: Vec<usize> = (0..6)
            .filter(|&y| img.row(y).chunks(3).all(|p| p == [255, 0, 0]))
            .collect();
        assert_eq!(red.len(), 1, "one red line");
    }
    server.close().unwrap();
}

#[test]
fn text_rpc_session() {
    let mut server = open(
        "device frameGrabber_nws_yarp\nsubdevice fakeFrameGrabber\nname /tcam\n\
         width 8\nheight 6\n",
    );
    let ns = name_client();
    let got = runtime::block_on(async move {
        let c = ns.query("/tcam/rpc").await.unwrap().expect("registered");
        let mut s = TcpStream::connect((c.host.as_str(), c.port)).await.unwrap();
        s.write_all(b"CONNECT foo\nd\n[visr] [get] [h]\nd\n[zzz]\n")
            .await
            .unwrap();
        let mut got = Vec::new();
        let mut buf = [0u8; 1024];
        tokio::time::timeout(T, async {
            while !String::from_utf8_lossy(&got).contains("[nak]") {
                let n = s.read(&mut buf).await.unwrap();
                assert!(n > 0, "closed");
                got.extend_from_slice(&buf[..n]);
            }
        })
        .await
        .expect("timed out");
        String::from_utf8_lossy(&got).into_owned()
    })
    .expect("the device runtime");
    assert!(got.contains("[visr] [h] [is] 6\r\n"), "{got}");
    server.close().unwrap();
}
