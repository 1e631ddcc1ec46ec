//! REP-2016 type hashes (`RIHS01_<sha256 hex>`), computed from the type descriptions of
//! [`crate::types::lookup`] (run-time definitions, else the built-in catalog).
//!
//! The hash is SHA-256 over the canonical JSON of the type description, as
//! `rosidl_generator_type_description` writes it: the `TypeDescription` of the type itself
//! plus every transitively referenced type (sorted by name), with `default_value` removed,
//! serialized by Python's `json.dumps` with separators `", "` and `": "`, keys in
//! declaration order.

use crate::types::{lookup, Base, MsgType};
use sha2::{Digest, Sha256};
use std::collections::BTreeMap;
use std::fmt::Write;

/// A type the catalog cannot describe completely.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum HashError {
    #[error("unknown ROS type {0}")]
    UnknownType(String),
}

/// The `RIHS01_…` hash of a catalog type.
pub fn rihs01(type_name: &str) -> Result<String, HashError> {
    let json = canonical_json(type_name)?;
    let digest = Sha256::digest(json.as_bytes());
    let mut s = String::with_capacity(71);
    s.push_str("RIHS01_");
    for b in digest {
        let _ = write!(s, "{b:02x}");
    }
    Ok(s)
}

/// The DDS USER_DATA QoS value rmw announces for an endpoint of `type_name`
/// (`typehash=RIHS01_…;`, as `rmw_dds_common::encode_type_hash_for_user_data_qos`). rclpy
/// reads the hash of remote endpoints from there.
pub fn user_data(type_name: &str) -> Result<String, HashError> {
    Ok(format!("typehash={};", rihs01(type_name)?))
}

/// `(DDS type name, USER_DATA)` for every endpoint type of the catalog, as rmw announces
/// them: a message's own hash, and for a service's request and response topics
/// (`pkg::srv::dds_::Name_Request_`, `…_Response_`) the hash of the service `pkg/srv/Name`.
pub fn endpoint_user_data() -> Vec<(String, String)> {
    let mut out = Vec::new();
    for m in crate::types::MESSAGES {
        let Some((_, kind, name)) = crate::types::split_name(m.name) else {
            continue;
        };
        let hashed = if kind == "srv" {
            // Only the request/response topics are endpoints; `_Event` and the service
            // description itself are not published here.
            match name
                .strip_suffix("_Request")
                .or_else(|| name.strip_suffix("_Response"))
            {
                Some(service) => m.name.replace(name, service),
                None => continue,
            }
        } else {
            m.name.to_string()
        };
        if let (Some(dds), Ok(ud)) = (crate::types::dds_type_name(m.name), user_data(&hashed)) {
            out.push((dds, ud));
        }
    }
    out
}

/// The exact text that is hashed (exposed for tests and debugging).
pub fn canonical_json(type_name: &str) -> Result<String, HashError> {
    let top = get(type_name)?;
    let mut refs = BTreeMap::new();
    collect_refs(top, &mut refs)?;
    let mut out = String::from("{\"type_description\": ");
    write_description(&mut out, top);
    out.push_str(", \"referenced_type_descriptions\": [");
    for (i, t) in refs.values().enumerate() {
        if i > 0 {
            out.push_str(", ");
        }
        write_description(&mut out, t);
    }
    out.push_str("]}");
    Ok(out)
}

fn get(name: &str) -> Result<&'static MsgType, HashError> {
    lookup(name).ok_or_else(|| HashError::UnknownType(name.to_string()))
}

fn collect_refs(
    t: &'static MsgType,
    refs: &mut BTreeMap<&'static str, &'static MsgType>,
) -> Result<(), HashError> {
    for field in t.fields {
        if let Base::Nested(n) = field.base {
            if !refs.contains_key(n) {
                let nt = get(n)?;
                refs.insert(n, nt);
                collect_refs(nt, refs)?;
            }
        }
    }
    Ok(())
}

