//! The Cartesian solver's time per request and the controller's time per period, for
//! BENCHMARKS.md: iCubGenova02's left arm (left_v2, torso blocked: 7 DOF), a pose 20-30 cm
//! away, against the solver's period (20 ms) and the controller's (10 ms).

use criterion::{criterion_group, criterion_main, Criterion};
use icub_cartesian::protocol::{self, word};
use icub_cartesian::solver::{SolverConfig, SolverCore};
use icub_ikin::minjerk::{CtrlPose, MinJerkController};
use icub_ikin::{Limb, RAD2DEG};
use nalgebra::DVector;
use yarp_proto::{Bottle, Property};

fn genova02_solver() -> SolverCore {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../../shared/robots-configuration/iCubGenova02/cartesianSolver.ini"
    );
    let ini = Property::from_config_text(std::fs::read_to_string(path).expect("the robot's file"))
        .expect("ini");
    let cfg = SolverConfig::from_ini("left_arm", &ini).expect("left_arm");
    let limb = Limb::arm("left_v2").unwrap();
    let limits: Vec<(f64, f64)> = limb
        .chain()
        .links()
        .iter()
        .map(|l| (l.min * RAD2DEG, l.max * RAD2DEG))
        .collect();
    SolverCore::new(cfg, &limits).unwrap()
}

fn pose_of(q: &[f64]) -> Vec<f64> {
    let mut limb = Limb::arm("left_v2").unwrap();
    limb.pose_from_encoders(&[0.0; 3], q)
        .unwrap()
        .iter()
        .copied()
        .collect()
}

fn bench(c: &mut Criterion) {
    let start = [-30.0, 30.0, 0.0, 45.0, 0.0, 0.0, 0.0];
    let targets = [
        pose_of(&[-50.0, 40.0, 20.0, 70.0, -20.0, -10.0, 10.0]),
        pose_of(&[-40.0, 20.0, 30.0, 60.0, 30.0, 10.0, -10.0]),
    ];
    let mut solver = genova02_solver();
    let mut k = 0;
    c.bench_function("solver: full pose, left arm 7 DOF (period 20 ms)", |b| {
        b.iter(|| {
            solver
                .set_feedback(&[vec![0.0; 3], start.to_vec()])
                .unwrap();
            k = (k + 1) % targets.len();
            solver.on_input(&Bottle::new().with(protocol::vector_option(word::XD, &targets[k])));
            solver.tick().expect("a solve")
        })
    });
    let arm = Limb::arm("left_v2").unwrap();
    let mut chain = arm.into_chain();
    let q0: Vec<f64> = start.iter().map(|v| v / RAD2DEG).collect();
    chain.set_ang(&q0).unwrap();
    let mut ctrl = MinJerkController::new(chain, CtrlPose::Full, 0.01).unwrap();
    ctrl.set_exec_time(1.0);
    ctrl.restart(&q0).unwrap();
    let qd = DVector::from_vec(vec![-0.8, 0.6, 0.3, 1.0, 0.2, -0.1, 0.1]);
    let xd = &targets[0];
    c.bench_function("controller: one min-jerk step (period 10 ms)", |b| {
        b.iter(|| ctrl.iterate(xd, &qd, None).clone())
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
