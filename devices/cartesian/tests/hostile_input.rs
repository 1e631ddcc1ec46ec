//! Malformed commands and targets (wrong types, missing items, lists for numbers, NaN, huge
//! indices) at every parser of network input the Cartesian and gaze cores have: a clear
//! `[nack]` or nothing, never a panic.

use icub_cartesian::gaze::core::{GazeConfig, GazeCore, GazeOutput};
use icub_cartesian::server::{CycleOutput, ServerConfig, ServerCore, SolverLink};
use icub_cartesian::solver::{SolverConfig, SolverCore};
use yarp_proto::{Bottle, Property};

/// Texts of bottles no well-behaved client sends.
const HOSTILE: &[&str] = &[
    "",
    "()",
    "[get]",
    "[set]",
    "[get] [lim] -1",
    "[get] [lim] 99999999999",
    "[get] [pose] -5",
    "[get] [pose] (1 2)",
    "[set] [lim] 1 \"a\" 3",
    "[set] [dof] 1",
    "[set] [dof] (nan inf -inf)",
    "[set] [resp] (1e308 -1e308)",
    "[set] [tip] (1 2)",
    "[set] [tsk2] (x (1) (2))",
    "[set] [conv] 3",
    "[set] [time] \"slow\"",
    "[go] [full] 1.0 3",
    "[go] [full] \"t\" (1 2 3 4 5 6 7)",
    "[go] [xyz] 1 ()",
    "[ask] ([xd] (1))",
    "[ask] ([xd] 3)",
    "[ask] ([xd] (nan nan nan)) ([q] (1 2 3 4 5 6 7 8 9 10 11 12))",
    "[rest]",
    "[rest] \"zero\"",
    "[del] 4",
    "[even] [regi] [ogoi] 7",
    "[even] [regi] [ogoi] \"x\"",
    "[tvel] (1 2)",
    "([xd] (1 2)) ([dof] (0)) ([pose] 3) ([mode] [xyz])",
    "look 3D 1",
    "look mono (left 1 2 z)",
    "look stereo (1 2)",
    "look ang (abs 1)",
    "get 2D (left)",
    "get 3D mono (1 2 3 4)",
    "get pose nobody",
    "bind pitch \"a\"",
    "rest (0)",
    "set Tneck (1)",
    "set track",
    "regi ongo 2",
];

struct NoSolver;

impl SolverLink for NoSolver {
    fn rpc(&mut self, _: &Bottle) -> Option<Bottle> {
        None
    }
    fn send(&mut self, _: &Bottle) {}
}

fn limits(n: usize) -> Vec<(f64, f64)> {
    vec![(-90.0, 90.0); n]
}

#[test]
fn the_solver_the_server_and_the_gaze_core_take_hostile_input() {
    let ini = Property::from_config_text("[left_arm]\nname s/left_arm\ntype left_v2\n").unwrap();
    let mut solver = SolverCore::new(
        SolverConfig::from_ini("left_arm", &ini).unwrap(),
        &limits(10),
    )
    .unwrap();
    let cfg = Property::from_config_text(
        "[GENERAL]\nControllerName c\nSolverNameToConnect s\nKinematicPart arm\n\
         KinematicType left_v2\nNumberOfDrivers 2\n[DRIVER_0]\nKey torso\n[DRIVER_1]\nKey arm\n",
    )
    .unwrap();
    let mut server =
        ServerCore::new(ServerConfig::from_property(&cfg).unwrap(), &limits(10)).unwrap();
    let mut gaze = GazeCore::new(GazeConfig::from_property(&Property::new()), &limits(6)).unwrap();
    for text in HOSTILE {
        let b = Bottle::from_text(text);
        solver.respond(&b);
        solver.on_input(&b);
        solver.tick();
        let mut out = CycleOutput::default();
        server.respond(&b, &mut NoSolver, &mut out);
        server.on_command(&b, &mut NoSolver);
        server.cycle(1.0, &[0.0; 10], Some(&b), true, &mut NoSolver);
        let mut gout = GazeOutput::default();
        gaze.respond(&b, &mut gout);
        gaze.target_of_mono(&b);
        gaze.target_of_stereo(&b);
        gaze.cycle(1.0, &[0.0; 3], &[0.0; 6]);
    }
}
