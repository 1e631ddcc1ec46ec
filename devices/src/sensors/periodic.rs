//! The period of the streaming wrappers, kept as C++ `PeriodicThread` keeps it: each
//! deadline is the previous one plus the period, so timer lateness does not lower the
//! rate; after a stall longer than a period the backlog is dropped, not replayed.
//!
//! Deadlines after the first (immediate) tick lie on a process-wide grid: multiples of
//! the period from one epoch. Every wrapper of a robot with the same period then wakes at
//! the same instant, so a runtime thread wakes once for all of them instead of once for
//! each (a robot has dozens of 100 Hz wrappers). The rate is the configured one.

use std::sync::OnceLock;
use std::time::{Duration, Instant};

/// Deadlines every `period`.
#[derive(Debug)]
pub struct Ticker {
    period: Duration,
    next: Instant,
    first: bool,
}

/// The first grid point of `period` at or after `t`.
fn on_grid(t: Instant, period: Duration) -> Instant {
    static EPOCH: OnceLock<Instant> = OnceLock::new();
    let epoch = *EPOCH.get_or_init(Instant::now);
    let p = period.as_nanos().max(1);
    let k = t.saturating_duration_since(epoch).as_nanos().div_ceil(p);
    epoch + Duration::from_nanos(u64::try_from(k * p).unwrap_or(u64::MAX))
}

impl Ticker {
    /// The first tick is immediate.
    pub fn new(period: Duration) -> Self {
        Ticker {
            period,
            next: Instant::now(),
            first: true,
        }
    }

    /// Waits for the next deadline on the tokio runtime.
    pub async fn tick(&mut self) {
        tokio::time::sleep_until(self.next.into()).await;
        self.advance();
    }

    /// Waits for the next deadline on the calling thread.
    pub fn tick_blocking(&mut self) {
        let now = Instant::now();
        if self.next > now {
            std::thread::sleep(self.next - now);
        }
        self.advance();
    }

    fn advance(&mut self) {
        let now = Instant::now();
        if std::mem::take(&mut self.first) {
            // onto the grid: the second tick comes within a period
            self.next = on_grid(now + Duration::from_nanos(1), self.period);
            return;
        }
        self.next += self.period;
        if self.next + self.period < now {
            // more than a period behind: start again from the next grid point
            self.next = on_grid(now, self.period);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tickers_of_one_period_share_their_deadlines() {
        let period = Duration::from_millis(10);
        let mut a = Ticker::new(period);
        a.tick_blocking();
        std::thread::sleep(Duration::from_millis(3));
        let mut b = Ticker::new(period);
        b.tick_blocking();
        let apart = a.next.max(b.next) - a.next.min(b.next);
        assert_eq!(apart.as_nanos() % period.as_nanos(), 0);
        let t0 = a.next;
        a.tick_blocking();
        assert_eq!(a.next, t0 + period);
        assert!(Instant::now() >= t0);
    }
}
