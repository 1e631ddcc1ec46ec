//! Reports the motor-control boards of a `canmotioncontrol` that fall silent and come
//! back, as icub-main's `CanBusMotionControl` statistics thread does ("have not heard from
//! board N since X seconds", repeated while it lasts) — and, since a board that comes back
//! may have been reset, says what the user must do about the configuration it lost.
//!
//! Reads of a silent board's joints already fail after the broadcast timeout (500 ms);
//! this only tells the user why, once per change and then every [`REPEAT`].

use std::sync::mpsc::{self, RecvTimeoutError};
use std::sync::{Arc, Weak};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use icub_can::client::MotorControlClient;

/// How often the boards' liveness is checked.
const CHECK: Duration = Duration::from_millis(250);
/// How often a board that stays silent is reported again (icub-main's
/// `BCAST_STATUS_TIMEOUT`).
pub const REPEAT: Duration = Duration::from_secs(6);

/// The watching thread of one device; stops at once when dropped (or when the client
/// goes).
pub struct PresenceWatch {
    stop: Option<mpsc::Sender<()>>,
    thread: Option<JoinHandle<()>>,
}

impl PresenceWatch {
    pub fn start(device: &str, client: &Arc<MotorControlClient>) -> PresenceWatch {
        let (stop, stopped) = mpsc::channel();
        let (c, id) = (Arc::downgrade(client), device.to_string());
        let thread = std::thread::Builder::new()
            .name(format!("{device} presence"))
            .spawn(move || watch(&id, &c, &stopped))
            .ok();
        PresenceWatch {
            stop: Some(stop),
            thread,
        }
    }
}

impl Drop for PresenceWatch {
    fn drop(&mut self) {
        // the watcher wakes as soon as its channel closes
        self.stop = None;
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

/// Per board: since when it is silent and when that was last reported.
#[derive(Default, Clone, Copy)]
struct Silence {
    since: Option<Instant>,
    reported: Option<Instant>,
}

fn watch(device: &str, client: &Weak<MotorControlClient>, stop: &mpsc::Receiver<()>) {
    let mut boards: Vec<Silence> = Vec::new();
    while let Err(RecvTimeoutError::Timeout) = stop.recv_timeout(CHECK) {
        let Some(c) = client.upgrade() else { return };
        let health = c.board_health();
        boards.resize(health.len(), Silence::default());
        for (h, s) in health.iter().zip(boards.iter_mut()) {
            let joints = joints_of(&c, h.address);
            match (h.alive, s.since) {
                (false, None) => {
                    // heard before and now silent past the broadcast timeout
                    if let Some(quiet) = h.silent_for {
                        s.since = Some(Instant::now() - quiet);
                        s.reported = Some(Instant::now());
                        tracing::error!(
                            "{device}: have not heard from board {} (joints {joints}) since {:.2} seconds: their encoders and status read as failed until it talks again",
                            h.address,
                            quiet.as_secs_f64()
                        );
                    }
                }
                (false, Some(since)) => {
                    if s.reported.is_none_or(|r| r.elapsed() >= REPEAT) {
                        s.reported = Some(Instant::now());
                        tracing::error!(
                            "{device}: have not heard from board {} (joints {joints}) since {:.2} seconds; check its power and CAN cable (or restart the board emulator)",
                            h.address,
                            since.elapsed().as_secs_f64()
                        );
                    }
                }
                (true, Some(since)) => {
                    *s = Silence::default();
                    tracing::warn!(
                        "{device}: board {} (joints {joints}) talks again after {:.1} s of silence and its encoders flow again. If it was reset (power cycle, restarted emulator) it has lost the configuration this device sent it at start-up (PIDs, limits, velocity shifts, broadcast policy, control mode): restart yarprobotinterface to configure it again",
                        h.address,
                        since.elapsed().as_secs_f64()
                    );
                }
                (true, None) => {}
            }
        }
    }
}

/// The device's joints on board `address`, as `0,1`.
fn joints_of(c: &MotorControlClient, address: u8) -> String {
    let p = c.params();
    p.axis_map
        .iter()
        .enumerate()
        .filter(|(_, &axis)| p.can_addresses.get(axis / 2) == Some(&address))
        .map(|(j, _)| j.to_string())
        .collect::<Vec<_>>()
        .join(",")
}
