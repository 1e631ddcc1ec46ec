//! The `shmem` carrier as C++ YARP's plugin lays it out on Linux (`ShmemCarrier`,
//! `ShmemHybridStream`, `ShmemInputStream` / `ShmemOutputStream` over ACE): sans-I/O
//! parts only — the side-channel packets, the names of the shared objects, and the ring
//! buffer's header with the arithmetic of reading and writing it.
//!
//! The handshake, after the usual tcp-family header (`7777 + 14`) and sender name:
//!
//! 1. the receiver listens on a new TCP port and answers with that port as a YARP number
//!    (where tcp answers with its own port number);
//! 2. the sender drops the first connection, connects to the new port, creates its ring
//!    (below) keyed by its own TCP port and sends [`Packet`] `CONNECT` (size 4096);
//! 3. the receiver attaches to the sender's ring (keyed by the peer's port), creates its
//!    own keyed by its own port, and answers `ACKNOWLEDGE`;
//! 4. the sender attaches to the receiver's ring. From then on the tcp-family protocol
//!    (index, blocks, acknowledgements, replies) flows through the two rings; the TCP
//!    connection only tells each side that the other is still there.
//!
//! A ring keyed by port `p` is a System V shared-memory segment with key `p` (after the
//! `n`-th resize: `(n << 16) + p`) holding a [`RingHeader`] and `size` data bytes, plus two
//! process-shared pthread mutexes, each alone in a file of the temp directory:
//! `SHMEM_ACCESS_MUTEX_<p>` guards the header, `SHMEM_WAITDATA_MUTEX_<p>` is held by the
//! reader and unlocked by the writer once per waiting read (a binary semaphore). A writer
//! that lacks room grows the ring to `size + 2 * len`: it creates the next segment, copies
//! the unread bytes there, and sets `resize` / `newsize` in the old header, which the
//! reader follows on its next read.

/// Ring size C++ creates a connection with.
pub const DEFAULT_RING_SIZE: i32 = 4096;

/// Bytes of the ring header (`struct ShmemHeader_t` on x86_64/aarch64 Linux).
pub const HEADER_LEN: usize = 28;

/// Byte offsets of the header fields (two `bool`s, padding, six native `int`s).
pub mod offset {
    pub const RESIZE: usize = 0;
    pub const CLOSE: usize = 1;
    pub const SIZE: usize = 4;
    pub const NEWSIZE: usize = 8;
    pub const HEAD: usize = 12;
    pub const TAIL: usize = 16;
    pub const AVAIL: usize = 20;
    pub const WAITING: usize = 24;
}

/// Commands of the side-channel packets.
pub mod command {
    pub const CONNECT: i32 = 0;
    pub const ACKNOWLEDGE: i32 = 1;
}

/// What our sender puts in `CONNECT`'s size field (C++ sends 4096 there and its receiver
/// ignores the field), and our receiver then in `ACKNOWLEDGE`'s (where C++ leaves stack
/// bytes): both sides are ours, and a writer also wakes a waiting reader with one byte on
/// the TCP side channel, so that readers wait in their event loop, not on a mutex.
pub const DOORBELL: i32 = 0x4c4c_4542;

/// Bytes of a side-channel packet.
pub const PACKET_LEN: usize = 8;

/// A side-channel packet (`struct ShmemPacket_t`: two native ints).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Packet {
    pub command: i32,
    pub size: i32,
}

impl Packet {
    /// What the sender sends once its ring exists (offering the [`DOORBELL`] or not).
    pub fn connect(doorbell: bool) -> Packet {
        Packet {
            command: command::CONNECT,
            size: if doorbell {
                DOORBELL
            } else {
                DEFAULT_RING_SIZE
            },
        }
    }

    /// What the receiver answers once both rings exist (C++ leaves `size` unset).
    pub fn acknowledge(doorbell: bool) -> Packet {
        Packet {
            command: command::ACKNOWLEDGE,
            size: if doorbell { DOORBELL } else { 0 },
        }
    }

    /// Whether the packet says its sender is ours and rings the [`DOORBELL`].
    pub fn doorbell(&self) -> bool {
        self.size == DOORBELL
    }

    pub fn encode(&self) -> [u8; PACKET_LEN] {
        let mut out = [0u8; PACKET_LEN];
        out[..4].copy_from_slice(&self.command.to_le_bytes());
        out[4..].copy_from_slice(&self.size.to_le_bytes());
        out
    }

    pub fn decode(b: &[u8; PACKET_LEN]) -> Packet {
        Packet {
            command: i32::from_le_bytes([b[0], b[1], b[2], b[3]]),
            size: i32::from_le_bytes([b[4], b[5], b[6], b[7]]),
        }
    }
}

/// The System V key of the ring of TCP port `port` after `resizes` resizes.
pub fn segment_key(port: u16, resizes: u32) -> i32 {
    (resizes << 16).wrapping_add(u32::from(port)) as i32
}

