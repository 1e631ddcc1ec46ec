//! Typed errors for the codecs. Every error says what was wrong and where.

use thiserror::Error;

/// Failure to decode binary Bottle data (untrusted network input).
#[derive(Debug, Clone, PartialEq, Eq, Error)]
pub enum DecodeError {
    #[error("truncated input at byte {offset}: needed {needed} more byte(s) for {what}")]
    Truncated {
        offset: usize,
        needed: usize,
        what: &'static str,
    },
    #[error("unknown type tag {tag:#x} at byte {offset}")]
    UnknownTag { tag: i32, offset: usize },
    #[error("negative length {len} for {what} at byte {offset}")]
    NegativeLength {
        len: i32,
        what: &'static str,
        offset: usize,
    },
    #[error("lists nested deeper than {limit} levels at byte {offset}")]
    TooDeep { limit: usize, offset: usize },
    #[error("{count} element(s) declared at byte {offset} but only {remaining} byte(s) remain")]
    CountTooLarge {
        count: i32,
        remaining: usize,
        offset: usize,
    },
}

impl DecodeError {
    /// Byte offset in the input where the problem was found.
    pub fn offset(&self) -> usize {
        match *self {
            DecodeError::Truncated { offset, .. }
            | DecodeError::UnknownTag { offset, .. }
            | DecodeError::NegativeLength { offset, .. }
            | DecodeError::TooDeep { offset, .. }
            | DecodeError::CountTooLarge { offset, .. } => offset,
        }
    }
}

/// Failure to parse configuration or command text, located by line (1-based).
#[derive(Debug, Clone, PartialEq, Eq, Error)]
pub enum ParseError {
    #[error("line {line}: {message}")]
    Syntax { line: usize, message: String },
    #[error("line {line}: cannot include {path:?}: {reason}")]
    Include {
        line: usize,
        path: String,
        reason: String,
    },
    #[error("text nested deeper than {limit} levels")]
    TooDeep { limit: usize },
}
