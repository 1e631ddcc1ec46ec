//! One direction of a shmem connection: the ring buffer of C++ YARP's `ShmemOutputStream`
//! / `ShmemInputStream`, written by one process and read by the other (layout and rules in
//! [`yarp_proto::wire::shmem`]). Nothing here waits for the peer except for the access
//! mutex, which is held only for the moment of a copy; waiting for data is the caller's
//! (see [`RingReader::try_read`]).

use super::sys::{ProcessMutex, Segment};
use std::io;
use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;
use yarp_proto::wire::shmem::{
    access_mutex_path, segment_key, waitdata_mutex_path, RingHeader, ShmemError, HEADER_LEN,
    MAX_RESIZES,
};

/// Longest single wait before the side channel and the stop flag are checked again.
pub(crate) const POLL: Duration = Duration::from_millis(100);

/// Bytes copied per step: the writer publishes (and wakes the reader) after each, so that
/// a large message is read while it is still being written.
const CHUNK: usize = 256 * 1024;

/// The TCP connection of the handshake, kept to notice a peer that goes away (C++ does
/// the same) and, between two of our processes, to wake a waiting reader (the "doorbell":
/// one byte, so that the reader can wait in the event loop instead of on a mutex).
pub(crate) struct Liveness {
    pub(crate) sock: tokio::net::TcpStream,
    stop: Arc<AtomicBool>,
    doorbell: bool,
}

impl Liveness {
    pub(crate) fn new(
        sock: tokio::net::TcpStream,
        stop: Arc<AtomicBool>,
        doorbell: bool,
    ) -> Liveness {
        Liveness {
            sock,
            stop,
            doorbell,
        }
    }

    /// Whether the peer is ours and rings the doorbell.
    pub(crate) fn doorbell(&self) -> bool {
        self.doorbell
    }

    /// An error once the peer closed the side channel or this side was told to stop.
    pub(crate) fn check(&self) -> io::Result<()> {
        if self.stop.load(Ordering::Relaxed) {
            return Err(io::Error::new(
                io::ErrorKind::Interrupted,
                "shmem connection closed by this port",
            ));
        }
        let mut b = [std::mem::MaybeUninit::<u8>::uninit(); 1];
        match socket2::SockRef::from(&self.sock).peek(&mut b) {
            Ok(0) => Err(gone()),
            Ok(_) => Ok(()),
            Err(e) if e.kind() == io::ErrorKind::WouldBlock => Ok(()),
            Err(e) => Err(e),
        }
    }

    fn ring(&self) {
        if self.doorbell {
            // a full socket buffer means the reader has bells enough to wake up
            let _ = socket2::SockRef::from(&self.sock).send(&[1]);
        }
    }
}

pub(crate) fn gone() -> io::Error {
    io::Error::new(
        io::ErrorKind::UnexpectedEof,
        "the shmem peer went away (its TCP side channel closed)",
    )
}

fn bad(e: ShmemError) -> io::Error {
    io::Error::new(io::ErrorKind::InvalidData, e)
}

fn peer_closed() -> io::Error {
    io::Error::new(
        io::ErrorKind::ConnectionAborted,
        "the shmem peer closed the connection",
    )
}

/// A ring's segment and its two mutexes.
struct Ring {
    seg: Segment,
    access: ProcessMutex,
    waitdata: Arc<ProcessMutex>,
    port: u16,
    resizes: u32,
}

impl Ring {
    fn header(&self) -> RingHeader {
        // SAFETY: the segment is at least HEADER_LEN bytes (checked when attached).
        let b = unsafe { std::ptr::read_volatile(self.seg.ptr() as *const [u8; HEADER_LEN]) };
        RingHeader::decode(&b)
    }

    fn set_header(&self, h: &RingHeader) {
        // SAFETY: as `header`; written while holding the access mutex.
        unsafe { std::ptr::write_volatile(self.seg.ptr() as *mut [u8; HEADER_LEN], h.encode()) }
    }

    /// Data bytes the segment really has.
    fn capacity(&self) -> usize {
        self.seg.len() - HEADER_LEN
    }

    fn data(&self) -> *mut u8 {
        // SAFETY: inside the segment (len >= HEADER_LEN).
        unsafe { self.seg.ptr().add(HEADER_LEN) }
    }

    /// Takes the access mutex. It is held only while a copy of at most [`CHUNK`] bytes
    /// runs, so this rarely waits, and then briefly; a peer that died holding it is
    /// noticed on the side channel.
    fn lock(&self, live: &Liveness) -> io::Result<()> {
        if self.access.try_lock() {
            return Ok(());
        }
        loop {
            if self.access.lock_for(Duration::from_millis(10))? {
                return Ok(());
            }
            live.check()?;
        }
    }

    /// Tells the other side the connection is over and wakes it (bounded wait: a peer
    /// that died holding the mutex must not keep us).
    fn mark_closed(&self) {
        if let Ok(true) = self.access.lock_for(Duration::from_millis(500)) {
            let mut h = self.header();
            while h.waiting > 0 {
                h.waiting -= 1;
                self.waitdata.unlock();
            }
            h.close = true;
            self.set_header(&h);
            self.access.unlock();
        }
    }
}