/// Resizes after which the key would leave the positive `int` range C++ computes it in.
pub const MAX_RESIZES: u32 = 0x7fff;

/// The file of the mutex guarding the ring of `port` (`temp_dir` ends with `/`, as
/// `ACE::get_temp_dir` returns it).
pub fn access_mutex_path(temp_dir: &str, port: u16) -> String {
    format!("{temp_dir}SHMEM_ACCESS_MUTEX_{port}")
}

/// The file of the mutex the reader of the ring of `port` waits on.
pub fn waitdata_mutex_path(temp_dir: &str, port: u16) -> String {
    format!("{temp_dir}SHMEM_WAITDATA_MUTEX_{port}")
}

/// What is wrong with a ring (a peer's bytes are untrusted).
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum ShmemError {
    #[error("shmem ring header: size {size} does not fit a segment of {capacity} data bytes")]
    BadSize { size: i32, capacity: usize },
    #[error(
        "shmem ring header is inconsistent (size {size}, head {head}, tail {tail}, avail {avail})"
    )]
    Inconsistent {
        size: i32,
        head: i32,
        tail: i32,
        avail: i32,
    },
    #[error("shmem ring resize to {newsize} bytes is not possible")]
    BadResize { newsize: i32 },
    #[error("shmem message of {len} bytes does not fit a ring")]
    TooLarge { len: usize },
}

/// A snapshot of a ring header, taken while holding the access mutex.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct RingHeader {
    pub resize: bool,
    pub close: bool,
    pub size: i32,
    pub newsize: i32,
    pub head: i32,
    pub tail: i32,
    pub avail: i32,
    pub waiting: i32,
}

/// Where the bytes of one read or write lie in the data area: one span, or two when
/// they wrap around its end.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Spans {
    pub first: (usize, usize),
    pub second: Option<(usize, usize)>,
}

