//! The generic conversion against the built-in ones, per message, as the gateway does it
//! from YARP to ROS: the Bottle (taken, not copied) to a ROS message, then CDR-encoded (as
//! the publisher does). JointState of an arm (16 joints) and a 640x480 rgb8 Image. The
//! `*_published` cases add what the gateway does next, a DDS write of the message
//! (ros2-client best-effort publisher on a loopback participant, ROS domain 232, no
//! reader; run under `netns-run`), so the
//! difference can be read against the gateway's whole per-message time.
//!
//! Run: `cargo bench -p yarp-ros2-gateway --bench conversion -- --warm-up-time 1 --measurement-time 3`

use byteorder::LittleEndian;
use criterion::{criterion_group, criterion_main, BatchSize, Criterion};
use std::hint::black_box;
use yarp_proto::{Bottle, Value};
use yarp_ros2_gateway::convert::{self, Ctx};
use yarp_ros2_gateway::dynmsg::{MsgSeed, Value as Ros};
use yarp_ros2_gateway::mapping::Conversion;
use yarp_ros2_gateway::{generic, image, types};

const JOINTS: usize = 16;
const JS: &str = "sensor_msgs/msg/JointState";
const IMAGE: &str = "sensor_msgs/msg/Image";

fn publish(m: &Ros) -> Vec<u8> {
    cdr_encoding::to_vec::<_, LittleEndian>(m).expect("encodes")
}

fn joint_names() -> Vec<String> {
    (0..JOINTS).map(|j| format!("l_arm_joint_{j}")).collect()
}

/// A control board's `state:o` (degrees), for the built-in `joint_state` conversion.
fn state_bottle() -> Bottle {
    (0..JOINTS)
        .map(|j| Value::Float64(j as f64 * 3.5 - 20.0))
        .collect()
}

/// The same message in the generic layout (radians, names in the Bottle).
fn generic_joint_state() -> Bottle {
    let names: Bottle = joint_names().into_iter().map(Value::string).collect();
    let pos: Bottle = (0..JOINTS)
        .map(|j| Value::Float64((j as f64 * 3.5 - 20.0).to_radians()))
        .collect();
    let mut b = Bottle::from_text("((0 0) \"\")");
    b.push(names);
    b.push(pos);
    b.push(Bottle::new());
    b.push(Bottle::new());
    b
}

fn pixels() -> Vec<u8> {
    (0..640 * 480 * 3).map(|i| (i % 251) as u8).collect()
}

fn generic_image() -> Bottle {
    let mut b = Bottle::from_text("((0 0) cam) 480 640 rgb8 0 1920");
    b.push(Value::Blob(pixels()));
    b
}

fn bench(c: &mut Criterion) {
    let (_ctx, mut node) = yarp_ros2_gateway::ros::start_node(
        232,
        &["127.0.0.1".parse().unwrap()],
        "/",
        "conversion_bench",
    )
    .expect("DDS participant");
    // Best effort: with no reader, a reliable writer's window would fill and block.
    let q = yarp_ros2_gateway::mapping::Qos {
        reliability: Some(yarp_ros2_gateway::mapping::Reliability::BestEffort),
        ..Default::default()
    };
    let js_pub = yarp_ros2_gateway::ros::publisher(&mut node, "/bench/joint_states", JS, &q)
        .expect("publisher");
    let img_pub =
        yarp_ros2_gateway::ros::publisher(&mut node, "/bench/image", IMAGE, &q).expect("publisher");
    let names = joint_names();
    let ctx = Ctx {
        joint_names: &names,
        stamp_ns: 1_700_000_000_000_000_000,
        ..Default::default()
    };
    let mut g = c.benchmark_group("joint_state_16");
    let state = state_bottle();
    g.bench_function("builtin", |b| {
        b.iter_batched(
            || state.clone(),
            |s| {
                let m = convert::to_ros_owned(Conversion::JointState, JS, s, &ctx).unwrap();
                black_box(publish(&m))
            },
            BatchSize::SmallInput,
        )
    });
    let gen = generic_joint_state();
    g.bench_function("generic", |b| {
        b.iter_batched(
            || gen.clone(),
            |s| {
                let m = convert::to_ros_owned(Conversion::Generic, JS, s, &ctx).unwrap();
                black_box(publish(&m))
            },
            BatchSize::SmallInput,
        )
    });
    for (label, conv, input) in [
        ("builtin_published", Conversion::JointState, &state),
        ("generic_published", Conversion::Generic, &gen),
    ] {
        g.bench_function(label, |b| {
            b.iter_batched(
                || input.clone(),
                |s| {
                    let m = convert::to_ros_owned(conv, JS, s, &ctx).unwrap();
                    js_pub.publish(m).unwrap();
                },
                BatchSize::SmallInput,
            )
        });
    }
    // ROS -> YARP (no built-in conversion of JointState this way): decode, then Bottle.
    let wire = publish(&convert::to_ros_owned(Conversion::Generic, JS, gen.clone(), &ctx).unwrap());
    let js = types::lookup(JS).unwrap();
    g.bench_function("generic_ros_to_yarp", |b| {
        b.iter(|| {
            use serde::de::DeserializeSeed;
            let mut d = cdr_encoding::CdrDeserializer::<LittleEndian>::new(&wire);
            let m = MsgSeed(js).deserialize(&mut d).unwrap();
            black_box(generic::to_yarp(js, &m).unwrap())
        })
    });
    g.finish();

    let mut g = c.benchmark_group("image_640x480_rgb8");
    g.sample_size(30);
    let yarp_img = image::yarp_image("rgb", 3, 640, 480, pixels());
    g.bench_function("builtin", |b| {
        b.iter_batched(
            || yarp_img.clone(),
            |s| {
                let m = convert::to_ros_owned(Conversion::Image, IMAGE, s, &ctx).unwrap();
                black_box(publish(&m))
            },
            BatchSize::LargeInput,
        )
    });
    let gen = generic_image();
    g.bench_function("generic", |b| {
        b.iter_batched(
            || gen.clone(),
            |s| {
                let m = convert::to_ros_owned(Conversion::Generic, IMAGE, s, &ctx).unwrap();
                black_box(publish(&m))
            },
            BatchSize::LargeInput,
        )
    });
    for (label, conv, input) in [
        ("builtin_published", Conversion::Image, &yarp_img),
        ("generic_published", Conversion::Generic, &gen),
    ] {
        g.bench_function(label, |b| {
            b.iter_batched(
                || input.clone(),
                |s| {
                    let m = convert::to_ros_owned(conv, IMAGE, s, &ctx).unwrap();
                    img_pub.publish(m).unwrap();
                },
                BatchSize::LargeInput,
            )
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
