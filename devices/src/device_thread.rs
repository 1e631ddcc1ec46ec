//! A device's own thread (a sensor's reader, a periodic estimator) and the flag that ends
//! it, as C++ devices keep a `yarp::os::Thread`: started on open or attach, asked to stop
//! and joined on close, detach or drop.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;

#[derive(Default)]
pub struct DeviceThread {
    stop: Arc<AtomicBool>,
    handle: Option<JoinHandle<()>>,
}

impl DeviceThread {
    /// Starts `body` on a thread named `name`, in place of the one running; `body` returns
    /// once the flag it is given is raised.
    pub fn spawn(
        &mut self,
        name: String,
        body: impl FnOnce(&AtomicBool) + Send + 'static,
    ) -> std::io::Result<()> {
        self.stop();
        let stop = Arc::new(AtomicBool::new(false));
        self.stop = stop.clone();
        self.handle = Some(
            std::thread::Builder::new()
                .name(name)
                .spawn(move || body(&stop))?,
        );
        Ok(())
    }

    pub fn is_running(&self) -> bool {
        self.handle.is_some()
    }

    /// Raises the flag and waits for the thread to end.
    pub fn stop(&mut self) {
        self.stop.store(true, Ordering::SeqCst);
        if let Some(h) = self.handle.take() {
            let _ = h.join();
        }
    }
}

impl Drop for DeviceThread {
    fn drop(&mut self) {
        self.stop();
    }
}

/// Whether `stop` is raised (the loop condition of a [`DeviceThread`]'s body).
pub fn stopped(stop: &AtomicBool) -> bool {
    stop.load(Ordering::SeqCst)
}
