//! Linux SocketCAN through the `socketcan` crate (real adapters, `vcan`).
//!
//! Opening fails with a clear [`BusError::Io`] on kernels without `AF_CAN` or when the
//! interface does not exist. A reader thread moves frames into the common receive queue.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::Duration;

use socketcan::{CanSocket, EmbeddedFrame, Frame, Socket};

use super::{BusError, BusStats, CanBus, IdFilter, RxQueue, DEFAULT_RX_QUEUE};
use crate::frame::CanFrame;

/// An endpoint on a SocketCAN interface.
pub struct SocketCanBus {
    name: String,
    socket: Arc<CanSocket>,
    queue: Arc<RxQueue>,
    stop: Arc<AtomicBool>,
    reader: Option<JoinHandle<()>>,
}

impl SocketCanBus {
    /// Opens interface `iface` (e.g. `can0`, `vcan1`).
    pub fn open(iface: &str) -> Result<Self, BusError> {
        let name = format!("socketcan://{iface}");
        let io = |source: std::io::Error| BusError::Io {
            bus: name.clone(),
            source,
        };
        let socket = CanSocket::open(iface).map_err(|e| {
            io(std::io::Error::new(
                e.kind(),
                format!("cannot open SocketCAN interface {iface:?}: {e}"),
            ))
        })?;
        socket
            .set_read_timeout(Duration::from_millis(50))
            .map_err(io)?;
        let socket = Arc::new(socket);
        let queue = Arc::new(RxQueue::new(DEFAULT_RX_QUEUE));
        let stop = Arc::new(AtomicBool::new(false));
        let (s, q, st, n) = (socket.clone(), queue.clone(), stop.clone(), name.clone());
        let reader = std::thread::Builder::new()
            .name(format!("can {iface}"))
            .spawn(move || {
                while !st.load(Ordering::Relaxed) {
                    match s.read_frame() {
                        Ok(f) => match CanFrame::from_id_word(f.id_word(), f.data(), f.dlc() as u8)
                        {
                            Ok(frame) => q.push(frame),
                            Err(_) => {
                                q.malformed.fetch_add(1, Ordering::Relaxed);
                            }
                        },
                        Err(e)
                            if matches!(
                                e.kind(),
                                std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                            ) => {}
                        Err(e) => {
                            q.close(format!("{n}: {e}"));
                            return;
                        }
                    }
                }
            })
            .map_err(io)?;
        Ok(Self {
            name,
            socket,
            queue,
            stop,
            reader: Some(reader),
        })
    }
}

impl Drop for SocketCanBus {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(h) = self.reader.take() {
            let _ = h.join();
        }
    }
}

fn to_socketcan(f: &CanFrame) -> Option<socketcan::CanFrame> {
    let id: socketcan::Id = if f.is_extended() {
        socketcan::ExtendedId::new(f.id())?.into()
    } else {
        socketcan::StandardId::new(f.id() as u16)?.into()
    };
    if f.is_remote() {
        socketcan::CanFrame::new_remote(id, f.len())
    } else {
        socketcan::CanFrame::new(id, f.data())
    }
}

impl CanBus for SocketCanBus {
    fn name(&self) -> &str {
        &self.name
    }

    fn send(&self, frame: &CanFrame) -> Result<(), BusError> {
        let f = to_socketcan(frame)
            .ok_or_else(|| BusError::Config(format!("frame {frame} not representable")))?;
        match self.socket.write_frame(&f) {
            Ok(()) => {
                self.queue.tx_frames.fetch_add(1, Ordering::Relaxed);
                Ok(())
            }
            // ENETDOWN is what the kernel reports for a bus-off / down controller.
            Err(e) if e.raw_os_error() == Some(100) => Err(BusError::BusOff(self.name.clone())),
            Err(source) => Err(BusError::Io {
                bus: self.name.clone(),
                source,
            }),
        }
    }

    fn recv(&self, timeout: Duration) -> Result<CanFrame, BusError> {
        self.queue.recv(&self.name, timeout)
    }

    fn try_recv(&self) -> Result<Option<CanFrame>, BusError> {
        self.queue.try_recv(&self.name)
    }

    fn set_filter(&self, filter: IdFilter) {
        self.queue.set_filter(filter);
    }

    fn stats(&self) -> BusStats {
        self.queue.stats()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn missing_interface_is_a_clear_error() {
        let err = SocketCanBus::open("nosuchcan9").err().expect("must fail");
        let msg = err.to_string();
        assert!(msg.contains("nosuchcan9"), "{msg}");
    }

    #[test]
    fn frames_convert() {
        let f = to_socketcan(&CanFrame::new(0x123, &[1, 2]).unwrap()).unwrap();
        assert_eq!(f.id_word(), 0x123);
        let r = to_socketcan(&CanFrame::new_remote(0x1234, true, 2).unwrap()).unwrap();
        assert!(r.is_remote_frame());
    }
}
