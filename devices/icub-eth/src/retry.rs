//! How an exchange with a board is retried: one type, and icub-main's policies as named
//! constants, so that each use says which policy it follows (the host's start-up, the
//! services' activation and the devices' asks share them).

use std::time::Duration;

/// A retry policy: how many attempts, how long each waits for its reply, and (for a
/// `setcheck`) how long after the set the value is asked back.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Retry {
    /// Attempts in all (at least one is made).
    pub attempts: u32,
    /// How long one attempt waits for the board's reply.
    pub timeout: Duration,
    /// `setcheck` only: the pause between the set and the ask that checks it.
    pub settle: Duration,
}

const fn ms(m: u64) -> Duration {
    Duration::from_millis(m)
}

impl Retry {
    /// `EthResource::verifyBoardPresence`: the management version asked 1 s × 21.
    pub const BOARD_PRESENCE: Retry = Retry::asks(21, ms(1000));
    /// `EthResource::setTimingOfRunningCycle`: `setcheck` of `appl config`, 5 × (10 ms, 2 s).
    pub const APPL_CONFIG: Retry = Retry::setchecks(5, ms(10), ms(2000));
    /// `EthResource::askBoardVersion`: `appl status`, once, 0.5 s.
    pub const BOARD_VERSION: Retry = Retry::asks(1, ms(500));
    /// `EthResource::verifyEPprotocol`: the endpoint descriptors, 0.1 s. C++ asks once; a
    /// loaded host may miss that reply, so it is asked up to three times.
    pub const ENDPOINTS: Retry = Retry::asks(3, ms(100));
    /// `EthResource::serviceVerifyActivate`, `serviceSetRegulars`, `serviceStart`,
    /// `serviceStop`: 0.5 s × 3.
    pub const SERVICE_COMMAND: Retry = Retry::asks(3, ms(500));
    /// The devices' `setcheckRemoteValue(id, value, 10, 0.010, 0.050)`.
    pub const DEVICE_SETCHECK: Retry = Retry::setchecks(10, ms(10), ms(50));
    /// A device's `askRemoteValue` (`theNVmanager`'s 0.5 s): a reply lost on a loaded host
    /// is asked again, up to three times within the same 0.5 s.
    pub const DEVICE_ASK: Retry = Retry::asks(3, Duration::from_nanos(500_000_000 / 3));

    /// `attempts` asks (or commands) of `timeout` each.
    pub const fn asks(attempts: u32, timeout: Duration) -> Retry {
        Retry {
            attempts,
            timeout,
            settle: Duration::ZERO,
        }
    }

    /// `attempts` set-wait-ask rounds.
    pub const fn setchecks(attempts: u32, settle: Duration, timeout: Duration) -> Retry {
        Retry {
            attempts,
            timeout,
            settle,
        }
    }

    /// Attempts in all, never zero.
    pub fn attempts(&self) -> u32 {
        self.attempts.max(1)
    }

    /// Runs `attempt` (given each attempt's timeout) until it succeeds or the attempts
    /// are spent; then the last error.
    pub fn run<T, E>(&self, mut attempt: impl FnMut(Duration) -> Result<T, E>) -> Result<T, E> {
        let mut n = 1;
        loop {
            match attempt(self.timeout) {
                Ok(v) => return Ok(v),
                Err(e) if n >= self.attempts() => return Err(e),
                Err(_) => n += 1,
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stops_at_the_first_success_or_after_the_last_attempt() {
        let mut calls = 0;
        let r: Result<u32, u32> = Retry::SERVICE_COMMAND.run(|t| {
            assert_eq!(t, ms(500));
            calls += 1;
            if calls == 2 {
                Ok(calls)
            } else {
                Err(calls)
            }
        });
        assert_eq!(r, Ok(2));
        let mut calls = 0;
        let r: Result<(), u32> = Retry::SERVICE_COMMAND.run(|_| {
            calls += 1;
            Err(calls)
        });
        assert_eq!(r, Err(3));
        let r: Result<(), ()> = Retry::asks(0, ms(1)).run(|_| Err(()));
        assert_eq!(r, Err(()), "zero attempts still tries once");
    }
}
