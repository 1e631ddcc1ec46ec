//! The `shmem` carrier between real ports: data of every size (ring resizes included),
//! envelopes, RPC replies, and hostile or dying peers (a hand-made peer that speaks the
//! C++ layout: System V segment keyed by its port, pthread mutexes in files). Nothing may
//! be left behind: no segment, no mutex file. Run under ../shared/netns-run.

mod common;
use common::{eventually, T};
use std::io::{Read, Write};
use std::path::PathBuf;
use std::sync::OnceLock;
use std::time::Duration;
use tokio::time::timeout;
use yarp_net::nameserver::NameClient;
use yarp_net::port::Port;
use yarp_proto::wire::shmem::{self, Packet, RingHeader, HEADER_LEN};
use yarp_proto::wire::{self, Carrier, YarpNumber};
use yarp_proto::{bottle, Bottle, Stamp, Value};

/// A private temp dir for the mutex files of this test binary (set before any port runs);
/// those of earlier runs whose process is gone are removed.
fn temp() -> &'static PathBuf {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        let tmp = std::env::temp_dir();
        for e in std::fs::read_dir(&tmp).into_iter().flatten().flatten() {
            let name = e.file_name().to_string_lossy().into_owned();
            let pid = name
                .strip_prefix("yarp-rs-shmem-")
                .and_then(|p| p.parse::<u32>().ok());
            if pid.is_some_and(|p| !std::path::Path::new(&format!("/proc/{p}")).exists()) {
                let _ = std::fs::remove_dir_all(e.path());
            }
        }
        let d = tmp.join(format!("yarp-rs-shmem-{}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        std::env::set_var("TMPDIR", &d);
        d
    })
}

async fn name_server() -> (NameClient, yarp_net::nameserver::ShutdownHandle) {
    temp();
    common::name_server().await
}

/// System V segments created by this process that still exist.
fn my_segments() -> Vec<String> {
    let me = std::process::id().to_string();
    std::fs::read_to_string("/proc/sysvipc/shm")
        .unwrap_or_default()
        .lines()
        .skip(1)
        .filter(|l| l.split_whitespace().nth(4) == Some(me.as_str()))
        .map(str::to_string)
        .collect()
}