fn write_description(out: &mut String, t: &MsgType) {
    let _ = write!(out, "{{\"type_name\": \"{}\", \"fields\": [", t.name);
    for (i, field) in t.fields.iter().enumerate() {
        if i > 0 {
            out.push_str(", ");
        }
        let nested = match field.base {
            Base::Nested(n) => n,
            Base::Prim(_) => "",
        };
        let _ = write!(
            out,
            "{{\"name\": \"{}\", \"type\": {{\"type_id\": {}, \"capacity\": {}, \
             \"string_capacity\": {}, \"nested_type_name\": \"{}\"}}}}",
            field.name,
            field.type_id(),
            field.capacity(),
            field.string_capacity,
            nested
        );
    }
    out.push_str("]}");
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Values from the `type_hashes` of the Kilted wheels' `share/**/*.json` files.
    #[test]
    fn matches_rosidl_for_known_types() {
        let cases = [
            (
                "std_msgs/msg/String",
                "RIHS01_df668c740482bbd48fb39d76a70dfd4bd59db1288021743503259e948f6b1a18",
            ),
            (
                "std_msgs/msg/MultiArrayLayout",
                "RIHS01_4c66e6f78e740ac103a94cf63259f968e48c617e7699e829b63c21a5cb50dac6",
            ),
            (
                "builtin_interfaces/msg/Time",
                "RIHS01_b106235e25a4c5ed35098aa0a61a3ee9c9b18d197f398b0e4206cea9acf9c197",
            ),
            (
                "std_srvs/srv/Empty",
                "RIHS01_5888399dedec5ccc85ea6451949fd2c9f97bfdf963f9a588821639fcd31b5d19",
            ),
            (
                "std_srvs/srv/Empty_Request",
                "RIHS01_458eaf200a3f63d9cc53d19436edebc0c140ef4c93ca75d5bd4ce19fd7759e35",
            ),
            // The wrappers' sensor, odometry and transform topics (tf2_msgs: the hash
            // Kilted's `rosidl hash` gives for ros2/geometry2's TFMessage).
            (
                "sensor_msgs/msg/CameraInfo",
                "RIHS01_b3dfd68ff46c9d56c80fd3bd4ed22c7a4ddce8c8348f2f59c299e73118e7e275",
            ),
            (
                "sensor_msgs/msg/LaserScan",
                "RIHS01_64c191398013af96509d518dac71d5164f9382553fce5c1f8cca5be7924bd828",
            ),
            (
                "sensor_msgs/msg/PointCloud2",
                "RIHS01_9198cabf7da3796ae6fe19c4cb3bdd3525492988c70522628af5daa124bae2b5",
            ),
            (
                "sensor_msgs/msg/BatteryState",
                "RIHS01_4bee5dfce981c98faa6828b868307a0a73f992ed0789f374ee96c8f840e69741",
            ),
            (
                "nav_msgs/msg/Odometry",
                "RIHS01_3cc97dc7fb7502f8714462c526d369e35b603cfc34d946e3f2eda2766dfec6e0",
            ),
            (
                "geometry_msgs/msg/TwistStamped",
                "RIHS01_5f0fcd4f81d5d06ad9b4c4c63e3ea51b82d6ae4d0558f1d475229b1121db6f64",
            ),
            (
                "tf2_msgs/msg/TFMessage",
                "RIHS01_e369d0f05a23ae52508854b66f6aa0437f3449d652e8cbf22d5abe85d020f087",
            ),
        ];
        for (name, want) in cases {
            assert_eq!(rihs01(name).unwrap(), want, "{name}");
        }
    }

    #[test]
    fn user_data_form() {
        assert_eq!(
            user_data("std_msgs/msg/String").unwrap(),
            "typehash=RIHS01_df668c740482bbd48fb39d76a70dfd4bd59db1288021743503259e948f6b1a18;"
        );
    }

    #[test]
    fn unknown_type_is_an_error() {
        assert_eq!(
            rihs01("nope/msg/Nope"),
            Err(HashError::UnknownType("nope/msg/Nope".into()))
        );
    }

    #[test]
    fn canonical_form_of_a_flat_type() {
        assert_eq!(
            canonical_json("std_msgs/msg/Bool").unwrap(),
            "{\"type_description\": {\"type_name\": \"std_msgs/msg/Bool\", \"fields\": \
             [{\"name\": \"data\", \"type\": {\"type_id\": 15, \"capacity\": 0, \
             \"string_capacity\": 0, \"nested_type_name\": \"\"}}]}, \
             \"referenced_type_descriptions\": []}"
        );
    }
}
