//! yarp-rs: samples announced by remote writers before this reader matched them.
//!
//! A remote writer often matches our reader before we match it (its SEDP announcement
//! reaches us later than ours reaches it), so its first DATA and HEARTBEATs arrive while
//! we cannot accept them. Remembering the sequence numbers they named lets the reader
//! ask for those samples as soon as it matches the writer, instead of waiting for the
//! writer's next periodic HEARTBEAT (3 s in Fast DDS): a short-lived publisher may be
//! gone by then, taking its samples with it.
//!
//! The DATA themselves are kept too (a few, briefly) and delivered once the writer
//! matches: on a loaded machine our discovery may take the writer's announcement only
//! after the publisher has sent its one message and left, when nobody can repair it.

use std::{
  collections::BTreeMap,
  time::{Duration, Instant},
};

use crate::{
  dds::{ddsdata::DDSData, with_key::datawriter::WriteOptions},
  structure::{guid::GUID, sequence_number::SequenceNumber, time::Timestamp},
};

/// At most this many writers are remembered: DATA of other topics also reaches a
/// reader, and those writers are never matched.
const MAX_WRITERS: usize = 64;
/// A record older than this is of a writer that did not match soon: dropped.
const KEEP_FOR: Duration = Duration::from_secs(10);
/// Samples kept per writer not matched yet (the first ones: later ones are asked for).
const MAX_SAMPLES_PER_WRITER: usize = 32;
/// Payload bytes kept for all writers not matched yet, per reader.
const MAX_KEPT_BYTES: usize = 1 << 20;

/// A DATA received from a writer before it matched, as the reader would have taken it.
pub(crate) struct EarlySample {
  pub sn: SequenceNumber,
  pub data: DDSData,
  pub received: Timestamp,
  pub options: WriteOptions,
}

/// The range of samples a writer named (DATA sent, or a HEARTBEAT's first..last).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Named {
  pub first: SequenceNumber,
  pub last: SequenceNumber,
}

/// What a writer not matched yet has shown us.
pub(crate) struct Early {
  pub named: Named,
  pub kept: Vec<EarlySample>,
}

#[derive(Default)]
pub(crate) struct EarlyWriters {
  named: BTreeMap<GUID, (Early, Instant)>,
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
    let (early, at) = self.named.entry(writer).or_insert((
      Early {
        named: Named { first, last },
        kept: Vec::new(),
      },
      now,
    ));
    early.named.first = early.named.first.min(first);
    early.named.last = early.named.last.max(last);
    *at = now;
  }

  /// Notes `writer`'s sample `sn` and keeps it, within the bounds, until the writer
  /// matches.
  pub fn keep(&mut self, writer: GUID, sample: EarlySample) {
    self.saw(writer, sample.sn, sample.sn);
    let size = sample.data.payload_size();
    let now = Instant::now();
    self
      .named
      .retain(|_, (_, at)| now.duration_since(*at) < KEEP_FOR);
    let kept_bytes: usize = self
      .named
      .values()
      .flat_map(|(e, _)| e.kept.iter())
      .map(|s| s.data.payload_size())
      .sum();
    if kept_bytes + size > MAX_KEPT_BYTES {
      return;
    }
    if let Some((early, _)) = self.named.get_mut(&writer) {
      if early.kept.len() < MAX_SAMPLES_PER_WRITER && early.kept.iter().all(|s| s.sn != sample.sn)
      {
        early.kept.push(sample);
      }
    }
  }

  /// What `writer` showed before it matched (forgotten now); kept samples in order.
  pub fn take(&mut self, writer: GUID) -> Option<Early> {
    let (mut early, at) = self.named.remove(&writer)?;
    early.kept.sort_by_key(|s| s.sn);
    (at.elapsed() < KEEP_FOR).then_some(early)
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
      e.take(guid(1)).map(|e| e.named),
      Some(Named {
        first: sn(1),
        last: sn(3)
      })
    );
    assert!(e.take(guid(1)).is_none());
  }

  #[test]
  fn is_bounded() {
    let mut e = EarlyWriters::default();
    for n in 0..200u8 {
      e.saw(guid(n), sn(1), sn(1));
    }
    assert_eq!(e.len(), MAX_WRITERS);
    assert!(e.take(guid(150)).is_none());
    assert!(e.take(guid(0)).is_some());
  }

  fn sample(n: i64, bytes: usize) -> EarlySample {
    use crate::{
      messages::submessages::elements::serialized_payload::SerializedPayload,
      RepresentationIdentifier,
    };
    EarlySample {
      sn: sn(n),
      data: DDSData::new(SerializedPayload::new(
        RepresentationIdentifier::CDR_LE,
        vec![0; bytes],
      )),
      received: Timestamp::ZERO,
      options: WriteOptions::default(),
    }
  }

  #[test]
  fn keeps_early_samples_in_order_within_bounds() {
    let mut e = EarlyWriters::default();
    e.keep(guid(1), sample(2, 10));
    e.keep(guid(1), sample(1, 10));
    e.keep(guid(1), sample(1, 10)); // a repeat: kept once
    for n in 3..100 {
      e.keep(guid(2), sample(n, 10));
    }
    // Over the byte budget: named (to be asked for) but not kept.
    e.keep(guid(3), sample(1, MAX_KEPT_BYTES));
    let one = e.take(guid(1)).expect("writer 1 kept");
    assert_eq!(one.kept.iter().map(|s| s.sn).collect::<Vec<_>>(), [sn(1), sn(2)]);
    let two = e.take(guid(2)).expect("writer 2 kept");
    assert_eq!(two.kept.len(), MAX_SAMPLES_PER_WRITER);
    assert_eq!(two.named.last, sn(99));
    let three = e.take(guid(3)).expect("writer 3 named");
    assert!(three.kept.is_empty());
    assert_eq!(three.named.first, sn(1));
  }
}
