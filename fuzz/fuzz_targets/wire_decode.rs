//! The connection decoder on arbitrary bytes (an accepting port reading whatever a peer
//! sends: headers, sender names, indexes, port commands, text lines), fed in two pieces
//! split at a byte chosen by the input. It must never panic, and splitting the stream
//! must not change the events. The same bytes also go through the index-less decoder
//! of the unix_stream carriers, with the same rule.
#![no_main]

use libfuzzer_sys::fuzz_target;
use yarp_proto::wire::{Decoder, DecoderConfig, IndexlessDecoder};

fn run_indexless(chunks: &[&[u8]]) -> (Vec<String>, bool) {
    let mut d = IndexlessDecoder::new(1 << 20);
    let mut msgs = Vec::new();
    for c in chunks {
        d.feed(c);
        loop {
            match d.poll() {
                Ok(Some(m)) => msgs.push(format!("{m:?}")),
                Ok(None) => break,
                Err(_) => return (msgs, true),
            }
        }
    }
    (msgs, false)
}

fn run(chunks: &[&[u8]]) -> (Vec<String>, bool) {
    let config = DecoderConfig {
        max_message_size: 1 << 20,
        max_line_len: 1 << 16,
        ..DecoderConfig::default()
    };
    let mut d = Decoder::accepting(config);
    let mut events = Vec::new();
    for c in chunks {
        match d.decode(c) {
            // uninterpreted bytes come out in whatever pieces they arrived: not compared
            Ok(evs) => events.extend(
                evs.into_iter()
                    .map(|e| format!("{e:?}"))
                    .filter(|e| !e.starts_with("Raw(")),
            ),
            Err(_) => return (events, true),
        }
    }
    (events, false)
}

fuzz_target!(|data: &[u8]| {
    let Some((&cut, rest)) = data.split_first() else {
        return;
    };
    let at = (cut as usize).min(rest.len());
    let whole = run(&[rest]);
    let split = run(&[&rest[..at], &rest[at..]]);
    if !whole.1 && !split.1 {
        assert_eq!(whole.0, split.0, "segmentation changed the events");
    }
    let whole = run_indexless(&[rest]);
    let split = run_indexless(&[&rest[..at], &rest[at..]]);
    if !whole.1 && !split.1 {
        assert_eq!(whole.0, split.0, "segmentation changed the index-less messages");
    }
});
