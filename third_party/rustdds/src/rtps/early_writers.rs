//! yarp-rs: samples announced by remote writers before this reader matched them.
//!
//! A remote writer often matches our reader before we match it (its SEDP announcement
//! reaches us later than ours reaches it), so its first DATA and HEARTBEATs arrive while
//! we cannot accept them. Remembering the sequence numbers they named lets the reader
//! ask for those samples as soon as it matches the writer, instead of waiting for the
//! writer's next periodic HEARTBEAT (3 s in Fast DDS): a short-lived publisher may be
//! gone by then, taking its samples with it.

use std::{
  collections::BTreeMap,
  time::{Duration, Instant},
};

use crate::structure::{guid::GUID, sequence_number::SequenceNumber};

/// At most this many writers are remembered: DATA of other topics also reaches a
/// reader, and those writers are never matched.
const MAX_WRITERS: usize = 64;
/// A record older than this is of a writer that did not match soon: dropped.
const KEEP_FOR: Duration = Duration::from_secs(10);

/// The range of samples a writer named (DATA sent, or a HEARTBEAT's first..last).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Named {
  pub first: SequenceNumber,
  pub last: SequenceNumber,
}

#[derive(Default)]
pub(crate) struct EarlyWriters {
  named: BTreeMap<GUID, (Named, Instant)>,
}

impl EarlyWriters {
  /// Notes that `writer`, not matched yet, has samples `first..=last`.
  pub fn saw(&mut self, writer: GUID, first: SequenceNumber, last: SequenceNumber) {
    if first < SequenceNumber::new(1) || last < first {
      return;
    }
    let now = Instant::now();
    if !self.named.contains_key(&writer) && self.named.len() >= MAX_WRITERS {
      self
        .named
        .retain(|_, (_, at)| now.duration_since(*at) < KEEP_FOR);
      if self.named.len() >= MAX_WRITERS {
        return;
      }
    }
    let (named, at) = self
      .named
      .entry(writer)
      .or_insert((Named { first, last }, now));
    named.first = named.first.min(first);
    named.last = named.last.max(last);
    *at = now;
  }

  /// The samples `writer` named before it matched (forgotten now).
  pub fn take(&mut self, writer: GUID) -> Option<Named> {
    let (named, at) = self.named.remove(&writer)?;
    (at.elapsed() < KEEP_FOR).then_some(named)
  }

  #[cfg(test)]
  pub fn len(&self) -> usize {
    self.named.len()
  }
}

#[cfg(test)]
mod tests {
  use super::*;
  use crate::structure::guid::{EntityId, GuidPrefix};

  fn guid(n: u8) -> GUID {
    GUID::new(GuidPrefix::new(&[n; 12]), EntityId::UNKNOWN)
  }

  fn sn(n: i64) -> SequenceNumber {
    SequenceNumber::new(n)
  }

  #[test]
  fn keeps_the_whole_range_named_and_forgets_on_take() {
    let mut e = EarlyWriters::default();
    e.saw(guid(1), sn(2), sn(3));
    e.saw(guid(1), sn(1), sn(1));
    e.saw(guid(1), sn(0), sn(9)); // not a valid range: ignored
    e.saw(guid(1), sn(5), sn(4)); // an empty HEARTBEAT: ignored
    assert_eq!(
      e.take(guid(1)),
      Some(Named {
        first: sn(1),
        last: sn(3)
      })
    );
    assert_eq!(e.take(guid(1)), None);
  }

  #[test]
  fn is_bounded() {
    let mut e = EarlyWriters::default();
    for n in 0..200u8 {
      e.saw(guid(n), sn(1), sn(1));
    }
    assert_eq!(e.len(), MAX_WRITERS);
    assert_eq!(e.take(guid(150)), None);
    assert!(e.take(guid(0)).is_some());
  }
}
