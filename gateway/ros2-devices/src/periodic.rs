//! The periodic publishing thread of a single-device wrapper (C++ `PeriodicThread` of
//! `WrapperSingle` devices): every `period`, `step` runs on the attached device.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;
use yarp_devices::sensors::periodic::Ticker;
use yarp_devices::{DevResult, DeviceDriver, DeviceError, SharedDevice};

/// A running thread; stopped and joined on drop.
pub struct Periodic {
    stop: Arc<AtomicBool>,
    thread: Option<std::thread::JoinHandle<()>>,
}

impl Periodic {
    /// Starts calling `step` on `device` every `period` (the first call at once).
    pub fn start(
        name: &str,
        period: Duration,
        device: SharedDevice,
        mut step: impl FnMut(&mut dyn DeviceDriver) + Send + 'static,
    ) -> DevResult<Periodic> {
        Periodic::every(name, name.to_string(), period, move || {
            let mut pd = device.lock();
            step(pd.device());
        })
    }

    /// Starts calling `step` every `period` (the first call at once) on a thread named
    /// `thread`; `device` is who reports that the thread could not start.
    pub fn every(
        device: &str,
        thread: String,
        period: Duration,
        mut step: impl FnMut() + Send + 'static,
    ) -> DevResult<Periodic> {
        let stop = Arc::new(AtomicBool::new(false));
        let s = stop.clone();
        let thread = std::thread::Builder::new()
            .name(thread)
            .spawn(move || {
                let mut tick = Ticker::new(period);
                while !s.load(Ordering::Relaxed) {
                    tick.tick_blocking();
                    step();
                }
            })
            .map_err(|e| DeviceError::Failed {
                device: device.to_string(),
                reason: format!("cannot start the publisher thread: {e}"),
            })?;
        Ok(Periodic {
            stop,
            thread: Some(thread),
        })
    }
}

impl Drop for Periodic {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

/// Rate-limited error log of a periodic step (C++ `yCErrorThrottle`): at most one line
/// every 5 s per wrapper.
#[derive(Default)]
pub struct Throttle(Option<std::time::Instant>);

impl Throttle {
    pub fn warn(&mut self, device: &str, what: impl std::fmt::Display) {
        let now = std::time::Instant::now();
        if self
            .0
            .is_none_or(|t| now.duration_since(t) > Duration::from_secs(5))
        {
            self.0 = Some(now);
            tracing::warn!("{device}: {what}");
        }
    }
}
