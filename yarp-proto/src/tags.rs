//! Bottle type tags, as C++ YARP writes them (`yarp/os/Bottle.h`).

pub const INT8: i32 = 0x20;
pub const INT16: i32 = 0x40;
pub const INT32: i32 = 0x01;
pub const INT64: i32 = 0x01 | 0x10;
pub const VOCAB32: i32 = 0x01 | 0x08;
pub const FLOAT32: i32 = 0x80;
pub const FLOAT64: i32 = 0x02 | 0x08;
pub const STRING: i32 = 0x04;
pub const BLOB: i32 = 0x04 | 0x08;
pub const LIST: i32 = 0x100;
pub const DICT: i32 = 0x200;

/// Bits that name a simple (unit) type.
pub const UNIT_MASK: i32 =
    INT8 | INT16 | INT32 | INT64 | VOCAB32 | FLOAT32 | FLOAT64 | STRING | BLOB;
/// Bits that name a group (list or dict).
pub const GROUP_MASK: i32 = LIST | DICT;

/// The two numberings of the float tags on the wire: C++ YARP 3 (up to 3.12) and
/// YARP 4.0, which renumbered them (`FLOAT32` took 3's `FLOAT64` code) and added
/// `VOCAB64`. A message of one cannot be read as the other when it holds floats, so
/// every encoding says which one it writes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum Generation {
    /// YARP 3.x, what robots run (3.12.3).
    #[default]
    V3,
    /// YARP 4.0.
    V4,
}

/// YARP 4.0's tags that differ from 3's.
pub mod v4 {
    pub const FLOAT32: i32 = 0x02 | 0x08;
    pub const FLOAT64: i32 = 0x04 | 0x10;
    pub const VOCAB64: i32 = 0x02 | 0x10;
}

impl Generation {
    pub const fn float32(self) -> i32 {
        match self {
            Generation::V3 => FLOAT32,
            Generation::V4 => v4::FLOAT32,
        }
    }
    pub const fn float64(self) -> i32 {
        match self {
            Generation::V3 => FLOAT64,
            Generation::V4 => v4::FLOAT64,
        }
    }
    /// Whether `tag` exists only in this generation, so that a message holding it is
    /// one of this generation's.
    pub const fn owns(self, tag: i32) -> bool {
        match self {
            Generation::V3 => tag == FLOAT32,
            Generation::V4 => tag == v4::FLOAT64 || tag == v4::VOCAB64,
        }
    }
}
