//! YARP 3.12's encoding of the control-board protocol: vocab Bottles (C++
//! `RPCMessagesParser` and `RemoteControlBoard`). A method is its head of vocabs
//! (`[set] [pos]`) followed by its arguments; its reply is shaped by its [`Style`].
//! Every value is encoded by one [`Wire3`] impl, so the methods themselves
//! (`methods.rs`) hold no Bottle code.

use super::methods::Method;
use super::rpc::RpcStamp;
use crate::error::DevResult;
use crate::interfaces::Pid;
use crate::vocabs::*;
use yarp_proto::{Bottle, Value, Vocab32};

/// How a method's reply looks on the wire.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Style {
    /// `[ok]` or `[fail]`.
    Set,
    /// `[ok]` for true, `[fail]` for false or failure (`[cald] j`).
    Check,
    /// `[is] <cmd[1]> value [tsta] count time [ok]`.
    Get,
    /// `[is] <cmd[1]> value [ok]`: no timestamp (PID, current, PWM, remote calibrator).
    GetBare,
    /// `[is] <joint | mode vocab> value [tsta] count time [ok]` (`IControlMode`).
    GetMode,
    /// `value [tsta] count time [ok]`: no `[is]`, no echo (`IInteractionMode`).
    GetPlain,
    /// `<cmd[1]> value [ok]` (`[get] [prot]`).
    Echo,
    /// `[is] value [ok]`: no echo, no timestamp (`IJointFault`).
    Is,
}

impl Style {
    /// Elements before the value in a reply.
    fn value_at(self) -> usize {
        match self {
            Style::Set | Style::Check | Style::GetPlain => 0,
            Style::Echo | Style::Is => 1,
            Style::Get | Style::GetBare | Style::GetMode => 2,
        }
    }
}

/// A method's 3.12 form: its head of vocabs and its reply's style.
#[derive(Debug, Clone, Copy)]
pub struct Form {
    pub head: &'static [i32],
    pub style: Style,
}

/// A value as 3.12 puts it in a Bottle and takes it back.
pub trait Wire3: Sized {
    fn put(&self, b: &mut Bottle);
    fn take(c: &mut Cursor<'_>) -> Option<Self>;
}

/// The elements of a Bottle not read yet.
pub struct Cursor<'a> {
    items: std::slice::Iter<'a, Value>,
    /// Reading a request as C++'s server does: a missing or mistyped number is 0.
    lenient: bool,
}

impl<'a> Cursor<'a> {
    /// A request's arguments, read as C++'s server reads them.
    pub fn request(items: &'a [Value]) -> Self {
        Cursor {
            items: items.iter(),
            lenient: true,
        }
    }
    /// A reply's values, which must be there.
    pub fn reply(items: &'a [Value]) -> Self {
        Cursor {
            items: items.iter(),
            lenient: false,
        }
    }
    fn next(&mut self) -> Option<&'a Value> {
        self.items.next()
    }
    fn is_empty(&self) -> bool {
        self.items.len() == 0
    }
    /// A number: C++'s `asInt32`/`asFloat64` read what is missing or not a number as 0.
    fn number<T: Default>(&mut self, f: impl FnOnce(&Value) -> Option<T>) -> Option<T> {
        match self.next().and_then(f) {
            Some(x) => Some(x),
            None if self.lenient => Some(T::default()),
            None => None,
        }
    }
}

/// C++ `Value::asVocab32`: vocabs, strings (packed, as `get axes` typed at a prompt) and
/// integers.
pub fn vocab(v: Option<&Value>) -> i32 {
    match v {
        Some(Value::Vocab32(x)) => x.0,
        Some(Value::String(s)) => Vocab32::encode(s).0,
        Some(v) => v.as_i32().unwrap_or(0),
        None => 0,
    }
}

impl Wire3 for () {
    fn put(&self, _: &mut Bottle) {}
    fn take(_: &mut Cursor<'_>) -> Option<Self> {
        Some(())
    }
}