fn check_segment(seg: &Segment) -> io::Result<()> {
    if seg.len() < HEADER_LEN {
        return Err(io::Error::new(
            io::ErrorKind::InvalidData,
            format!(
                "shmem segment of {} bytes has no room for a header",
                seg.len()
            ),
        ));
    }
    Ok(())
}

/// The ring this side writes (C++ `ShmemOutputStream`): created here, keyed by our port.
pub(crate) struct RingWriter {
    ring: Ring,
    /// Segments replaced by resizes that the reader may not have followed yet: kept (and
    /// reachable by key) until it did.
    old: Vec<Segment>,
}

impl RingWriter {
    pub(crate) fn create(temp_dir: &str, port: u16, size: i32) -> io::Result<RingWriter> {
        let seg = Segment::create(segment_key(port, 0), size as usize + HEADER_LEN)?;
        let access = ProcessMutex::create(Path::new(&access_mutex_path(temp_dir, port)))?;
        let waitdata = ProcessMutex::create(Path::new(&waitdata_mutex_path(temp_dir, port)))?;
        let ring = Ring {
            seg,
            access,
            waitdata: Arc::new(waitdata),
            port,
            resizes: 0,
        };
        ring.set_header(&RingHeader::new(size));
        Ok(RingWriter {
            ring,
            old: Vec::new(),
        })
    }

    /// Once the reader has the current segment, nobody needs any of ours by key: mark
    /// them all for removal, so that nothing outlives the two processes.
    fn tidy(&mut self) {
        if self.ring.seg.attached() >= 2 {
            for mut s in self.old.drain(..) {
                s.remove();
            }
            self.ring.seg.remove();
        }
    }

    /// Writes `parts` as one stream of bytes, growing the ring as C++ does when they do not
    /// fit, publishing every [`CHUNK`] so that the reader copies while we copy.
    pub(crate) fn write(&mut self, parts: &[&[u8]], live: &Liveness) -> io::Result<()> {
        let total: usize = parts.iter().map(|p| p.len()).sum();
        self.ring.lock(live)?;
        let reserved = self.reserve(total);
        self.ring.access.unlock();
        let (size, mut pos) = reserved?;
        self.tidy();
        let data = self.ring.data();
        let mut unpublished = 0usize;
        for part in parts {
            let mut rest: &[u8] = part;
            while !rest.is_empty() {
                let n = rest.len().min(CHUNK - unpublished);
                let first = n.min(size - pos);
                // SAFETY: `reserve` found at least `total` free bytes from `pos` on, which
                // the reader does not touch until they are published; spans lie within
                // `size`, which fits the segment (validated).
                unsafe {
                    std::ptr::copy_nonoverlapping(rest.as_ptr(), data.add(pos), first);
                    std::ptr::copy_nonoverlapping(rest.as_ptr().add(first), data, n - first);
                }
                pos = (pos + n) % size;
                rest = &rest[n..];
                unpublished += n;
                if unpublished == CHUNK {
                    self.publish(unpublished, size, live)?;
                    unpublished = 0;
                }
            }
        }
        if unpublished > 0 {
            self.publish(unpublished, size, live)?;
        }
        Ok(())
    }

    /// Under the access mutex: makes room for `len` bytes; the ring size and where they go.
    fn reserve(&mut self, len: usize) -> io::Result<(usize, usize)> {
        let mut h = self.ring.header();
        if h.close {
            return Err(peer_closed());
        }
        h.validate(self.ring.capacity()).map_err(bad)?;
        if let Some(newsize) = h.grown_size(len).map_err(bad)? {
            h = self.resize(h, newsize)?;
        }
        Ok((h.size as usize, h.head as usize))
    }

    /// C++ `ShmemOutputStreamImpl::Resize`: the next segment, the unread bytes moved to its
    /// start, the old header pointing the reader there.
    fn resize(&mut self, mut h: RingHeader, newsize: i32) -> io::Result<RingHeader> {
        let next = self.ring.resizes + 1;
        if next > MAX_RESIZES {
            return Err(bad(ShmemError::TooLarge {
                len: newsize as usize,
            }));
        }
        let nh = h.resized(newsize).map_err(bad)?;
        let seg = Segment::create(
            segment_key(self.ring.port, next),
            newsize as usize + HEADER_LEN,
        )?;
        check_segment(&seg)?;
        let spans = h.read_spans(h.avail as usize);
        // SAFETY: the spans lie within the old ring (validated header); the new segment
        // holds `newsize >= avail` data bytes.
        unsafe {
            let dst = seg.ptr().add(HEADER_LEN);
            let src = self.ring.data();
            let (o, n) = spans.first;
            std::ptr::copy_nonoverlapping(src.add(o), dst, n);
            if let Some((o2, n2)) = spans.second {
                std::ptr::copy_nonoverlapping(src.add(o2), dst.add(n), n2);
            }
        }
        h.resize = true;
        h.newsize = newsize;
        self.ring.set_header(&h);
        let old = std::mem::replace(&mut self.ring.seg, seg);
        self.ring.resizes = next;
        self.ring.set_header(&nh);
        if old.attached() >= 2 {
            // the reader has it: it will follow by key only to the new one
            let mut old = old;
            old.remove();
        } else {
            self.old.push(old);
        }
        Ok(nh)
    }

