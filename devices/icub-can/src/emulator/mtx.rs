//! An emulated Xsens sensor served on a serial port: the MTx of the iCub head
//! ([`crate::xsens::EmulatedMtx`], `MTData`) or an MTi such as the ergoCub waist's
//! ([`crate::xsens::mti::EmulatedMti`], `MTData2`). It answers the host's configuration
//! messages and, while measuring, streams at its period with
//! [`crate::xsens::emulated_motion`].
//!
//! [`pty_link`] makes a pseudo-terminal whose device path a configuration can name (as
//! `serial` of `xsensmtx`), so no hardware or kernel serial driver is needed.

use crate::xsens::mti::EmulatedMti;
use crate::xsens::{emulated_motion, Decoder, EmulatedMtx, Message, Sample};
use serialport::{SerialPort, TTYPort};
use std::io::{ErrorKind, Read, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// A running emulated MTx; stops (and closes its port) on drop.
pub struct MtxHandle {
    stop: Arc<AtomicBool>,
    /// While set, the sensor neither answers nor streams (an unplugged cable).
    pub silent: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
    /// A link made by [`pty_link`] and the terminal it names, removed on drop.
    link: Option<(PathBuf, PathBuf)>,
}

impl MtxHandle {
    /// Makes the sensor go quiet (`true`) or come back (`false`).
    pub fn set_silent(&self, silent: bool) {
        self.silent.store(silent, Ordering::SeqCst);
    }
}

impl Drop for MtxHandle {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::SeqCst);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
        // Remove our link, unless someone has since pointed it elsewhere.
        if let Some((link, pts)) = self.link.take() {
            if std::fs::read_link(&link).is_ok_and(|target| target == pts) {
                let _ = std::fs::remove_file(&link);
            }
        }
    }
}

/// The emulator's end of a serial line: bytes both ways, and reads that give up after
/// a settable time.
pub trait MtxPort: Read + Write + Send + 'static {
    /// How long the next reads may wait for a byte.
    fn set_read_timeout(&mut self, timeout: Duration) -> std::io::Result<()>;
}

/// The longest read of the emulator thread (bounds how long stopping takes).
const MAX_READ_WAIT: Duration = Duration::from_millis(50);

/// An emulated Xsens sensor as a state machine.
pub trait EmulatedMt: Send + 'static {
    /// The replies to one host message.
    fn handle(&mut self, m: &Message) -> Vec<Message>;
    /// How often [`Self::sample_at`] is asked (s).
    fn period_s(&self) -> f64;
    /// The data message due at `t` (s since start) of motion `s`, when measuring.
    fn sample_at(&mut self, t: f64, s: &Sample) -> Option<Message>;
}

impl EmulatedMt for EmulatedMtx {
    fn handle(&mut self, m: &Message) -> Vec<Message> {
        EmulatedMtx::handle(self, m)
    }
    fn period_s(&self) -> f64 {
        EmulatedMtx::period_s(self)
    }
    fn sample_at(&mut self, _t: f64, s: &Sample) -> Option<Message> {
        self.sample(s)
    }
}

impl EmulatedMt for EmulatedMti {
    fn handle(&mut self, m: &Message) -> Vec<Message> {
        EmulatedMti::handle(self, m)
    }
    fn period_s(&self) -> f64 {
        EmulatedMti::period_s(self)
    }
    fn sample_at(&mut self, t: f64, s: &Sample) -> Option<Message> {
        self.sample(t, s)
    }
}

