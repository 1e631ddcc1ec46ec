//! The open `canmotioncontrol` boards of this process, by axis name.
//!
//! C++ `parametricCalibrator` reaches `IControlCalibration` through the device it is
//! given (usually a `controlboardremapper`). Here `canmotioncontrol` registers its
//! joints on open and the calibrator finds, for each joint of its target (by the
//! target's `IAxisInfo` names), the board that drives it: its `IRemoteCalibrator` calls
//! arrive while the target is locked by their caller, so they cannot go through it. Registrations end when their handle is dropped.

use parking_lot::Mutex;
use std::sync::{Arc, Weak};

use icub_can::client::MotorControlClient;

struct Entry {
    axis: String,
    joint: usize,
    client: Weak<MotorControlClient>,
    owner: u64,
}

static TABLE: Mutex<Vec<Entry>> = Mutex::new(Vec::new());
static NEXT_OWNER: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(1);

/// Keeps a client's joints registered while alive.
#[derive(Debug)]
pub struct Registration {
    owner: u64,
}

/// Registers every joint of `client` under its `AxisName`.
pub fn register(client: &Arc<MotorControlClient>) -> Registration {
    let owner = NEXT_OWNER.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let mut t = TABLE.lock();
    for (joint, axis) in client.params().axis_names.iter().enumerate() {
        t.push(Entry {
            axis: axis.clone(),
            joint,
            client: Arc::downgrade(client),
            owner,
        });
    }
    Registration { owner }
}

impl Drop for Registration {
    fn drop(&mut self) {
        let mut t = TABLE.lock();
        t.retain(|e| e.owner != self.owner);
    }
}

/// The board and joint index driving axis `name` (the most recently opened one when
/// several devices use the same name).
pub fn find(name: &str) -> Option<(Arc<MotorControlClient>, usize)> {
    let t = TABLE.lock();
    t.iter()
        .rev()
        .filter(|e| e.axis == name)
        .find_map(|e| Some((e.client.upgrade()?, e.joint)))
}
