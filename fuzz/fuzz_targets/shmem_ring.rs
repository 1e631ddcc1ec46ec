//! The shmem ring header as a peer may leave it in shared memory: any 28 bytes, any
//! segment size, then reads and writes. A header that validates must only ever lead to
//! spans inside the segment, and resizes must keep the unread bytes.
#![no_main]

use libfuzzer_sys::fuzz_target;
use yarp_proto::wire::shmem::{Packet, RingHeader, HEADER_LEN, PACKET_LEN};

fuzz_target!(|data: &[u8]| {
    if data.len() < HEADER_LEN + 4 {
        return;
    }
    let (head, rest) = data.split_at(HEADER_LEN);
    let mut h = RingHeader::decode(head.try_into().unwrap());
    let mut capacity = u32::from_le_bytes([rest[0], rest[1], rest[2], rest[3]]) as usize;
    if let Ok(p) = <[u8; PACKET_LEN]>::try_from(&rest[..PACKET_LEN.min(rest.len())]) {
        assert_eq!(Packet::decode(&p).encode(), p);
    }
    let _ = h.validate_resize(capacity);
    if h.validate(capacity).is_err() {
        return;
    }
    for op in &rest[4..] {
        let n = (*op as usize) * 37;
        let spans = if op & 1 == 0 { h.read_spans(n) } else { h.write_spans(n) };
        for (o, l) in std::iter::once(spans.first).chain(spans.second) {
            assert!(o + l <= h.size as usize && o + l <= capacity);
        }
        if op & 1 == 0 {
            assert!(spans.len() <= h.avail as usize);
            h.consume(spans.len());
        } else {
            assert!(spans.len() <= h.free());
            h.produce(spans.len());
        }
        if op % 7 == 0 {
            if let Ok(Some(size)) = h.grown_size(n) {
                let r = h.resized(size).expect("a grown ring holds what it had");
                assert_eq!(r.avail, h.avail);
                r.validate(size as usize).expect("a resized ring is valid");
                h = r;
                capacity = size as usize;
            }
        }
        h.validate(capacity).expect("operations keep a ring valid");
    }
});