impl Spans {
    pub fn len(&self) -> usize {
        self.first.1 + self.second.map_or(0, |s| s.1)
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

impl RingHeader {
    /// A fresh ring of `size` data bytes.
    pub fn new(size: i32) -> RingHeader {
        RingHeader {
            size,
            ..RingHeader::default()
        }
    }

    pub fn decode(b: &[u8; HEADER_LEN]) -> RingHeader {
        let int = |o: usize| i32::from_le_bytes([b[o], b[o + 1], b[o + 2], b[o + 3]]);
        RingHeader {
            resize: b[offset::RESIZE] != 0,
            close: b[offset::CLOSE] != 0,
            size: int(offset::SIZE),
            newsize: int(offset::NEWSIZE),
            head: int(offset::HEAD),
            tail: int(offset::TAIL),
            avail: int(offset::AVAIL),
            waiting: int(offset::WAITING),
        }
    }

    pub fn encode(&self) -> [u8; HEADER_LEN] {
        let mut b = [0u8; HEADER_LEN];
        b[offset::RESIZE] = u8::from(self.resize);
        b[offset::CLOSE] = u8::from(self.close);
        for (o, v) in [
            (offset::SIZE, self.size),
            (offset::NEWSIZE, self.newsize),
            (offset::HEAD, self.head),
            (offset::TAIL, self.tail),
            (offset::AVAIL, self.avail),
            (offset::WAITING, self.waiting),
        ] {
            b[o..o + 4].copy_from_slice(&v.to_le_bytes());
        }
        b
    }

    /// Checks the ring against the data bytes its segment really has: every span this
    /// header leads to then lies inside the segment.
    pub fn validate(&self, capacity: usize) -> Result<(), ShmemError> {
        if self.size <= 0 || self.size as usize > capacity {
            return Err(ShmemError::BadSize {
                size: self.size,
                capacity,
            });
        }
        let ok = (0..self.size).contains(&self.head)
            && (0..self.size).contains(&self.tail)
            && (0..=self.size).contains(&self.avail)
            && (self.tail as i64 + self.avail as i64) % self.size as i64 == self.head as i64;
        if !ok {
            return Err(ShmemError::Inconsistent {
                size: self.size,
                head: self.head,
                tail: self.tail,
                avail: self.avail,
            });
        }
        Ok(())
    }

    /// Free bytes.
    pub fn free(&self) -> usize {
        (self.size - self.avail).max(0) as usize
    }

    fn spans(&self, start: i32, len: usize) -> Spans {
        let size = self.size as usize;
        let start = start as usize;
        let first = len.min(size - start);
        Spans {
            first: (start, first),
            second: (first < len).then_some((0, len - first)),
        }
    }

    /// Up to `max` unread bytes (of a validated header).
    pub fn read_spans(&self, max: usize) -> Spans {
        self.spans(self.tail, max.min(self.avail as usize))
    }

    /// Room for `len` bytes at `head`, or fewer if the ring has less room (validated
    /// header).
    pub fn write_spans(&self, len: usize) -> Spans {
        self.spans(self.head, len.min(self.free()))
    }

    /// Records that `n` bytes (at most `avail`) were read.
    pub fn consume(&mut self, n: usize) {
        let n = n.min(self.avail.max(0) as usize) as i32;
        self.avail -= n;
        self.tail = ((self.tail as i64 + n as i64) % self.size as i64) as i32;
    }

    /// Records that `n` bytes (at most the free room) were written.
    pub fn produce(&mut self, n: usize) {
        let n = n.min(self.free()) as i32;
        self.avail += n;
        self.head = ((self.head as i64 + n as i64) % self.size as i64) as i32;
    }

    /// The size C++ grows a ring to when `len` bytes do not fit (`size + 2 * len`), or
    /// `None` when they fit.
    pub fn grown_size(&self, len: usize) -> Result<Option<i32>, ShmemError> {
        if self.free() >= len {
            return Ok(None);
        }
        let want = self.size as i64 + 2 * len as i64;
        i32::try_from(want)
            .map(Some)
            .map_err(|_| ShmemError::TooLarge { len })
    }

    /// The header of the ring that replaces this one after a resize to `newsize`: the
    /// unread bytes move to its start.
    pub fn resized(&self, newsize: i32) -> Result<RingHeader, ShmemError> {
        if newsize < self.avail || newsize <= 0 {
            return Err(ShmemError::BadResize { newsize });
        }
        Ok(RingHeader {
            resize: false,
            close: self.close,
            size: newsize,
            newsize: 0,
            head: self.avail % newsize,
            tail: 0,
            avail: self.avail,
            waiting: self.waiting,
        })
    }

    /// Checks a resize announced by the writer against the segment it names.
    pub fn validate_resize(&self, capacity: usize) -> Result<(), ShmemError> {
        if self.newsize <= 0 || self.newsize as usize > capacity {
            return Err(ShmemError::BadResize {
                newsize: self.newsize,
            });
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn layout_matches_cpp() {
        let h = RingHeader {
            resize: true,
            close: false,
            size: 4096,
            newsize: 8,
            head: 1,
            tail: 2,
            avail: 3,
            waiting: 4,
        };
        let b = h.encode();
        assert_eq!(b[0..4], [1, 0, 0, 0]);
        assert_eq!(b[4..8], 4096i32.to_le_bytes());
        assert_eq!(b[24..28], 4i32.to_le_bytes());
        assert_eq!(RingHeader::decode(&b), h);
        assert_eq!(Packet::connect(false).encode(), [0, 0, 0, 0, 0, 16, 0, 0]);
        assert_eq!(
            Packet::decode(&Packet::acknowledge(false).encode()).command,
            1
        );
        assert!(!Packet::connect(false).doorbell());
        assert!(Packet::decode(&Packet::acknowledge(true).encode()).doorbell());
        assert_eq!(segment_key(10002, 0), 10002);
        assert_eq!(segment_key(10002, 2), (2 << 16) + 10002);
        assert_eq!(
            access_mutex_path("/tmp/", 10002),
            "/tmp/SHMEM_ACCESS_MUTEX_10002"
        );
    }

    #[test]
    fn ring_arithmetic_wraps() {
        let mut h = RingHeader::new(10);
        h.validate(10).unwrap();
        assert_eq!(h.write_spans(4).len(), 4);
        h.produce(8);
        h.consume(6);
        assert_eq!((h.head, h.tail, h.avail), (8, 6, 2));
        let w = h.write_spans(5);
        assert_eq!(w.first, (8, 2));
        assert_eq!(w.second, Some((0, 3)));
        h.produce(5);
        assert_eq!((h.head, h.avail), (3, 7));
        let r = h.read_spans(100);
        assert_eq!(r.first, (6, 4));
        assert_eq!(r.second, Some((0, 3)));
        h.validate(10).unwrap();
        assert_eq!(h.grown_size(4).unwrap(), Some(18));
        assert_eq!(h.grown_size(3).unwrap(), None);
        let n = h.resized(18).unwrap();
        assert_eq!((n.head, n.tail, n.avail, n.size), (7, 0, 7, 18));
    }

    #[test]
    fn hostile_headers_are_refused() {
        let mut h = RingHeader::new(4096);
        assert!(h.validate(4095).is_err());
        h.avail = 5000;
        assert!(h.validate(4096).is_err());
        h.avail = 1;
        assert!(
            h.validate(4096).is_err(),
            "head does not follow tail + avail"
        );
        h.size = -1;
        assert!(h.validate(4096).is_err());
        let mut r = RingHeader::new(16);
        r.resize = true;
        r.newsize = 1 << 30;
        assert!(r.validate_resize(4096).is_err());
        let full = RingHeader {
            avail: i32::MAX,
            ..RingHeader::new(i32::MAX)
        };
        assert!(full.grown_size(1).is_err());
    }
}