impl Wire3 for f64 {
    fn put(&self, b: &mut Bottle) {
        b.push(*self);
    }
    fn take(c: &mut Cursor<'_>) -> Option<Self> {
        c.number(Value::as_f64)
    }
}

impl Wire3 for i32 {
    fn put(&self, b: &mut Bottle) {
        b.push(*self);
    }
    fn take(c: &mut Cursor<'_>) -> Option<Self> {
        c.number(Value::as_i32)
    }
}

/// Joints, motors and counts travel as int32.
impl Wire3 for usize {
    fn put(&self, b: &mut Bottle) {
        b.push(i32::try_from(*self).unwrap_or(i32::MAX));
    }
    fn take(c: &mut Cursor<'_>) -> Option<Self> {
        usize::try_from(c.number(Value::as_i64)?).ok()
    }
}

/// Calibration types.
impl Wire3 for u32 {
    fn put(&self, b: &mut Bottle) {
        b.push(i32::try_from(*self).unwrap_or(i32::MAX));
    }
    fn take(c: &mut Cursor<'_>) -> Option<Self> {
        u32::try_from(c.number(Value::as_i64)?).ok()
    }
}

/// Booleans are int32 0 or 1 (not YARP's `[ok]`/`[fail]` vocabs).
impl Wire3 for bool {
    fn put(&self, b: &mut Bottle) {
        b.push(i32::from(*self));
    }
    fn take(c: &mut Cursor<'_>) -> Option<Self> {
        c.number(|v| v.as_f64().map(|x| x != 0.0).or_else(|| v.as_bool()))
    }
}

impl Wire3 for String {
    fn put(&self, b: &mut Bottle) {
        b.push(self.as_str());
    }
    fn take(c: &mut Cursor<'_>) -> Option<Self> {
        c.next()?.as_str().map(str::to_string)
    }
}

impl Wire3 for Vocab32 {
    fn put(&self, b: &mut Bottle) {
        b.push(*self);
    }
    fn take(c: &mut Cursor<'_>) -> Option<Self> {
        c.next().map(|v| Vocab32(vocab(Some(v))))
    }
}

/// A list, each item encoded as `T`.
impl<T: Wire3> Wire3 for Vec<T> {
    fn put(&self, b: &mut Bottle) {
        let list = b.add_list();
        for x in self {
            x.put(list);
        }
    }
    fn take(c: &mut Cursor<'_>) -> Option<Self> {
        // the list itself must be there (C++ checks it), not its items
        let list = c.next()?.as_list()?;
        let mut items = Cursor {
            items: list.items().iter(),
            lenient: c.lenient,
        };
        let mut out = Vec::with_capacity(list.len());
        while !items.is_empty() {
            out.push(T::take(&mut items)?);
        }
        Some(out)
    }
}

/// An argument C++'s client may leave out (`[park]` without its flag).
impl<T: Wire3> Wire3 for Option<T> {
    fn put(&self, b: &mut Bottle) {
        if let Some(x) = self {
            x.put(b);
        }
    }
    fn take(c: &mut Cursor<'_>) -> Option<Self> {
        if c.is_empty() {
            Some(None)
        } else {
            T::take(c).map(Some)
        }
    }
}

impl<A: Wire3, B: Wire3> Wire3 for (A, B) {
    fn put(&self, b: &mut Bottle) {
        self.0.put(b);
        self.1.put(b);
    }
    fn take(c: &mut Cursor<'_>) -> Option<Self> {
        Some((A::take(c)?, B::take(c)?))
    }
}

impl<A: Wire3, B: Wire3, C: Wire3> Wire3 for (A, B, C) {
    fn put(&self, b: &mut Bottle) {
        self.0.put(b);
        self.1.put(b);
        self.2.put(b);
    }
    fn take(c: &mut Cursor<'_>) -> Option<Self> {
        Some((A::take(c)?, B::take(c)?, C::take(c)?))
    }
}

/// A Bottle as one nested list.
impl Wire3 for Bottle {
    fn put(&self, b: &mut Bottle) {
        b.push(Value::List(self.clone()));
    }
    fn take(c: &mut Cursor<'_>) -> Option<Self> {
        c.next()?.as_list().cloned()
    }
}

