//! The reader thread and request/reply matching shared by all clients.

use parking_lot::{Condvar, Mutex};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use super::ClientError;
use crate::bus::{BusError, CanBus};
use crate::frame::CanFrame;
use crate::proto::Message;

type Matcher = Box<dyn Fn(&Message) -> bool + Send>;

struct Pending {
    matcher: Matcher,
    reply: Option<Message>,
}

/// Owns the bus endpoint's reader thread; serialises polling requests.
pub(crate) struct Link {
    pub(crate) bus: Arc<dyn CanBus>,
    pub(crate) host: u8,
    request_lock: Mutex<()>,
    pending: Mutex<Option<Pending>>,
    replied: Condvar,
    stop: AtomicBool,
    /// Frames that did not decode as iCub messages.
    pub(crate) malformed: AtomicU64,
    /// Set when the bus reported a fatal error (closed).
    pub(crate) dead: Mutex<Option<String>>,
}

impl Link {
    /// Starts the reader; `on_message` sees every decoded message that is not a reply
    /// being waited for.
    pub(crate) fn start(
        bus: Arc<dyn CanBus>,
        host: u8,
        mut on_message: impl FnMut(&Message) + Send + 'static,
    ) -> Result<(Arc<Self>, JoinHandle<()>), ClientError> {
        let link = Arc::new(Self {
            bus,
            host,
            request_lock: Mutex::new(()),
            pending: Mutex::new(None),
            replied: Condvar::new(),
            stop: AtomicBool::new(false),
            malformed: AtomicU64::new(0),
            dead: Mutex::new(None),
        });
        let l = link.clone();
        let thread = std::thread::Builder::new()
            .name(format!("icub-can client {}", link.bus.name()))
            .spawn(move || {
                while !l.stop.load(Ordering::Relaxed) {
                    let frame = match l.bus.recv(Duration::from_millis(50)) {
                        Ok(f) => f,
                        Err(BusError::Timeout(_)) => continue,
                        Err(e) => {
                            *l.dead.lock() = Some(e.to_string());
                            l.replied.notify_all();
                            return;
                        }
                    };
                    let msg = match Message::decode_for(&frame, l.host) {
                        Ok(m) => m,
                        Err(e) => {
                            l.malformed.fetch_add(1, Ordering::Relaxed);
                            tracing::debug!(bus = l.bus.name(), %frame, "ignoring malformed frame: {e}");
                            continue;
                        }
                    };
                    {
                        let mut p = l.pending.lock();
                        if let Some(pending) = p.as_mut() {
                            if pending.reply.is_none() && (pending.matcher)(&msg) {
                                pending.reply = Some(msg);
                                l.replied.notify_all();
                                continue;
                            }
                        }
                    }
                    on_message(&msg);
                }
            })
            .map_err(|e| ClientError::Config(format!("cannot start reader thread: {e}")))?;
        Ok((link, thread))
    }

    pub(crate) fn stop(&self) {
        self.stop.store(true, Ordering::Relaxed);
    }

    fn check_alive(&self) -> Result<(), ClientError> {
        match self.dead.lock().as_ref() {
            Some(reason) => Err(ClientError::Bus(BusError::Closed(reason.clone()))),
            None => Ok(()),
        }
    }

    pub(crate) fn send(&self, frames: &[CanFrame]) -> Result<(), ClientError> {
        self.check_alive()?;
        Ok(self.bus.send_all(frames)?)
    }

    /// Sends `frame` and waits at most `timeout` for a message accepted by `matcher`.
    pub(crate) fn request(
        &self,
        frame: CanFrame,
        matcher: impl Fn(&Message) -> bool + Send + 'static,
        timeout: Duration,
    ) -> Result<Option<Message>, ClientError> {
        let _one_at_a_time = self.request_lock.lock();
        self.check_alive()?;
        *self.pending.lock() = Some(Pending {
            matcher: Box::new(matcher),
            reply: None,
        });
        let sent = self.bus.send(&frame);
        let deadline = Instant::now() + timeout;
        let mut p = self.pending.lock();
        if let Err(e) = sent {
            *p = None;
            return Err(e.into());
        }
        loop {
            if let Some(reply) = p.as_mut().and_then(|x| x.reply.take()) {
                *p = None;
                return Ok(Some(reply));
            }
            let now = Instant::now();
            if now >= deadline || self.dead.lock().is_some() {
                *p = None;
                drop(p);
                self.check_alive()?;
                return Ok(None);
            }
            self.replied.wait_for(&mut p, deadline - now);
        }
    }
}
