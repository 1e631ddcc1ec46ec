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
