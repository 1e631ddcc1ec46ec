//! Forward kinematics, Jacobians and IK of the iCub arm.

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion};
use icub_ikin::{Chain, IkConfig, IkSolver, Limb};

/// Right arm v2 with the torso released: 10 DOF.
fn arm10() -> Chain {
    let mut c = Limb::arm("right_v2").unwrap().into_chain();
    for i in 0..3 {
        c.release_link(i).unwrap();
    }
    c
}

fn bench(c: &mut Criterion) {
    let chain = arm10();
    let q = [0.1, -0.2, 0.3, -0.5, 0.4, 0.2, 1.0, 0.1, -0.3, 0.05];
    c.bench_function("fk_10dof_h", |b| {
        b.iter(|| black_box(&chain).h_at(black_box(&q)).unwrap())
    });
    c.bench_function("fk_10dof_pose7", |b| {
        b.iter(|| black_box(&chain).pose_at(black_box(&q)).unwrap())
    });
    c.bench_function("geo_jacobian_10dof", |b| {
        b.iter(|| black_box(&chain).geo_jacobian_at(black_box(&q)).unwrap())
    });
    c.bench_function("ana_jacobian_10dof", |b| {
        b.iter(|| black_box(&chain).ana_jacobian_at(black_box(&q)).unwrap())
    });

    let target = chain
        .h_at(&[0.3, 0.1, -0.4, -0.9, 0.6, 0.5, 1.2, -0.4, -0.5, 0.1])
        .unwrap();
    let pose = IkSolver::new(IkConfig::default()).unwrap();
    let position = IkSolver::new(IkConfig::position()).unwrap();
    c.bench_function("ik_10dof_pose", |b| {
        b.iter(|| pose.solve(&chain, black_box(&target), Some(&q)).unwrap())
    });
    c.bench_function("ik_10dof_position", |b| {
        b.iter(|| {
            position
                .solve(&chain, black_box(&target), Some(&q))
                .unwrap()
        })
    });
    let arm7 = Limb::arm("right_v2").unwrap().into_chain();
    let target7 = arm7.h_at(&[-0.9, 0.6, 0.5, 1.2, -0.4, -0.5, 0.1]).unwrap();
    c.bench_function("ik_7dof_pose", |b| {
        b.iter(|| {
            pose.solve(&arm7, black_box(&target7), Some(&[0.0; 7]))
                .unwrap()
        })
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
