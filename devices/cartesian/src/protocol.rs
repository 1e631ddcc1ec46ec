//! The words and option lists of icub-main's Cartesian protocol, shared by the solver,
//! the server and the client: the vocabs of `CommonCartesianController.h` and
//! `iKinVocabs.h`, and iKinHlp's `CartesianHelper` options — `([xd] (x y z ...))`,
//! `([pose] [full])`, `([mode] [cont])`, `([tok] 12.5)` — looked up by key, in any order.

use yarp_proto::{Bottle, Value};

/// The protocol's vocabs, as C++ spells them (4 characters at most).
pub mod word {
    pub const GET: &str = "get";
    pub const SET: &str = "set";
    pub const ASK: &str = "ask";
    pub const STORE: &str = "stor";
    pub const RESTORE: &str = "rest";
    pub const DELETE: &str = "del";
    pub const GO: &str = "go";
    pub const TASKVEL: &str = "tvel";
    pub const STOP: &str = "stop";
    pub const EVENT: &str = "even";
    pub const SUSPEND: &str = "susp";
    pub const RUN: &str = "run";
    pub const STATUS: &str = "stat";
    pub const HELP: &str = "help";
    pub const CFG: &str = "cfg";
    pub const QUIT: &str = "quit";

    pub const MODE: &str = "mode";
    pub const REFERENCE: &str = "refe";
    pub const PRIO: &str = "prio";
    pub const TIME: &str = "time";
    pub const TOL: &str = "tol";
    pub const DOF: &str = "dof";
    pub const REST_POS: &str = "resp";
    pub const REST_WEIGHTS: &str = "resw";
    pub const DES: &str = "des";
    pub const LIM: &str = "lim";
    pub const XD: &str = "xd";
    pub const X: &str = "x";
    pub const Q: &str = "q";
    pub const XDOT: &str = "xdot";
    pub const QDOT: &str = "qdot";
    pub const TIP: &str = "tip";
    pub const DONE: &str = "done";
    pub const IS_SOLVER_ON: &str = "ison";
    pub const POSE: &str = "pose";
    pub const INFO: &str = "info";
    pub const TWEAK: &str = "twea";
    pub const REGISTER: &str = "regi";
    pub const UNREGISTER: &str = "unre";
    pub const LIST: &str = "list";
    pub const TOKEN: &str = "tok";
    pub const VERBOSITY: &str = "verb";
    pub const TASK2: &str = "tsk2";
    pub const CONVERGENCE: &str = "conv";

    pub const FULL: &str = "full";
    pub const XYZ: &str = "xyz";
    pub const ANG: &str = "ang";
    pub const TRACK: &str = "cont";
    pub const SINGLE: &str = "shot";
    pub const TRUE: &str = "true";
    pub const FALSE: &str = "fals";
    pub const ON: &str = "on";
    pub const OFF: &str = "off";
    pub const ONGOING: &str = "ogoi";

    pub const ACK: &str = "ack";
    pub const NACK: &str = "nack";
}

/// `[ack]`.
pub fn ack() -> Bottle {
    Bottle::new().with(Value::vocab(word::ACK))
}

/// `[nack]`.
pub fn nack() -> Bottle {
    Bottle::new().with(Value::vocab(word::NACK))
}

/// Whether item `i` is the vocab `w` (a string of the same text counts, as C++'s
/// `asVocab32` reads strings: a command typed in `yarp rpc` works).
pub fn is_word(b: &Bottle, i: usize, w: &str) -> bool {
    word_at(b, i).is_some_and(|got| got == w)
}

/// The text of item `i` when it is a vocab or a string.
pub fn word_at(b: &Bottle, i: usize) -> Option<String> {
    match b.get(i)? {
        Value::Vocab32(v) => Some(v.as_string()),
        Value::String(_) => b.get(i)?.as_str().map(str::to_string),
        _ => None,
    }
}

/// Whether a reply starts with `[ack]`.
pub fn is_ack(reply: &Bottle) -> bool {
    is_word(reply, 0, word::ACK)
}

/// A list of float64 values.
pub fn f64_list(v: &[f64]) -> Value {
    Value::List(v.iter().copied().collect())
}

/// A list of int32 values.
pub fn i32_list(v: impl IntoIterator<Item = i32>) -> Value {
    Value::List(v.into_iter().map(Value::Int32).collect())
}

/// The numbers of a list value (ints read as floats).
pub fn numbers(v: &Value) -> Option<Vec<f64>> {
    v.as_list()?.iter().map(Value::as_f64).collect()
}

/// `([tag] (v0 v1 ...))` (`addVectorOption`).
pub fn vector_option(tag: &str, v: &[f64]) -> Value {
    Value::List(Bottle::new().with(Value::vocab(tag)).with(f64_list(v)))
}

/// `([tag] [value])` (`addPoseOption`, `addModeOption`).
pub fn vocab_option(tag: &str, value: &str) -> Value {
    Value::List(
        Bottle::new()
            .with(Value::vocab(tag))
            .with(Value::vocab(value)),
    )
}

/// `([tok] <f64>)` (`addTokenOption`).
pub fn token_option(token: f64) -> Value {
    Value::List(
        Bottle::new()
            .with(Value::vocab(word::TOKEN))
            .with(Value::Float64(token)),
    )
}

/// The vector of option `tag`, if the bottle has one.
pub fn find_vector(b: &Bottle, tag: &str) -> Option<Vec<f64>> {
    numbers(b.find(tag)?)
}

/// The word of option `tag`.
pub fn find_word(b: &Bottle, tag: &str) -> Option<String> {
    let v = b.find(tag)?;
    match v {
        Value::Vocab32(w) => Some(w.as_string()),
        _ => v.as_str().map(str::to_string),
    }
}

/// The number of option `tag`.
pub fn find_number(b: &Bottle, tag: &str) -> Option<f64> {
    b.find(tag)?.as_f64()
}

/// A boolean as the protocol words it: `[true]` / `[fals]`.
pub fn truth(on: bool) -> Value {
    Value::vocab(if on { word::TRUE } else { word::FALSE })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn options_are_found_by_key_in_any_order() {
        let b = Bottle::new()
            .with(token_option(3.5))
            .with(vocab_option(word::POSE, word::XYZ))
            .with(vector_option(word::XD, &[0.1, 0.2, 0.3]));
        assert_eq!(find_vector(&b, "xd"), Some(vec![0.1, 0.2, 0.3]));
        assert_eq!(find_word(&b, "pose").as_deref(), Some("xyz"));
        assert_eq!(find_number(&b, "tok"), Some(3.5));
        assert_eq!(find_vector(&b, "q"), None);
    }

    #[test]
    fn an_ack_is_a_specialised_vocab_list_on_the_wire() {
        // tag 265 (list of vocabs), one item, "ack"
        assert_eq!(
            ack().encode(),
            [9, 1, 0, 0, 1, 0, 0, 0, b'a', b'c', b'k', 0]
        );
        let typed = Bottle::from_text("get info");
        assert!(is_word(&typed, 0, word::GET) && is_word(&typed, 1, word::INFO));
    }
}