fn mutex_files() -> Vec<String> {
    std::fs::read_dir(temp())
        .map(|d| {
            d.filter_map(|e| e.ok())
                .map(|e| e.file_name().to_string_lossy().into_owned())
                .filter(|n| n.starts_with("SHMEM_"))
                .collect()
        })
        .unwrap_or_default()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn shmem_between_ports_every_size_rpc_and_no_leftovers() {
    let (ns, stop) = name_server().await;
    let w = Port::open("/ws", ns.clone()).await.unwrap();
    let r = Port::open("/rs", ns.clone()).await.unwrap();
    w.connect("/rs", Some("shmem"))
        .await
        .expect("shmem connect");
    eventually("input appears", || !r.inputs().is_empty()).await;
    // sizes across the initial 4 KiB ring, its growth and wrap-around
    for (i, n) in [10usize, 5000, 100_000, 3 << 20, 100, 9 << 20, 7]
        .iter()
        .enumerate()
    {
        let b = bottle![i as i32, "x", Value::Blob(vec![7u8; *n])];
        assert_eq!(w.write_stamped(&b, Stamp::new(i as i32, 0.5)).await, 1);
        let m = timeout(T, r.read()).await.unwrap().unwrap();
        assert_eq!(m.stamp, Some(Stamp::new(i as i32, 0.5)));
        assert_eq!(m.from, "/ws");
        assert_eq!(m.bottle().unwrap(), b, "size {n}");
    }
    // RPC: the reply travels back through the other ring
    let server = tokio::spawn(async move {
        for _ in 0..2 {
            let mut m = timeout(T, r.read()).await.unwrap().unwrap();
            let mut b = m.bottle().unwrap();
            b.push(Value::Blob(vec![1u8; 2 << 20]));
            m.reply(b);
        }
        r
    });
    for k in 0..2 {
        let reply = timeout(T, w.rpc(&bottle!["ping", k]))
            .await
            .unwrap()
            .unwrap();
        assert_eq!(reply.get(1).and_then(|v| v.as_i32()), Some(k));
        assert_eq!(
            reply.get(2).and_then(|v| v.as_bytes()).map(<[u8]>::len),
            Some(2 << 20)
        );
    }
    let r = server.await.unwrap();
    assert!(w.disconnect("/rs"));
    eventually("input removed after q", || r.inputs().is_empty()).await;
    eventually("no segment left", || my_segments().is_empty()).await;
    eventually("no mutex file left", || mutex_files().is_empty()).await;
    stop.shutdown();
}

/// A peer written against the C++ layout by hand: it connects to `port` with the shmem
/// header, creates its ring keyed by its side-channel port, and attaches ours.
struct RawPeer {
    side: std::net::TcpStream,
    seg: *mut u8,
    seg_len: usize,
    id: i32,
    files: Vec<PathBuf>,
    mutexes: Vec<*mut libc::pthread_mutex_t>,
}

// SAFETY: the raw pointers are mappings shared between processes anyway; one thread at a
// time uses the peer.
unsafe impl Send for RawPeer {}

impl RawPeer {
    fn connect(port: u16, name: &str, size: usize) -> RawPeer {
        let mut tcp = std::net::TcpStream::connect(("127.0.0.1", port)).unwrap();
        tcp.write_all(&wire::encode_connection_start(
            &Carrier::Shmem.spec(),
            name.as_bytes(),
        ))
        .unwrap();
        let mut reply = [0u8; 8];
        tcp.read_exact(&mut reply).unwrap();
        let alt = YarpNumber::decode(&reply).unwrap().0 as u16;
        drop(tcp);
        let side = std::net::TcpStream::connect(("127.0.0.1", alt)).unwrap();
        let me = side.local_addr().unwrap().port();
        let key = shmem::segment_key(me, 0);
        let seg_len = size + HEADER_LEN;
        // SAFETY: test-only raw System V calls on a fresh segment.
        let (id, seg) = unsafe {
            let id = libc::shmget(key, seg_len, libc::IPC_CREAT | libc::IPC_EXCL | 0o644);
            assert!(id >= 0, "shmget: {}", std::io::Error::last_os_error());
            let p = libc::shmat(id, std::ptr::null(), 0) as *mut u8;
            (id, p)
        };
        let t = format!("{}/", temp().display());
        let mut peer = RawPeer {
            side,
            seg,
            seg_len,
            id,
            files: Vec::new(),
            mutexes: Vec::new(),
        };
        for path in [
            shmem::access_mutex_path(&t, me),
            shmem::waitdata_mutex_path(&t, me),
        ] {
            peer.make_mutex(PathBuf::from(path));
        }
        peer.set_header(&RingHeader::new(size as i32));
        peer.side
            .write_all(&Packet::connect(false).encode())
            .unwrap();
        let mut ack = [0u8; 8];
        peer.side.read_exact(&mut ack).unwrap();
        assert_eq!(Packet::decode(&ack).command, shmem::command::ACKNOWLEDGE);
        peer
    }

    fn make_mutex(&mut self, path: PathBuf) {
        let size = std::mem::size_of::<libc::pthread_mutex_t>();
        let f = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .create(true)
            .truncate(true)
            .open(&path)
            .unwrap();
        f.set_len(size as u64).unwrap();
        use std::os::fd::AsRawFd;
        // SAFETY: test-only mapping of the file just sized.
        unsafe {
            let p = libc::mmap(
                std::ptr::null_mut(),
                size,
                libc::PROT_READ | libc::PROT_WRITE,
                libc::MAP_SHARED,
                f.as_raw_fd(),
                0,
            ) as *mut libc::pthread_mutex_t;
            let mut a: libc::pthread_mutexattr_t = std::mem::zeroed();
            libc::pthread_mutexattr_init(&mut a);
            libc::pthread_mutexattr_setpshared(&mut a, libc::PTHREAD_PROCESS_SHARED);
            libc::pthread_mutex_init(p, &a);
            self.mutexes.push(p);
        }
        self.files.push(path);
    }

    fn header(&self) -> RingHeader {
        // SAFETY: the segment is ours and longer than a header.
        RingHeader::decode(unsafe { &*(self.seg as *const [u8; HEADER_LEN]) })
    }

    fn set_header(&self, h: &RingHeader) {
        // SAFETY: as `header`.
        unsafe { std::ptr::write_volatile(self.seg as *mut [u8; HEADER_LEN], h.encode()) }
    }

    /// Appends bytes as a C++ writer does (under the access mutex, waking the reader).
    fn write(&self, bytes: &[u8]) {
        // SAFETY: the mutexes are initialised; spans come from the ring arithmetic.
        unsafe {
            libc::pthread_mutex_lock(self.mutexes[0]);
            let mut h = self.header();
            let s = h.write_spans(bytes.len());
            assert_eq!(s.len(), bytes.len(), "test ring too small");
            let data = self.seg.add(HEADER_LEN);
            std::ptr::copy_nonoverlapping(bytes.as_ptr(), data.add(s.first.0), s.first.1);
            if let Some((o, n)) = s.second {
                std::ptr::copy_nonoverlapping(bytes.as_ptr().add(s.first.1), data.add(o), n);
            }
            h.produce(bytes.len());
            while h.waiting > 0 {
                h.waiting -= 1;
                libc::pthread_mutex_unlock(self.mutexes[1]);
            }
            self.set_header(&h);
            libc::pthread_mutex_unlock(self.mutexes[0]);
        }
    }

    /// Overwrites the header (as a hostile peer would), waking the reader.
    fn poke(&self, f: impl FnOnce(&mut RingHeader)) {
        // SAFETY: as `write`.
        unsafe {
            libc::pthread_mutex_lock(self.mutexes[0]);
            let mut h = self.header();
            f(&mut h);
            h.waiting = 0;
            self.set_header(&h);
            libc::pthread_mutex_unlock(self.mutexes[1]);
            libc::pthread_mutex_unlock(self.mutexes[0]);
        }
    }
}

impl Drop for RawPeer {
    fn drop(&mut self) {
        // SAFETY: detaching and removing what `connect` made.
        unsafe {
            libc::shmdt(self.seg.cast());
            libc::shmctl(self.id, libc::IPC_RMID, std::ptr::null_mut());
        }
        let _ = self.seg_len;
        for f in &self.files {
            let _ = std::fs::remove_file(f);
        }
    }
}

fn message(b: &Bottle) -> Vec<u8> {
    wire::data_message(b, false)
}

/// Runs a hostile peer against a fresh port; the port's input must end by itself and
/// leave nothing behind.
async fn hostile(name: &str, act: impl FnOnce(&mut RawPeer) + Send + 'static) {
    let (ns, stop) = name_server().await;
    let r = Port::open(name, ns.clone()).await.unwrap();
    let port = r.contact().port;
    let from = format!("{name}-peer");
    let peer = tokio::task::spawn_blocking(move || {
        let p = RawPeer::connect(port, &from, 4096);
        // one good message first: the connection works
        p.write(&message(&bottle!["fine", 1]));
        p
    })
    .await
    .unwrap();
    let m = timeout(T, r.read()).await.unwrap().unwrap();
    assert_eq!(m.bottle().unwrap(), bottle!["fine", 1]);
    assert_eq!(r.inputs().len(), 1);
    let peer = tokio::task::spawn_blocking(move || {
        let mut p = peer;
        act(&mut p);
        p
    })
    .await
    .unwrap();
    eventually("the input ends", || r.inputs().is_empty()).await;
    drop(peer);
    eventually("no segment left", || my_segments().is_empty()).await;
    let mine: Vec<_> = mutex_files();
    assert!(mine.is_empty(), "left-over mutex files: {mine:?}");
    stop.shutdown();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_peer_that_dies_mid_message_ends_the_connection() {
    hostile("/dies", |p| {
        let msg = message(&bottle![Value::Blob(vec![9u8; 3000])]);
        p.write(&msg[..1000]);
        // the process "dies": its side channel closes, the rest never comes
        p.side.shutdown(std::net::Shutdown::Both).unwrap();
    })
    .await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_hostile_ring_size_ends_the_connection() {
    hostile("/huge", |p| {
        p.write(&message(&bottle![1])[..10]);
        p.poke(|h| h.size = 1 << 30);
        std::thread::sleep(Duration::from_millis(300));
    })
    .await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_resize_to_a_segment_of_the_wrong_size_ends_the_connection() {
    hostile("/resize", |p| {
        // announce a resize to 1 MiB but provide a segment of 8 KiB under the next key
        let me = p.side.local_addr().unwrap().port();
        // SAFETY: test-only segment, removed below.
        let id = unsafe {
            libc::shmget(
                shmem::segment_key(me, 1),
                8192 + HEADER_LEN,
                libc::IPC_CREAT | 0o644,
            )
        };
        assert!(id >= 0);
        p.poke(|h| {
            h.resize = true;
            h.newsize = 1 << 20;
        });
        std::thread::sleep(Duration::from_millis(300));
        // SAFETY: removing the segment made above.
        unsafe {
            libc::shmctl(id, libc::IPC_RMID, std::ptr::null_mut());
        }
    })
    .await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_hostile_index_is_refused() {
    hostile("/index", |p| {
        // an index announcing blocks of 2 GiB each
        let mut bad = Vec::new();
        wire::Index::new(vec![8, 0x7fff_ffff, 0x7fff_ffff]).encode(&mut bad);
        p.write(&bad);
        std::thread::sleep(Duration::from_millis(300));
    })
    .await;
}