/// A remote variable's value: 3.12 sends its elements flat after the key (C++
/// `cmd.append(val)`, read back as the command's tail), 4.0 the Bottle nested.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Flat(pub Bottle);

impl Wire3 for Flat {
    fn put(&self, b: &mut Bottle) {
        for v in self.0.iter() {
            b.push(v.clone());
        }
    }
    fn take(c: &mut Cursor<'_>) -> Option<Self> {
        let mut rest = Bottle::new();
        while let Some(v) = c.next() {
            rest.push(v.clone());
        }
        Some(Flat(rest))
    }
}

/// A PID's ten gains as one list.
impl Wire3 for Pid {
    fn put(&self, b: &mut Bottle) {
        self.to_array().to_vec().put(b);
    }
    fn take(c: &mut Cursor<'_>) -> Option<Self> {
        Vec::<f64>::take(c).map(|g| Pid::from_slice(&g))
    }
}

/// Values 3.12 sends as one list and 4.0 as `N` separate doubles (the impedance's).
#[derive(Debug, Clone, PartialEq)]
pub struct Listed<const N: usize>(pub Vec<f64>);

impl<const N: usize> Wire3 for Listed<N> {
    fn put(&self, b: &mut Bottle) {
        self.0.put(b);
    }
    fn take(c: &mut Cursor<'_>) -> Option<Self> {
        Vec::<f64>::take(c).map(Listed)
    }
}

/// A joint that 4.0 sends as an int16 (the PIDs' and the limits' calls); an int32 in 3.12.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct J16(pub usize);

impl Wire3 for J16 {
    fn put(&self, b: &mut Bottle) {
        self.0.put(b);
    }
    fn take(c: &mut Cursor<'_>) -> Option<Self> {
        usize::take(c).map(J16)
    }
}

/// A PID's type, as 3.12 names it (`[pos]`, `[vel]`, `[trq]`, `[cur]`); 4.0 numbers
/// them (`pos1`), see `v4.rs`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PidType(pub Vocab32);

impl PidType {
    /// 4.0's name: the first of each of 3.12's four types is numbered 1 (`pos1`).
    pub fn to_v4(self) -> Vocab32 {
        let name = self.0.as_string();
        match name.as_str() {
            "pos" | "vel" | "trq" | "cur" => Vocab32::new(&format!("{name}1")),
            _ => self.0,
        }
    }
    /// The type 4.0's name `v` stands for, in 3.12's names where 3.12 has it.
    pub fn from_v4(v: Vocab32) -> PidType {
        let name = v.as_string();
        PidType(match name.as_str() {
            "pos1" | "vel1" | "trq1" | "cur1" => Vocab32::new(&name[..3]),
            _ => v,
        })
    }
}

impl Wire3 for PidType {
    fn put(&self, b: &mut Bottle) {
        self.0.put(b);
    }
    fn take(c: &mut Cursor<'_>) -> Option<Self> {
        Vocab32::take(c).map(PidType)
    }
}

/// Whether a calibration is done: 3.12's `[ok]`/`[fail]`, 4.0's return value.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Done(pub bool);

impl Wire3 for Done {
    fn put(&self, b: &mut Bottle) {
        self.0.put(b);
    }
    fn take(c: &mut Cursor<'_>) -> Option<Self> {
        bool::take(c).map(Done)
    }
}

/// The joints of a group command: their count, then their list (`n (j1 j2 ...)`).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Group(pub Vec<usize>);

impl Wire3 for Group {
    fn put(&self, b: &mut Bottle) {
        self.0.len().put(b);
        self.0.put(b);
    }
    fn take(c: &mut Cursor<'_>) -> Option<Self> {
        let n = usize::take(c)?;
        let joints = Vec::<usize>::take(c)?;
        (joints.len() == n).then_some(Group(joints))
    }
}

impl std::ops::Deref for Group {
    type Target = [usize];
    fn deref(&self) -> &[usize] {
        &self.0
    }
}

