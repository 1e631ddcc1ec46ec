//! Skin (class 4) and MTB inertial (class 5) broadcasts.

use super::{i16_at, need, MsgClass, Payload, ProtoError};

/// Sensor bits of `ACC_GYRO_SETUP` (`icubCanProto_inertial_sensorflags_t`).
pub mod inertial_bits {
    pub const ANALOG_ACC: u8 = 0x01;
    pub const INTERNAL_ACC: u8 = 0x02;
    pub const EXTERNAL_GYRO: u8 = 0x04;
    pub const EXTERNAL_ACC: u8 = 0x08;
}

/// Half of one skin triangle's 12 taxels (`CanBusSkin`): the identifier's low nibble is
/// the triangle (0..15); bit 7 of the first byte tells the head (taxels 0..7, seven
/// values) from the tail (taxels 7..12, five values, optionally followed by error bytes).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct SkinFrame {
    pub triangle: u8,
    /// The first data byte (0x40 head, 0xC0 tail on MTB firmware).
    pub header: u8,
    /// Taxel values (7 for the head, 5..7 for the tail).
    pub values: Payload,
}

impl SkinFrame {
    pub const HEAD: u8 = 0x40;
    pub const TAIL: u8 = 0xC0;

    /// The head half of a triangle.
    pub fn head(triangle: u8, taxels: [u8; 7]) -> Self {
        Self {
            triangle: triangle & 0xF,
            header: Self::HEAD,
            values: Payload::new(&taxels),
        }
    }
    /// The tail half of a triangle.
    pub fn tail(triangle: u8, taxels: [u8; 5]) -> Self {
        Self {
            triangle: triangle & 0xF,
            header: Self::TAIL,
            values: Payload::new(&taxels),
        }
    }
    /// Whether this is the tail half.
    pub fn is_tail(&self) -> bool {
        self.header & 0x80 != 0
    }
    /// Index of the first taxel carried within the triangle.
    pub fn first_taxel(&self) -> usize {
        if self.is_tail() {
            7
        } else {
            0
        }
    }
    /// The taxel values (the tail's trailing error bytes excluded).
    pub fn taxels(&self) -> &[u8] {
        let v = self.values.as_slice();
        if self.is_tail() {
            &v[..5]
        } else {
            v
        }
    }

    pub fn encode(&self, b: &mut [u8; 8]) -> usize {
        b[0] = self.header;
        let v = self.values.as_slice();
        b[1..1 + v.len()].copy_from_slice(v);
        1 + v.len()
    }

    pub fn decode(triangle: u8, d: &[u8]) -> Result<Self, ProtoError> {
        need("skin frame", d, 1, 8, "1..8")?;
        let header = d[0];
        if header & 0x80 != 0 {
            need("skin tail", d, 6, 8, "6..8")?;
        } else {
            need("skin head", d, 8, 8, "8")?;
        }
        Ok(Self {
            triangle,
            header,
            values: Payload::new(&d[1..]),
        })
    }
}

/// MTB inertial messages (`ICUBCANPROTO_PER_IS_MSG__*`, `CanBusInertialMTB`): three
/// signed 16-bit little-endian axes in raw sensor units.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum InertialMsg {
    /// Type 0: digital gyroscope.
    Gyroscope([i16; 3]),
    /// Type 1: digital accelerometer.
    Accelerometer([i16; 3]),
}

impl InertialMsg {
    pub fn encode(&self, b: &mut [u8; 8]) -> (u8, usize) {
        let (kind, v) = match *self {
            Self::Gyroscope(v) => (0, v),
            Self::Accelerometer(v) => (1, v),
        };
        for (i, x) in v.iter().enumerate() {
            b[2 * i..2 * i + 2].copy_from_slice(&x.to_le_bytes());
        }
        (kind, 6)
    }

    pub fn decode(kind: u8, d: &[u8]) -> Result<Self, ProtoError> {
        let v = |d: &[u8]| [i16_at(d, 0), i16_at(d, 2), i16_at(d, 4)];
        match kind {
            0 => {
                need("gyroscope", d, 6, 8, "at least 6")?;
                Ok(Self::Gyroscope(v(d)))
            }
            1 => {
                need("accelerometer", d, 6, 8, "at least 6")?;
                Ok(Self::Accelerometer(v(d)))
            }
            code => Err(ProtoError::Unknown {
                class: MsgClass::PeriodicInertial,
                code,
            }),
        }
    }
}
