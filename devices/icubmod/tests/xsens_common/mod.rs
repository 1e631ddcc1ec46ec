//! What the Xsens device tests share: a still sensor's sample, bounded waits, closeness.

#![allow(dead_code)]

use icub_can::xsens::Sample;
use std::time::{Duration, Instant};

/// A sensor at rest, tilted a little: every field distinct, in the sensor's units.
pub fn still(_t: f64) -> Sample {
    Sample {
        acc: [0.5, -0.25, -9.75],
        gyr: [0.1, -0.2, 0.3],
        mag: [0.5, 0.0, 0.4],
        euler: [1.5, -2.5, 30.0],
    }
}

/// Polls `ok` every 10 ms until it holds or `timeout` passes; whether it held.
pub fn eventually(timeout: Duration, mut ok: impl FnMut() -> bool) -> bool {
    let end = Instant::now() + timeout;
    while Instant::now() < end {
        if ok() {
            return true;
        }
        std::thread::sleep(Duration::from_millis(10));
    }
    ok()
}

pub fn close(a: &[f64], b: &[f64]) -> bool {
    a.len() == b.len() && a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-4)
}
