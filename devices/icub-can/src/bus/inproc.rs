//! An in-process CAN bus: any number of endpoints, every frame delivered to all the others.

use parking_lot::Mutex;
use std::collections::HashMap;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, OnceLock, Weak};
use std::time::Duration;

use super::{BusError, BusStats, CanBus, IdFilter, RxQueue, DEFAULT_RX_QUEUE};
use crate::frame::CanFrame;

/// A virtual bus; cheap to clone (all clones are the same bus).
#[derive(Clone)]
pub struct VirtualBus {
    hub: Arc<Hub>,
}

struct Hub {
    name: String,
    nodes: Mutex<Vec<Weak<RxQueue>>>,
    bus_off: AtomicBool,
}

impl VirtualBus {
    /// A new, private bus.
    pub fn new(name: impl Into<String>) -> Self {
        Self {
            hub: Arc::new(Hub {
                name: format!("inproc://{}", name.into()),
                nodes: Mutex::new(Vec::new()),
                bus_off: AtomicBool::new(false),
            }),
        }
    }

    /// The process-wide bus with this name, created on first use (`inproc://NAME`).
    pub fn named(name: &str) -> Self {
        static REGISTRY: OnceLock<Mutex<HashMap<String, VirtualBus>>> = OnceLock::new();
        let mut reg = REGISTRY.get_or_init(Default::default).lock();
        reg.entry(name.to_string())
            .or_insert_with(|| VirtualBus::new(name))
            .clone()
    }

    /// A new endpoint on this bus.
    pub fn endpoint(&self) -> VirtualEndpoint {
        let queue = Arc::new(RxQueue::new(DEFAULT_RX_QUEUE));
        let mut nodes = self.hub.nodes.lock();
        nodes.retain(|w| w.strong_count() > 0);
        nodes.push(Arc::downgrade(&queue));
        VirtualEndpoint {
            hub: self.hub.clone(),
            queue,
        }
    }

    /// Simulates (or clears) a bus-off condition: sends fail with [`BusError::BusOff`].
    pub fn set_bus_off(&self, off: bool) {
        self.hub.bus_off.store(off, Ordering::SeqCst);
    }

    /// Number of live endpoints.
    pub fn endpoints(&self) -> usize {
        let nodes = self.hub.nodes.lock();
        nodes.iter().filter(|w| w.strong_count() > 0).count()
    }
}

/// One node on a [`VirtualBus`].
pub struct VirtualEndpoint {
    hub: Arc<Hub>,
    queue: Arc<RxQueue>,
}

impl CanBus for VirtualEndpoint {
    fn name(&self) -> &str {
        &self.hub.name
    }

    fn send(&self, frame: &CanFrame) -> Result<(), BusError> {
        self.send_all(std::slice::from_ref(frame))
    }

    fn send_all(&self, frames: &[CanFrame]) -> Result<(), BusError> {
        if self.hub.bus_off.load(Ordering::SeqCst) {
            return Err(BusError::BusOff(self.hub.name.clone()));
        }
        // Collect receivers first so no queue lock is taken while holding the node list.
        let peers: Vec<Arc<RxQueue>> = {
            let nodes = self.hub.nodes.lock();
            nodes
                .iter()
                .filter_map(Weak::upgrade)
                .filter(|q| !Arc::ptr_eq(q, &self.queue))
                .collect()
        };
        for peer in &peers {
            peer.push_all(frames.iter().copied());
        }
        self.queue
            .tx_frames
            .fetch_add(frames.len() as u64, Ordering::Relaxed);
        Ok(())
    }

    fn recv(&self, timeout: Duration) -> Result<CanFrame, BusError> {
        self.queue.recv(&self.hub.name, timeout)
    }

    fn try_recv(&self) -> Result<Option<CanFrame>, BusError> {
        self.queue.try_recv(&self.hub.name)
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
    fn broadcast_to_all_but_sender() {
        let bus = VirtualBus::new("t");
        let (a, b, c) = (bus.endpoint(), bus.endpoint(), bus.endpoint());
        let f = CanFrame::new(0x101, &[1, 2]).unwrap();
        a.send(&f).unwrap();
        assert_eq!(b.recv(Duration::from_millis(100)).unwrap(), f);
        assert_eq!(c.recv(Duration::from_millis(100)).unwrap(), f);
        assert!(a.try_recv().unwrap().is_none());
        assert_eq!(a.stats().tx_frames, 1);
        assert_eq!(b.stats().rx_frames, 1);
    }

    #[test]
    fn filters_and_bus_off() {
        let bus = VirtualBus::new("t");
        let (a, b) = (bus.endpoint(), bus.endpoint());
        b.set_filter(IdFilter::ids([0x200]));
        a.send(&CanFrame::new(0x100, &[]).unwrap()).unwrap();
        a.send(&CanFrame::new(0x200, &[]).unwrap()).unwrap();
        assert_eq!(b.recv(Duration::from_millis(100)).unwrap().id(), 0x200);
        assert!(b.try_recv().unwrap().is_none());
        bus.set_bus_off(true);
        assert!(matches!(
            a.send(&CanFrame::new(1, &[]).unwrap()),
            Err(BusError::BusOff(_))
        ));
        bus.set_bus_off(false);
        assert!(a.send(&CanFrame::new(1, &[]).unwrap()).is_ok());
    }

    #[test]
    fn named_buses_are_shared_and_dropped_endpoints_leave() {
        let a = VirtualBus::named("shared-test").endpoint();
        let b = VirtualBus::named("shared-test").endpoint();
        a.send(&CanFrame::new(7, &[7]).unwrap()).unwrap();
        assert_eq!(b.recv(Duration::from_millis(100)).unwrap().data(), &[7]);
        let bus = VirtualBus::named("shared-test");
        assert_eq!(bus.endpoints(), 2);
        drop(b);
        assert_eq!(bus.endpoints(), 1);
    }
}
