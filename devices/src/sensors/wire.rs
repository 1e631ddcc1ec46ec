//! The multiple-analog-sensors messages (C++ `multipleAnalogSensorsSerializations.thrift`)
//! and the thrift wire form C++ `yarp::os::idl::WireWriter` gives them.
//!
//! WireWriter tags every element, also in lists whose elements share a type (a list of
//! strings is `0x100` + tagged strings, where a Bottle would be the compact `0x104`). Only
//! `yarp::sig::Vector` keeps its own compact float64 form. So RPC replies are encoded here
//! rather than through `Bottle::encode`. The measurement stream happens to have no list
//! that a Bottle would compact differently, so it travels as a plain Bottle.

use super::family::{SensorFamily, FAMILY_COUNT};
use super::interfaces::SensorMeasurement;
use thiserror::Error;
use yarp_proto::{tags, Bottle, Value, Vocab32};

/// C++ `SensorMetadata`.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct SensorMetadata {
    pub name: String,
    pub frame_name: String,
    pub additional_metadata: String,
}

impl SensorMetadata {
    pub fn new(name: impl Into<String>, frame_name: impl Into<String>) -> Self {
        SensorMetadata {
            name: name.into(),
            frame_name: frame_name.into(),
            additional_metadata: String::new(),
        }
    }
}

/// C++ `SensorRPCData`: the metadata of every sensor, per family (the `getMetadata` reply).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct SensorRpcData {
    pub families: [Vec<SensorMetadata>; FAMILY_COUNT],
}

/// C++ `SensorStreamingData`: one measurement per sensor, per family.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct SensorStreamingData {
    pub families: [Vec<SensorMeasurement>; FAMILY_COUNT],
}

/// A message that does not have the shape of a MAS structure.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum WireError {
    #[error("expected a list of {expected} sensor families, got {got} elements")]
    FamilyCount { expected: usize, got: usize },
    #[error("{family}: sensor {index} is malformed: {what}")]
    BadSensor {
        family: &'static str,
        index: usize,
        what: &'static str,
    },
    #[error("{family}: expected a list of sensors")]
    NotAList { family: &'static str },
}

/// The thrift wire writer (C++ `WireWriter`), in one generation's numbering of tags
/// (YARP 4.0 renumbered the floats).
#[derive(Debug, Default)]
pub struct WireWriter {
    out: Vec<u8>,
    generation: tags::Generation,
}

impl WireWriter {
    pub fn new() -> Self {
        Self::default()
    }

    /// A writer for a peer of `generation`.
    pub fn for_generation(generation: tags::Generation) -> Self {
        WireWriter {
            out: Vec::new(),
            generation,
        }
    }

    /// Bytes already in wire form (a nested Portable that writes itself).
    pub fn raw(&mut self, bytes: &[u8]) -> &mut Self {
        self.out.extend_from_slice(bytes);
        self
    }

    /// The generation whose tags it writes.
    pub fn generation(&self) -> tags::Generation {
        self.generation
    }

    /// `writeBool`: the vocab `ok` or `fail`.
    pub fn bool(&mut self, b: bool) -> &mut Self {
        self.vocab(Vocab32::new(if b { "ok" } else { "fail" }))
    }

    /// A `list<i32>` (or of an enum): compact, as the generated code writes it.
    pub fn int32_list(&mut self, v: impl ExactSizeIterator<Item = i32>) -> &mut Self {
        self.i32(tags::LIST | tags::INT32);
        self.i32(v.len() as i32);
        for x in v {
            self.i32(x);
        }
        self
    }

    fn i32(&mut self, x: i32) {
        self.out.extend_from_slice(&x.to_le_bytes());
    }

    /// `writeListHeader(n)` / `writeListBegin(0, n)`: a mixed list, elements tagged.
    pub fn list_header(&mut self, n: usize) -> &mut Self {
        self.i32(tags::LIST);
        self.i32(n as i32);
        self
    }

    pub fn string(&mut self, s: &str) -> &mut Self {
        self.i32(tags::STRING);
        self.i32(s.len() as i32);
        self.out.extend_from_slice(s.as_bytes());
        self
    }

    /// A `list<string>`: compact, its strings untagged, as the generated code writes it.
    pub fn string_list(&mut self, v: &[String]) -> &mut Self {
        self.i32(tags::LIST | tags::STRING);
        self.i32(v.len() as i32);
        for s in v {
            self.i32(s.len() as i32);
            self.out.extend_from_slice(s.as_bytes());
        }
        self
    }

    pub fn int32(&mut self, x: i32) -> &mut Self {
        self.i32(tags::INT32);
        self.i32(x);
        self
    }

    /// A tagged int16 (tag, then two bytes).
    pub fn int16(&mut self, x: i16) -> &mut Self {
        self.i32(tags::INT16);
        self.out.extend_from_slice(&x.to_le_bytes());
        self
    }

    pub fn vocab(&mut self, v: Vocab32) -> &mut Self {
        self.i32(tags::VOCAB32);
        self.i32(v.0);
        self
    }

    pub fn float64(&mut self, x: f64) -> &mut Self {
        self.i32(self.generation.float64());
        self.out.extend_from_slice(&x.to_le_bytes());
        self
    }

