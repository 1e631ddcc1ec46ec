//! What a peer sends the readers of the ergoCub repeaters' carriers: an mjpeg stream (the
//! writer's HTTP answer and multipart JPEG parts, split where the input chooses) with
//! each part decoded as a JPEG, and the Bottles the port monitors' receiving side takes
//! (`depthimage_compression_zlib`, `bottle_compression_zlib`, `throttleDown`), and any
//! monitor chain a sender's name with carrier qualifiers asks for, applied to the data.
#![no_main]

use libfuzzer_sys::fuzz_target;
use yarp_proto::portmonitor::{Monitor, Side};
use yarp_proto::wire::mjpeg::{decode_jpeg, StreamDecoder, StreamEvent, MAX_FRAME};
use yarp_proto::wire::modifiers::CarrierName;
use yarp_proto::Bottle;

fuzz_target!(|data: &[u8]| {
    let Some((&pick, rest)) = data.split_first() else {
        return;
    };
    match pick % 3 {
        0 => {
            // the stream in two pieces: the same frames whatever the split
            let cut = rest.first().map_or(0, |&c| c as usize).min(rest.len());
            let frames = |pieces: &[&[u8]]| {
                let mut d = StreamDecoder::new();
                let mut out = Vec::new();
                for p in pieces {
                    d.feed(p);
                    while let Ok(Some(ev)) = d.poll() {
                        out.push(ev);
                    }
                }
                out
            };
            let whole = frames(&[rest]);
            assert_eq!(whole, frames(&[&rest[..cut], &rest[cut..]]));
            for ev in whole {
                if let StreamEvent::Frame(jpeg) = ev {
                    assert!(jpeg.len() <= MAX_FRAME);
                    if let Ok((img, _)) = decode_jpeg(&jpeg) {
                        let _ = img.to_bottle();
                    }
                }
            }
        }
        1 => {
            let _ = decode_jpeg(rest);
        }
        _ => {
            let b = Bottle::decode(rest).unwrap_or_else(|_| Bottle::from_text(rest));
            for file in [
                "depthimage_compression_zlib",
                "bottle_compression_zlib",
                "throttleDown",
            ] {
                let c = CarrierName::parse(&format!(
                    "fast_tcp+recv.portmonitor+file.{file}+type.dll"
                ));
                if let Ok(Some(m)) = Monitor::for_side(&c, Side::Receiver) {
                    let _ = m.update(&b);
                }
            }
            let text = String::from_utf8_lossy(rest);
            let (_, c) = CarrierName::from_sender_specifier("tcp", &text);
            // whatever chain the sender's name asks for, applied to the data
            for side in [Side::Receiver, Side::Sender] {
                if let Ok(Some(mut m)) = Monitor::for_side(&c, side) {
                    if m.accept(std::time::Instant::now()) {
                        let _ = m.update(&b);
                    }
                }
            }
            let _ = yarp_proto::portmonitor::with_stats_monitor("/a", "/b", &c.to_string());
        }
    }
});