    fn publish(&mut self, n: usize, size: usize, live: &Liveness) -> io::Result<()> {
        self.ring.lock(live)?;
        let r = (|| -> io::Result<bool> {
            let mut h = self.ring.header();
            if h.close {
                return Err(peer_closed());
            }
            h.validate(self.ring.capacity()).map_err(bad)?;
            if h.size as usize != size || h.free() < n {
                return Err(io::Error::new(
                    io::ErrorKind::InvalidData,
                    "the shmem ring changed under its writer",
                ));
            }
            h.produce(n);
            let woke = h.waiting > 0;
            while h.waiting > 0 {
                h.waiting -= 1;
                self.ring.waitdata.unlock();
            }
            self.ring.set_header(&h);
            Ok(woke)
        })();
        self.ring.access.unlock();
        if r? {
            live.ring();
        }
        Ok(())
    }

    pub(crate) fn close(&mut self) {
        self.ring.mark_closed();
    }
}

impl Drop for RingWriter {
    fn drop(&mut self) {
        for s in self.old.iter_mut() {
            s.remove();
        }
        self.ring.seg.remove();
    }
}

/// The ring the peer writes (C++ `ShmemInputStream`): attached by the peer's port.
pub(crate) struct RingReader {
    ring: Ring,
}

impl RingReader {
    pub(crate) fn open(temp_dir: &str, port: u16) -> io::Result<RingReader> {
        let mut seg = Segment::open(segment_key(port, 0))?;
        check_segment(&seg)?;
        // the writer never looks its segments up again: gone with the last of us
        seg.remove();
        let access = ProcessMutex::open(Path::new(&access_mutex_path(temp_dir, port)))?;
        let waitdata = ProcessMutex::open(Path::new(&waitdata_mutex_path(temp_dir, port)))?;
        // held from now on; the writer unlocks it to wake us
        waitdata.try_lock();
        let ring = Ring {
            seg,
            access,
            waitdata: Arc::new(waitdata),
            port,
            resizes: 0,
        };
        ring.header().validate(ring.capacity()).map_err(bad)?;
        Ok(RingReader { ring })
    }

    /// Copies what is there (at most `dst_len` bytes) into `dst`; `None` when the ring is
    /// empty, in which case this reader is registered as waiting when `wait` (the writer
    /// then wakes it: the wait-data mutex for C++, the doorbell between ours).
    ///
    /// # Safety
    /// `dst` must be valid for writes of `dst_len` bytes.
    pub(crate) unsafe fn try_read(
        &mut self,
        dst: *mut u8,
        dst_len: usize,
        wait: bool,
        live: &Liveness,
    ) -> io::Result<Option<usize>> {
        self.ring.lock(live)?;
        // SAFETY: forwarded contract.
        let r = unsafe { self.read_locked(dst, dst_len, wait) };
        self.ring.access.unlock();
        r
    }

    /// The mutex a C++ writer unlocks to wake us.
    pub(crate) fn waitdata(&self) -> Arc<ProcessMutex> {
        self.ring.waitdata.clone()
    }

    /// Under the access mutex: copies what is there, or registers as waiting.
    unsafe fn read_locked(
        &mut self,
        dst: *mut u8,
        dst_len: usize,
        wait: bool,
    ) -> io::Result<Option<usize>> {
        let mut h = self.ring.header();
        if h.close {
            return Err(peer_closed());
        }
        while h.resize {
            let next = self.ring.resizes + 1;
            if next > MAX_RESIZES {
                return Err(bad(ShmemError::BadResize { newsize: h.newsize }));
            }
            let mut seg = Segment::open(segment_key(self.ring.port, next))?;
            check_segment(&seg)?;
            h.validate_resize(seg.len() - HEADER_LEN).map_err(bad)?;
            seg.remove();
            self.ring.seg = seg;
            self.ring.resizes = next;
            h = self.ring.header();
        }
        h.validate(self.ring.capacity()).map_err(bad)?;
        if h.avail == 0 {
            if wait {
                h.waiting = h.waiting.saturating_add(1);
                self.ring.set_header(&h);
            }
            return Ok(None);
        }
        let spans = h.read_spans(dst_len.min(CHUNK));
        let src = self.ring.data();
        // SAFETY: spans lie within the validated ring; `dst` holds `dst_len` bytes.
        unsafe {
            let (o, n) = spans.first;
            std::ptr::copy_nonoverlapping(src.add(o), dst, n);
            if let Some((o2, n2)) = spans.second {
                std::ptr::copy_nonoverlapping(src.add(o2), dst.add(n), n2);
            }
        }
        h.consume(spans.len());
        self.ring.set_header(&h);
        Ok(Some(spans.len()))
    }

    pub(crate) fn close(&mut self) {
        self.ring.mark_closed();
    }
}