    /// `ConnectionWriter::appendInt16`: two bytes, untagged (how C++ writes an
    /// `ApplicationNetworkProtocolVersion`).
    pub fn raw_int16(&mut self, x: i16) -> &mut Self {
        self.out.extend_from_slice(&x.to_le_bytes());
        self
    }

    /// A `yarp::sig::Vector`: its own compact float64 list.
    pub fn float_vector(&mut self, v: &[f64]) -> &mut Self {
        self.i32(tags::LIST | self.generation.float64());
        self.i32(v.len() as i32);
        for x in v {
            self.out.extend_from_slice(&x.to_le_bytes());
        }
        self
    }

    pub fn into_bytes(self) -> Vec<u8> {
        self.out
    }
}

impl SensorRpcData {
    /// The metadata of `family`.
    pub fn family(&self, family: SensorFamily) -> &[SensorMetadata] {
        &self.families[family.index()]
    }

    /// The `getMetadata` reply as C++ writes it: 12 lists of `(name frame additional)`.
    pub fn encode_reply(&self) -> Vec<u8> {
        let mut w = WireWriter::new();
        w.list_header(FAMILY_COUNT);
        for family in &self.families {
            w.list_header(family.len());
            for m in family {
                w.list_header(3)
                    .string(&m.name)
                    .string(&m.frame_name)
                    .string(&m.additional_metadata);
            }
        }
        w.into_bytes()
    }

    /// Reads a received `getMetadata` reply (either list form).
    pub fn from_bottle(b: &Bottle) -> Result<SensorRpcData, WireError> {
        let mut data = SensorRpcData::default();
        for (family, list) in families_of(b)? {
            for (index, v) in list.iter().enumerate() {
                let bad = |what| WireError::BadSensor {
                    family: family.tag(),
                    index,
                    what,
                };
                let fields = v.as_list().ok_or(bad("not a list"))?;
                let text = |i: usize| -> Result<String, WireError> {
                    match fields.get(i) {
                        Some(Value::String(s)) => Ok(String::from_utf8_lossy(s).into_owned()),
                        None => Ok(String::new()),
                        Some(_) => Err(bad("a field is not a string")),
                    }
                };
                data.families[family.index()].push(SensorMetadata {
                    name: text(0)?,
                    frame_name: text(1)?,
                    additional_metadata: text(2)?,
                });
            }
        }
        Ok(data)
    }
}

impl SensorStreamingData {
    /// The measurements of `family`.
    pub fn family(&self, family: SensorFamily) -> &[SensorMeasurement] {
        &self.families[family.index()]
    }

    /// The message streamed on `measures:o`: 12 lists of `((values...) timestamp)`.
    pub fn to_bottle(&self) -> Bottle {
        let mut b = Bottle::with_capacity(FAMILY_COUNT);
        for family in &self.families {
            let list: Bottle = family
                .iter()
                .map(|m| {
                    let values: Bottle = m.values.iter().copied().collect();
                    Value::List(Bottle::new().with(Value::List(values)).with(m.timestamp))
                })
                .collect();
            b.push(Value::List(list));
        }
        b
    }

    /// Reads a received measurement message.
    pub fn from_bottle(b: &Bottle) -> Result<SensorStreamingData, WireError> {
        let mut data = SensorStreamingData::default();
        for (family, list) in families_of(b)? {
            for (index, v) in list.iter().enumerate() {
                let bad = |what| WireError::BadSensor {
                    family: family.tag(),
                    index,
                    what,
                };
                let pair = v.as_list().ok_or(bad("not a list"))?;
                let values = pair
                    .get(0)
                    .and_then(Value::as_list)
                    .ok_or(bad("no measurement vector"))?
                    .iter()
                    .map(|x| x.as_f64().ok_or(bad("a value is not a number")))
                    .collect::<Result<Vec<f64>, _>>()?;
                let timestamp = pair
                    .get(1)
                    .and_then(Value::as_f64)
                    .ok_or(bad("no timestamp"))?;
                data.families[family.index()].push(SensorMeasurement { values, timestamp });
            }
        }
        Ok(data)
    }
}

/// The 12 family lists of a metadata reply or measurement message.
fn families_of(b: &Bottle) -> Result<impl Iterator<Item = (SensorFamily, &Bottle)>, WireError> {
    if b.len() != FAMILY_COUNT {
        return Err(WireError::FamilyCount {
            expected: FAMILY_COUNT,
            got: b.len(),
        });
    }
    let lists = SensorFamily::ALL
        .iter()
        .zip(b.iter())
        .map(|(f, v)| {
            v.as_list()
                .map(|l| (*f, l))
                .ok_or(WireError::NotAList { family: f.tag() })
        })
        .collect::<Result<Vec<_>, _>>()?;
    Ok(lists.into_iter())
}

/// The `getMetadata` request as the C++ client writes it: a list of one tagged string.
pub fn encode_get_metadata_request() -> Vec<u8> {
    let mut w = WireWriter::new();
    w.list_header(1).string(super::rpc::GET_METADATA);
    w.into_bytes()
}
