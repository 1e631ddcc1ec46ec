//! Little-endian field readers and writers for the C structs of icub-firmware-shared.
//!
//! The boards (ARM Cortex-M) and the host (x86-64) both lay the structs out in little
//! endian with natural alignment; the entity codecs write every field and every filler at
//! its C offset, so an encoded struct is byte-for-byte what `memcpy` of the C struct gives.

use thiserror::Error;

/// A struct's bytes do not have the size its C type has.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Error)]
#[error("{type_name}: expected {expected} bytes, got {got}")]
pub struct SizeError {
    /// The C type, e.g. `eOmc_joint_status_core_t`.
    pub type_name: &'static str,
    pub expected: usize,
    pub got: usize,
}

/// A fixed-size C struct of the embObj protocol with an exact wire layout.
pub trait Entity: Sized {
    /// The C type name (for errors and logs).
    const C_TYPE: &'static str;
    /// `sizeof` the C type.
    const SIZE: usize;
    /// Appends exactly [`Self::SIZE`] bytes.
    fn write(&self, w: &mut Writer);
    /// Reads from exactly [`Self::SIZE`] bytes (the caller checked the length).
    fn read(r: &mut Reader) -> Self;

    /// The struct's bytes.
    fn to_bytes(&self) -> Vec<u8> {
        let mut w = Writer::with_capacity(Self::SIZE);
        self.write(&mut w);
        debug_assert_eq!(w.len(), Self::SIZE, "{}", Self::C_TYPE);
        w.into_inner()
    }

    /// Decodes the struct from exactly `SIZE` bytes.
    fn from_bytes(b: &[u8]) -> Result<Self, SizeError> {
        if b.len() != Self::SIZE {
            return Err(SizeError {
                type_name: Self::C_TYPE,
                expected: Self::SIZE,
                got: b.len(),
            });
        }
        Ok(Self::read(&mut Reader::new(b)))
    }
}

/// Appends little-endian fields.
#[derive(Debug, Default)]
pub struct Writer(Vec<u8>);

impl Writer {
    pub fn with_capacity(n: usize) -> Self {
        Self(Vec::with_capacity(n))
    }
    pub fn len(&self) -> usize {
        self.0.len()
    }
    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }
    pub fn into_inner(self) -> Vec<u8> {
        self.0
    }
    pub fn u8(&mut self, v: u8) {
        self.0.push(v);
    }
    pub fn i8(&mut self, v: i8) {
        self.0.push(v as u8);
    }
    pub fn u16(&mut self, v: u16) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    pub fn i16(&mut self, v: i16) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    pub fn u32(&mut self, v: u32) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    pub fn i32(&mut self, v: i32) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    pub fn u64(&mut self, v: u64) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    pub fn f32(&mut self, v: f32) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    pub fn bytes(&mut self, b: &[u8]) {
        self.0.extend_from_slice(b);
    }
    /// `n` zero bytes (C fillers and alignment padding).
    pub fn zeros(&mut self, n: usize) {
        self.0.resize(self.0.len() + n, 0);
    }
    pub fn entity<T: Entity>(&mut self, v: &T) {
        v.write(self);
    }
}

/// Reads little-endian fields; reading past the end yields zeros (entity decoders are
/// only called on buffers whose length was checked, so this never hides a short input).
#[derive(Debug)]
pub struct Reader<'a> {
    b: &'a [u8],
    at: usize,
}

impl<'a> Reader<'a> {
    pub fn new(b: &'a [u8]) -> Self {
        Self { b, at: 0 }
    }
    pub fn position(&self) -> usize {
        self.at
    }
    fn take<const N: usize>(&mut self) -> [u8; N] {
        let mut out = [0u8; N];
        if let Some(s) = self.b.get(self.at..self.at + N) {
            out.copy_from_slice(s);
        }
        self.at += N;
        out
    }
    pub fn u8(&mut self) -> u8 {
        self.take::<1>()[0]
    }
    pub fn i8(&mut self) -> i8 {
        self.take::<1>()[0] as i8
    }
    pub fn u16(&mut self) -> u16 {
        u16::from_le_bytes(self.take())
    }
    pub fn i16(&mut self) -> i16 {
        i16::from_le_bytes(self.take())
    }
    pub fn u32(&mut self) -> u32 {
        u32::from_le_bytes(self.take())
    }
    pub fn i32(&mut self) -> i32 {
        i32::from_le_bytes(self.take())
    }
    pub fn u64(&mut self) -> u64 {
        u64::from_le_bytes(self.take())
    }
    pub fn f32(&mut self) -> f32 {
        f32::from_le_bytes(self.take())
    }
    pub fn array<const N: usize>(&mut self) -> [u8; N] {
        self.take()
    }
    pub fn skip(&mut self, n: usize) {
        self.at += n;
    }
    pub fn entity<T: Entity>(&mut self) -> T {
        T::read(self)
    }
}
