//! The period of the streaming wrappers, kept as C++ `PeriodicThread` keeps it: each
//! deadline is the previous one plus the period, so timer lateness does not lower the
//! rate; after a stall longer than a period the backlog is dropped, not replayed.

use std::time::Duration;
use tokio::time::Instant;

/// Deadlines every `period`.
#[derive(Debug)]
pub struct Ticker {
    period: Duration,
    next: Instant,
}

impl Ticker {
    /// The first tick is immediate.
    pub fn new(period: Duration) -> Self {
        Ticker {
            period,
            next: Instant::now(),
        }
    }

    /// Waits for the next deadline.
    pub async fn tick(&mut self) {
        tokio::time::sleep_until(self.next).await;
        let now = Instant::now();
        self.next += self.period;
        if self.next + self.period < now {
            // more than a period behind: start again from now
            self.next = now + self.period;
        }
    }
}
