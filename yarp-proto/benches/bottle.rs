//! Bottle codec benchmarks (criterion).
//!
//! Run: `cargo bench -p yarp-proto --bench bottle -- --warm-up-time 1 --measurement-time 3`
//!
//! Every group sets `Throughput::Bytes` to the size of the encoded bytes (binary) or of
//! the text line (text), so criterion reports bytes/s next to the time per operation.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use std::hint::black_box;
use yarp_proto::{Bottle, Value, Vocab32};

/// 1000 float64 values: a homogeneous (compacted, tag 0x10a) list.
fn float_list() -> Bottle {
    (0..1000).map(|i| (i as f64) * 0.001 - 0.5).collect()
}

/// A list of 10 lists of 10 lists of 10 mixed values (1000 leaves, 3 levels).
fn nested() -> Bottle {
    let mut top = Bottle::new();
    for i in 0..10 {
        let mid = top.add_list();
        for j in 0..10 {
            let leaf = mid.add_list();
            for k in 0..10 {
                let n = i * 100 + j * 10 + k;
                let v: Value = match k % 5 {
                    0 => Value::Int32(n),
                    1 => Value::Float64(n as f64 * 0.25),
                    2 => Value::string(format!("s{n}")),
                    3 => Value::Vocab32(Vocab32::new("pos")),
                    _ => Value::Int64(i64::from(n) << 33),
                };
                leaf.push(v);
            }
        }
    }
    top
}

/// A ~1 KB text line: ints, floats, words, quoted strings, a vocab and a nested list.
fn text_line() -> Vec<u8> {
    let mut s = String::new();
    let mut i = 0;
    while s.len() < 1000 {
        match i % 6 {
            0 => s.push_str(&format!("{} ", i * 37 - 500)),
            1 => s.push_str(&format!("{} ", i as f64 * 1.5 + 0.125)),
            2 => s.push_str(&format!("word{i} ")),
            3 => s.push_str(&format!("\"quoted string {i}\" ")),
            4 => s.push_str("[set] "),
            _ => s.push_str(&format!("(nested {i} (deeper 2.5 \"x y\") {{1 2 3}}) ")),
        }
        i += 1;
    }
    s.trim_end().as_bytes().to_vec()
}

fn binary(c: &mut Criterion) {
    for (name, b) in [("float64x1000", float_list()), ("nested10x10x10", nested())] {
        let bytes = b.encode();
        // sanity: what we measure is a faithful round trip
        assert_eq!(Bottle::decode(&bytes).unwrap(), b);
        let mut g = c.benchmark_group("binary");
        g.throughput(Throughput::Bytes(bytes.len() as u64));
        g.bench_with_input(BenchmarkId::new("encode", name), &b, |bn, b| {
            bn.iter(|| black_box(b).encode())
        });
        g.bench_with_input(BenchmarkId::new("decode", name), &bytes, |bn, bytes| {
            bn.iter(|| Bottle::decode(black_box(bytes)).unwrap())
        });
        g.finish();
    }
}

fn text(c: &mut Criterion) {
    let line = text_line();
    let b = Bottle::from_text(&line);
    assert!(b.len() > 50, "line parsed into {} elements", b.len());
    let printed = b.to_text();
    let mut g = c.benchmark_group("text");
    g.throughput(Throughput::Bytes(line.len() as u64));
    g.bench_with_input(BenchmarkId::new("parse", "line1k"), &line, |bn, line| {
        bn.iter(|| Bottle::from_text(black_box(line)))
    });
    g.throughput(Throughput::Bytes(printed.len() as u64));
    g.bench_with_input(BenchmarkId::new("print", "line1k"), &b, |bn, b| {
        bn.iter(|| black_box(b).to_text())
    });
    g.finish();
}

criterion_group!(benches, binary, text);
criterion_main!(benches);