/// Serves `mtx` on `port` in a thread until the handle is dropped, streaming
/// `motion(seconds since start)`. The thread waits in its reads until the next sample
/// is due.
pub fn serve(
    mut port: impl MtxPort,
    mut mtx: impl EmulatedMt,
    mut motion: impl FnMut(f64) -> Sample + Send + 'static,
) -> std::io::Result<MtxHandle> {
    let stop = Arc::new(AtomicBool::new(false));
    let silent = Arc::new(AtomicBool::new(false));
    let (st, si) = (stop.clone(), silent.clone());
    let thread = std::thread::Builder::new()
        .name("xsens-mtx".into())
        .spawn(move || {
            let start = Instant::now();
            let mut next = Instant::now();
            let mut dec = Decoder::new();
            let mut buf = [0u8; 256];
            while !st.load(Ordering::SeqCst) {
                let wait = next.saturating_duration_since(Instant::now());
                let _ =
                    port.set_read_timeout(wait.clamp(Duration::from_micros(100), MAX_READ_WAIT));
                match port.read(&mut buf) {
                    Ok(n) if !si.load(Ordering::SeqCst) => dec.push(&buf[..n]),
                    Ok(_) => {}
                    Err(e) if e.kind() == ErrorKind::TimedOut => {}
                    Err(e) if e.kind() == ErrorKind::Interrupted => {}
                    Err(e) => {
                        // The host side closed (pty hang-up): wait for it to come back.
                        tracing::trace!("emulated MTx: {e}");
                        std::thread::sleep(Duration::from_millis(10));
                    }
                }
                while let Some(r) = dec.next_message() {
                    match r {
                        Ok(m) => {
                            for reply in mtx.handle(&m) {
                                let _ = port.write_all(&reply.encode());
                            }
                        }
                        Err(e) => tracing::debug!("emulated MTx: {e}"),
                    }
                }
                if Instant::now() >= next {
                    let t = start.elapsed().as_secs_f64();
                    if !si.load(Ordering::SeqCst) {
                        if let Some(m) = mtx.sample_at(t, &motion(t)) {
                            let _ = port.write_all(&m.encode());
                        }
                    }
                    next += Duration::from_secs_f64(mtx.period_s());
                    if next < Instant::now() {
                        next = Instant::now(); // fell behind: no burst to catch up
                    }
                }
            }
        })?;
    Ok(MtxHandle {
        stop,
        silent,
        thread: Some(thread),
        link: None,
    })
}

/// A pseudo-terminal pair: the emulator's end (reads time out after 2 ms until set
/// otherwise), and the path a host opens.
pub fn pty() -> std::io::Result<(impl MtxPort, PathBuf)> {
    let (mut master, slave) = TTYPort::pair().map_err(std::io::Error::other)?;
    master
        .set_timeout(Duration::from_millis(2))
        .map_err(std::io::Error::other)?;
    let path = slave
        .name()
        .map(PathBuf::from)
        .ok_or_else(|| std::io::Error::other("pseudo-terminal without a name"))?;
    Ok((
        PtyEnds {
            master,
            _slave: slave,
        },
        path,
    ))
}

/// Serves an emulated MTx on a new pseudo-terminal reachable as `link` (a symbolic link
/// replacing any earlier one, removed when the handle is dropped), e.g. the `serial` path
/// a robot file names.
pub fn pty_link(link: &Path) -> std::io::Result<(MtxHandle, PathBuf)> {
    pty_link_with(link, EmulatedMtx::default())
}

/// [`pty_link`] for any emulated sensor, e.g. an [`EmulatedMti`].
pub fn pty_link_with(link: &Path, mt: impl EmulatedMt) -> std::io::Result<(MtxHandle, PathBuf)> {
    pty_link_moving(link, mt, emulated_motion)
}

/// As [`pty_link_with`], streaming what `motion(seconds since start)` gives (a body's
/// reading of the sensor) instead of the emulated head's motion.
pub fn pty_link_moving(
    link: &Path,
    mt: impl EmulatedMt,
    motion: impl FnMut(f64) -> Sample + Send + 'static,
) -> std::io::Result<(MtxHandle, PathBuf)> {
    let (port, path) = pty()?;
    if link.symlink_metadata().is_ok() {
        std::fs::remove_file(link)?;
    }
    std::os::unix::fs::symlink(&path, link)?;
    let mut handle = serve(port, mt, motion)?;
    handle.link = Some((link.to_path_buf(), path.clone()));
    Ok((handle, path))
}

/// The master end of a pty, with its slave end kept open so that a host closing and
/// reopening the path causes no hang-up on the master.
struct PtyEnds {
    master: TTYPort,
    _slave: TTYPort,
}

impl Read for PtyEnds {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        self.master.read(buf)
    }
}

impl MtxPort for PtyEnds {
    fn set_read_timeout(&mut self, timeout: Duration) -> std::io::Result<()> {
        self.master
            .set_timeout(timeout)
            .map_err(std::io::Error::other)
    }
}

impl Write for PtyEnds {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.master.write(buf)
    }
    fn flush(&mut self) -> std::io::Result<()> {
        self.master.flush()
    }
}