/// The request Bottle of `m`.
pub fn request<M: Method>(m: &M) -> Bottle {
    let mut b = Bottle::new();
    for v in M::V3.head {
        b.push(Vocab32(*v));
    }
    m.put_args(&mut b);
    b
}

/// `m` from `cmd` when `cmd` starts with `M`'s head and its arguments decode.
pub fn decode<M: Method>(cmd: &Bottle) -> Option<M> {
    let head = M::V3.head;
    let items = cmd.items();
    if head.is_empty()
        || items.len() < head.len()
        || !head.iter().zip(items).all(|(h, v)| vocab(Some(v)) == *h)
    {
        return None;
    }
    M::take_args(&mut Cursor::request(&items[head.len()..]))
}

/// The reply to `cmd` after serving it: shaped by `M`'s style, `[fail]` on failure.
pub fn reply<M: Method>(cmd: &Bottle, result: DevResult<M::Reply>, stamp: &mut RpcStamp) -> Bottle {
    let mut b = Bottle::new();
    let value = match result {
        Ok(v) => v,
        Err(e) => {
            tracing::warn!("controlBoard rpc: `{cmd}` refused by the device: {e}: replying [fail]");
            b.push(Vocab32(FAILED));
            return b;
        }
    };
    let style = M::V3.style;
    match style {
        Style::Set => {}
        Style::Check => {
            // a true reply is `[ok]`: the value is put aside and read as an int
            let mut v = Bottle::new();
            value.put(&mut v);
            let ok = v.get(0).and_then(Value::as_i32) != Some(0);
            b.push(Vocab32(if ok { OK } else { FAILED }));
            return b;
        }
        Style::Get | Style::GetBare => {
            b.push(Vocab32(IS));
            b.push(cmd.get(1).cloned().unwrap_or(Value::Vocab32(Vocab32(0))));
        }
        Style::GetMode => {
            b.push(Vocab32(IS));
            match vocab(cmd.get(2)) {
                CM_CONTROL_MODE => b.push(cmd.get(3).and_then(Value::as_i32).unwrap_or(0)),
                v => b.push(Vocab32(v)),
            };
        }
        Style::GetPlain => {}
        Style::Is => {
            b.push(Vocab32(IS));
        }
        Style::Echo => {
            b.push(cmd.get(1).cloned().unwrap_or(Value::Vocab32(Vocab32(0))));
        }
    }
    value.put(&mut b);
    if matches!(style, Style::Get | Style::GetMode | Style::GetPlain) {
        let s = stamp.update();
        b.push(Vocab32(TIMESTAMP)).push(s.count).push(s.time);
    }
    b.push(Vocab32(OK));
    b
}

/// What a reply says, for a client.
#[derive(Debug, PartialEq)]
pub enum Answer<T> {
    Value(T),
    /// `[fail]`, `[nak]` or nothing: the server refused or did not understand.
    Refused,
    /// `[ok]` without the value asked: the server speaks another protocol.
    Malformed,
}

/// C++ `CHECK_FAIL`: a reply is a failure when it is empty or starts with `[fail]`
/// (`[nak]` too: the command was not understood).
pub fn reply_ok(reply: &Bottle) -> bool {
    match reply.get(0) {
        None => false,
        Some(Value::Vocab32(x)) => x.0 != FAILED && x.0 != NAK,
        Some(_) => true,
    }
}

/// The value of `M`'s reply.
pub fn answer<M: Method>(reply: &Bottle) -> Answer<M::Reply> {
    let ok = reply_ok(reply);
    if M::V3.style == Style::Check {
        let truth = [Value::from(i32::from(ok))];
        return M::Reply::take(&mut Cursor::reply(&truth)).map_or(Answer::Malformed, Answer::Value);
    }
    if !ok {
        return Answer::Refused;
    }
    let at = M::V3.style.value_at().min(reply.len());
    match M::Reply::take(&mut Cursor::reply(&reply.items()[at..])) {
        Some(v) => Answer::Value(v),
        None => Answer::Malformed,
    }
}
