//! The network variables of one board, as both sides keep them: each entity instance
//! (endpoint, entity, index) is one buffer of its C struct's size, and every tag reads or
//! writes its slice of it (the `EOnvSet` of the C transceivers).

use crate::id::{entity_item_size, Id32};
use crate::wire::Entity;
use std::collections::HashMap;
use thiserror::Error;

/// Why a variable could not be read or written.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Error)]
pub enum NvError {
    #[error("variable {0} is not defined by the protocol")]
    Unknown(Id32),
    #[error("variable {0} is not present on this board")]
    Absent(Id32),
    #[error("variable {id} has {expected} bytes, got {got}")]
    Size {
        id: Id32,
        expected: usize,
        got: usize,
    },
}

/// Entity instances keyed by `(endpoint, entity, index)`.
#[derive(Debug, Clone, Default)]
pub struct NvStore {
    items: HashMap<(u8, u8, u8), Vec<u8>>,
}

impl NvStore {
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds `count` zeroed instances of an entity (indices 0..count).
    pub fn add_entity(&mut self, ep: u8, ent: u8, count: u8) {
        if let Some(size) = entity_item_size(ep, ent) {
            for i in 0..count {
                self.items
                    .entry((ep, ent, i))
                    .or_insert_with(|| vec![0; size]);
            }
        }
    }

    /// Number of instances of an entity.
    pub fn count(&self, ep: u8, ent: u8) -> u8 {
        self.items
            .keys()
            .filter(|k| k.0 == ep && k.1 == ent)
            .count() as u8
    }

    pub fn contains(&self, id: Id32) -> bool {
        id.layout().is_some()
            && self
                .items
                .contains_key(&(id.endpoint(), id.entity(), id.index()))
    }

    /// The variable's bytes.
    pub fn get(&self, id: Id32) -> Result<&[u8], NvError> {
        let l = id.layout().ok_or(NvError::Unknown(id))?;
        let item = self
            .items
            .get(&(id.endpoint(), id.entity(), id.index()))
            .ok_or(NvError::Absent(id))?;
        item.get(l.offset..l.offset + l.size)
            .ok_or(NvError::Unknown(id))
    }

    /// Writes the variable; `data` must have exactly its size (as `EOagent` requires of a `set`).
    pub fn set(&mut self, id: Id32, data: &[u8]) -> Result<(), NvError> {
        let l = id.layout().ok_or(NvError::Unknown(id))?;
        if data.len() != l.size {
            return Err(NvError::Size {
                id,
                expected: l.size,
                got: data.len(),
            });
        }
        let item = self
            .items
            .get_mut(&(id.endpoint(), id.entity(), id.index()))
            .ok_or(NvError::Absent(id))?;
        let slot = item
            .get_mut(l.offset..l.offset + l.size)
            .ok_or(NvError::Unknown(id))?;
        slot.copy_from_slice(data);
        Ok(())
    }

    /// The raw bytes of a whole entity instance.
    pub fn item_mut(&mut self, ep: u8, ent: u8, index: u8) -> Option<&mut [u8]> {
        self.items.get_mut(&(ep, ent, index)).map(Vec::as_mut_slice)
    }

    /// Reads a variable as its typed struct.
    pub fn read<T: Entity>(&self, id: Id32) -> Result<T, NvError> {
        let b = self.get(id)?;
        T::from_bytes(b).map_err(|e| NvError::Size {
            id,
            expected: e.expected,
            got: e.got,
        })
    }

    /// Writes a variable from its typed struct.
    pub fn write<T: Entity>(&mut self, id: Id32, v: &T) -> Result<(), NvError> {
        self.set(id, &v.to_bytes())
    }
}
