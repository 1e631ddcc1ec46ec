//! What a client, a solver or a robot may send icub-main's Cartesian and gaze
//! controllers: bytes read as a text bottle (first byte even) or as a binary one (odd),
//! then given to every parser of network input the cores have: the solver's `rpc` and
//! `in` port, the server's `rpc:i`, `command:i` and the solver's answers, the gaze
//! controller's `rpc` and its mono/stereo targets; the cores then run a cycle on it.
//! Must never panic (a `[nack]` or nothing is the answer to nonsense).
#![no_main]

use icub_cartesian::gaze::core::{GazeConfig, GazeCore, GazeOutput};
use icub_cartesian::server::{CycleOutput, ServerConfig, ServerCore, SolverLink};
use icub_cartesian::solver::{SolverConfig, SolverCore};
use libfuzzer_sys::fuzz_target;
use yarp_proto::{Bottle, Property};

/// A solver that answers every request with the fuzzed bottle.
struct EchoSolver<'a>(&'a Bottle);

impl SolverLink for EchoSolver<'_> {
    fn rpc(&mut self, _: &Bottle) -> Option<Bottle> {
        Some(self.0.clone())
    }
    fn send(&mut self, _: &Bottle) {}
}

fuzz_target!(|data: &[u8]| {
    let Some((&pick, rest)) = data.split_first() else {
        return;
    };
    let b = if pick % 2 == 0 {
        Bottle::from_text(rest)
    } else {
        match Bottle::decode(rest) {
            Ok(b) => b,
            Err(_) => return,
        }
    };
    let limits = vec![(-90.0, 90.0); 10];
    let ini = Property::from_config_text("[left_arm]\nname s/left_arm\ntype left_v2\n").unwrap();
    let mut solver =
        SolverCore::new(SolverConfig::from_ini("left_arm", &ini).unwrap(), &limits).unwrap();
    solver.respond(&b);
    solver.on_input(&b);
    solver.tick();
    let cfg = Property::from_config_text(
        "[GENERAL]\nControllerName c\nSolverNameToConnect s\nKinematicPart arm\n\
         KinematicType left_v2\nNumberOfDrivers 2\n[DRIVER_0]\nKey torso\n[DRIVER_1]\nKey arm\n",
    )
    .unwrap();
    let mut server = ServerCore::new(ServerConfig::from_property(&cfg).unwrap(), &limits).unwrap();
    let mut out = CycleOutput::default();
    server.respond(&b, &mut EchoSolver(&b), &mut out);
    server.on_command(&b, &mut EchoSolver(&b));
    server.cycle(0.01, &[0.0; 10], Some(&b), true, &mut EchoSolver(&b));
    server.cycle(0.02, &[1.0; 10], None, true, &mut EchoSolver(&b));
    let mut gaze =
        GazeCore::new(GazeConfig::from_property(&Property::new()), &limits[..6]).unwrap();
    let mut gout = GazeOutput::default();
    gaze.respond(&b, &mut gout);
    gaze.target_of_mono(&b);
    gaze.target_of_stereo(&b);
    gaze.cycle(0.01, &[0.0; 3], &[0.0; 6]);
});
