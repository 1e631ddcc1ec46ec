//! A device's parameters, declared once: [`device_params!`] turns one declaration (name,
//! type, unit, default, required, description per parameter) into a typed struct, its
//! reader from the configuration and the table `--help` prints, as C++ YARP's
//! `yarpDeviceParamParserGenerator` turns a device's `.md` table into its `_ParamsParser`.
//!
//! [`Params`] is the typed access underneath, for what a declaration cannot say (a value
//! whose meaning depends on another, a list per joint).

use crate::error::{DevResult, DeviceError};
use std::fmt::Write as _;
use std::time::Duration;
use yarp_proto::{Bottle, Property, Value};

/// Typed access to a device's configuration, with errors naming parameter and device.
/// Keys may be `name` (top level) or `GROUP::name` (inside a `[GROUP]` section).
pub struct Params<'a> {
    pub device: &'a str,
    pub config: &'a Property,
}

impl<'a> Params<'a> {
    pub fn new(device: &'a str, config: &'a Property) -> Self {
        Params { device, config }
    }

    /// The raw value of `key` (`GROUP::name` looks inside the group, `A::B::name`
    /// inside group `B` of group `A`).
    pub fn find(&self, key: &str) -> Option<&'a Value> {
        match key.rsplit_once("::") {
            Some((groups, name)) => self.group(groups)?.find(name),
            None => self.config.find(key),
        }
    }

    /// The group `A::B` (a line whose values are lines), walked from the top.
    fn group(&self, path: &str) -> Option<&'a Bottle> {
        let mut names = path.split("::");
        let mut group = self.config.find_group(names.next()?)?;
        for name in names {
            group = group.find_group(name)?;
        }
        Some(group)
    }

    /// The error for parameter `key` holding `got` where `expected` was wanted.
    pub fn invalid(&self, key: &str, expected: &'static str, got: impl ToString) -> DeviceError {
        DeviceError::BadParam {
            device: self.device.to_string(),
            param: key.to_string(),
            expected,
            got: got.to_string(),
        }
    }

    pub fn missing(&self, key: &str) -> DeviceError {
        DeviceError::MissingParam {
            device: self.device.to_string(),
            param: key.to_string(),
        }
    }

    /// An integer parameter; `None` when absent, an error when of another type.
    pub fn int(&self, key: &str) -> DevResult<Option<i64>> {
        match self.find(key) {
            None => Ok(None),
            Some(v) if v.is_int() => Ok(v.as_i64()),
            Some(v) => Err(self.invalid(key, "an integer", v)),
        }
    }

    /// A float parameter (integers accepted).
    pub fn float(&self, key: &str) -> DevResult<Option<f64>> {
        match self.find(key) {
            None => Ok(None),
            Some(v) if v.is_int() || v.is_float() => Ok(v.as_f64()),
            Some(v) => Err(self.invalid(key, "a number", v)),
        }
    }

    /// A string parameter (vocabs accepted).
    pub fn string(&self, key: &str) -> DevResult<Option<String>> {
        match self.find(key) {
            None => Ok(None),
            Some(v) if v.is_string() || v.is_vocab() => Ok(Some(v.to_string_bare())),
            Some(v) => Err(self.invalid(key, "a string", v)),
        }
    }

    /// A boolean parameter as C++ `Value::asBool` reads it (`true`/`false`, a number,
    /// non-zero being true; the strings `"true"`, `"false"`, `"1"`, `"0"`); a key given
    /// without a value (`--constantValue`) counts as true.
    pub fn boolean(&self, key: &str) -> DevResult<Option<bool>> {
        let Some(v) = self.find(key) else {
            return Ok((!key.contains("::") && self.config.check(key)).then_some(true));
        };
        let b = match v.as_str() {
            Some("true" | "TRUE" | "True" | "1" | "on") => Some(true),
            Some("false" | "FALSE" | "False" | "0" | "off") => Some(false),
            Some(_) => None,
            None => v.as_bool(),
        };
        b.map(Some)
            .ok_or_else(|| self.invalid(key, "true or false", v))
    }

    /// A vector parameter: either a list value or the rest of the group line
    /// (`AxisName "a" "b"` in a section), each element checked with `f`.
    pub fn vector<T>(
        &self,
        key: &str,
        expected: &'static str,
        f: impl Fn(&Value) -> Option<T>,
    ) -> DevResult<Option<Vec<T>>> {
        let line = match key.rsplit_once("::") {
            Some((groups, name)) => self.group(groups).and_then(|g| g.find_group(name)),
            None => self.config.find_group(key),
        };
        let Some(line) = line else {
            return Ok(None);
        };
        flatten_line(line)
            .iter()
            .map(|v| f(v).ok_or_else(|| self.invalid(key, expected, v)))
            .collect::<DevResult<Vec<T>>>()
            .map(Some)
    }
}

/// `(key a b c)` or `(key (a b c))` -> `[a, b, c]`.
fn flatten_line(line: &Bottle) -> Vec<Value> {
    let rest: Vec<Value> = line.iter().skip(1).cloned().collect();
    if rest.len() == 1 {
        if let Some(l) = rest[0].as_list() {
            return l.iter().cloned().collect();
        }
    }
    rest
}

/// A type a declared parameter may have, with the name C++'s tables give it.
pub trait ParamType: Sized {
    /// The type as the C++ documentation names it (`string`, `double`, `int`, ...).
    const TYPE: &'static str;
    /// The value of `key`; `None` when absent, an error naming the parameter when it
    /// does not read as this type.
    fn read(p: &Params<'_>, key: &str) -> DevResult<Option<Self>>;
}

impl ParamType for String {
    const TYPE: &'static str = "string";
    fn read(p: &Params<'_>, key: &str) -> DevResult<Option<Self>> {
        p.string(key)
    }
}

impl ParamType for f64 {
    const TYPE: &'static str = "double";
    fn read(p: &Params<'_>, key: &str) -> DevResult<Option<Self>> {
        p.float(key)
    }
}

impl ParamType for bool {
    const TYPE: &'static str = "bool";
    fn read(p: &Params<'_>, key: &str) -> DevResult<Option<Self>> {
        p.boolean(key)
    }
}

/// Any value, for a parameter checked by hand.
impl ParamType for Value {
    const TYPE: &'static str = "value";
    fn read(p: &Params<'_>, key: &str) -> DevResult<Option<Self>> {
        Ok(p.find(key).cloned())
    }
}

/// Seconds, as C++ declares a period or timeout (`double`, unit `s`).
impl ParamType for Duration {
    const TYPE: &'static str = "double";
    fn read(p: &Params<'_>, key: &str) -> DevResult<Option<Self>> {
        match p.float(key)? {
            None => Ok(None),
            Some(s) => Duration::try_from_secs_f64(s)
                .map(Some)
                .map_err(|_| p.invalid(key, "a number of seconds, not negative", s)),
        }
    }
}

macro_rules! integer_params {
    ($($t:ty),*) => {$(
        impl ParamType for $t {
            const TYPE: &'static str = "int";
            fn read(p: &Params<'_>, key: &str) -> DevResult<Option<Self>> {
                match p.int(key)? {
                    None => Ok(None),
                    Some(i) => <$t>::try_from(i).map(Some).map_err(|_| {
                        p.invalid(key, concat!("an integer that fits ", stringify!($t)), i)
                    }),
                }
            }
        }
    )*};
}
integer_params!(i64, u64, i32, u32, u16, u8, usize);

impl ParamType for Vec<f64> {
    const TYPE: &'static str = "vector<double>";
    fn read(p: &Params<'_>, key: &str) -> DevResult<Option<Self>> {
        p.vector(key, "numbers", |v| {
            (v.is_int() || v.is_float()).then(|| v.as_f64()).flatten()
        })
    }
}

impl ParamType for Vec<i64> {
    const TYPE: &'static str = "vector<int>";
    fn read(p: &Params<'_>, key: &str) -> DevResult<Option<Self>> {
        p.vector(key, "integers", |v| {
            v.is_int().then(|| v.as_i64()).flatten()
        })
    }
}

impl ParamType for Vec<String> {
    const TYPE: &'static str = "vector<string>";
    fn read(p: &Params<'_>, key: &str) -> DevResult<Option<Self>> {
        p.vector(key, "strings", |v| {
            (v.is_string() || v.is_vocab()).then(|| v.to_string_bare())
        })
    }
}

/// A number C++ takes only when written as a float (`0.02`, not `1`): its parsers use
/// `isFloat64()` before reading.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FloatOnly(pub f64);

impl ParamType for FloatOnly {
    const TYPE: &'static str = "double";
    fn read(p: &Params<'_>, key: &str) -> DevResult<Option<Self>> {
        match p.find(key) {
            None => Ok(None),
            Some(v) if v.is_float() => Ok(v.as_f64().map(FloatOnly)),
            Some(v) => Err(p.invalid(key, "a float number such as 0.02 (C++ rejects integers)", v)),
        }
    }
}

impl IntoDefault<FloatOnly> for f64 {
    fn into_default(self) -> FloatOnly {
        FloatOnly(self)
    }
}

/// A [`FloatOnly`] duration in seconds greater than zero.
pub fn positive_float(x: &FloatOnly) -> Result<(), &'static str> {
    positive(&x.0)
}

/// How a declared default becomes the parameter's value: the value itself, a `&str` for
/// a `String`, seconds for a `Duration`.
pub trait IntoDefault<T> {
    fn into_default(self) -> T;
}

impl<T> IntoDefault<T> for T {
    fn into_default(self) -> T {
        self
    }
}

impl IntoDefault<String> for &str {
    fn into_default(self) -> String {
        self.to_string()
    }
}

impl<T: Clone, const N: usize> IntoDefault<Vec<T>> for [T; N] {
    fn into_default(self) -> Vec<T> {
        self.to_vec()
    }
}

impl IntoDefault<Duration> for f64 {
    fn into_default(self) -> Duration {
        Duration::from_secs_f64(self)
    }
}

/// One declared parameter, as a row of C++'s parameter table.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ParamSpec {
    /// The key, `GROUP::name` inside a group.
    pub name: &'static str,
    pub ty: &'static str,
    /// `-` when the value has no unit.
    pub unit: &'static str,
    /// The default as declared; `None` for a required or an optional parameter.
    pub default: Option<&'static str>,
    pub required: bool,
    pub description: &'static str,
    /// The values accepted, when not every value of the type is (`in 1..=1024`).
    pub range: Option<&'static str>,
}

/// `found`, unless it lies outside `lo..=hi` (declared `; in lo..=hi`).
pub fn check_range<T: PartialOrd + std::fmt::Debug, B: IntoDefault<T>>(
    p: &Params<'_>,
    key: &str,
    found: Option<T>,
    lo: B,
    hi: B,
    expected: &'static str,
) -> DevResult<Option<T>> {
    match found {
        Some(v) if !(lo.into_default()..=hi.into_default()).contains(&v) => {
            Err(p.invalid(key, expected, format!("{v:?}")))
        }
        found => Ok(found),
    }
}

/// `found`, unless `check` refuses it (declared `; check f`; `f` says what was expected).
pub fn check_with<T: std::fmt::Debug>(
    p: &Params<'_>,
    key: &str,
    found: Option<T>,
    check: impl Fn(&T) -> Result<(), &'static str>,
) -> DevResult<Option<T>> {
    match found {
        Some(v) => match check(&v) {
            Ok(()) => Ok(Some(v)),
            Err(expected) => Err(p.invalid(key, expected, format!("{v:?}").trim_matches('"'))),
        },
        None => Ok(None),
    }
}

/// A port name or prefix, as the wrappers need it: `/...`.
pub fn port_name(name: &str) -> Result<(), &'static str> {
    match name.starts_with('/') {
        true => Ok(()),
        false => Err("a port name starting with '/'"),
    }
}

/// A duration in seconds greater than zero (a period, a timeout).
pub fn positive(x: &f64) -> Result<(), &'static str> {
    match *x > 0.0 && x.is_finite() {
        true => Ok(()),
        false => Err("a number of seconds greater than 0"),
    }
}

/// `found`, unless it is below `min` (declared `; min m`).
pub fn check_min<T: PartialOrd + std::fmt::Debug, B: IntoDefault<T>>(
    p: &Params<'_>,
    key: &str,
    found: Option<T>,
    min: B,
    expected: &'static str,
) -> DevResult<Option<T>> {
    match found {
        Some(v) if v.partial_cmp(&min.into_default()).is_none_or(|o| o.is_lt()) => {
            Err(p.invalid(key, expected, format!("{v:?}")))
        }
        found => Ok(found),
    }
}

impl ParamSpec {
    /// The group part of the key (`""` at the top level) and the name in it.
    pub fn group_and_name(&self) -> (&'static str, &'static str) {
        match self.name.rsplit_once("::") {
            Some((g, n)) => (g, n),
            None => ("", self.name),
        }
    }
}

/// A declared default as the user would type it: no parentheses, no quotes.
fn default_text(declared: &'static str) -> &'static str {
    let d = declared
        .strip_prefix('(')
        .and_then(|d| d.strip_suffix(')'))
        .unwrap_or(declared);
    d.trim_matches('"')
}

/// What `--help` prints for `device`: C++'s header, the parameters as the table of the
/// device's C++ documentation, and the two example invocations C++ prints.
pub fn documentation(device: &str, params: &[ParamSpec]) -> String {
    let mut doc = String::new();
    let rule = "=============================================";
    let _ = writeln!(doc, "\n{rule}\nThis is the help for device: {device}\n");
    if params.is_empty() {
        let _ = writeln!(doc, "This device declares no parameters.\n{rule}");
        return doc;
    }
    let _ = writeln!(
        doc,
        "This is the list of the parameters accepted by the device:"
    );
    let head = [
        "Group",
        "Parameter name",
        "Type",
        "Units",
        "Default Value",
        "Required",
        "Description",
        "Notes",
    ];
    let rows: Vec<[String; 8]> = params
        .iter()
        .map(|p| {
            let (group, name) = p.group_and_name();
            [
                if group.is_empty() { "-" } else { group }.to_string(),
                name.to_string(),
                p.ty.to_string(),
                p.unit.to_string(),
                p.default.map(default_text).unwrap_or("-").to_string(),
                if p.required { "Yes" } else { "No" }.to_string(),
                p.description.to_string(),
                p.range.unwrap_or("").to_string(),
            ]
        })
        .collect();
    let mut widths = head.map(str::len);
    for row in &rows {
        for (w, cell) in widths.iter_mut().zip(row) {
            *w = (*w).max(cell.chars().count());
        }
    }
    let line = |cells: &[&str]| {
        let mut s = String::from("|");
        for (cell, w) in cells.iter().zip(widths) {
            let _ = write!(s, " {cell:<w$} |");
        }
        s
    };
    let _ = writeln!(doc, "{}", line(&head));
    let dashes = widths.map(|w| "-".repeat(w));
    let _ = writeln!(doc, "{}", line(&dashes.each_ref().map(String::as_str)));
    for row in &rows {
        let _ = writeln!(doc, "{}", line(&row.each_ref().map(String::as_str)));
    }
    let example = |all: bool| {
        let mut s = format!(" yarpdev --device {device}");
        for p in params.iter().filter(|p| all || p.required) {
            let value = match (p.required, p.default) {
                (true, _) => "<mandatory_value>",
                (false, Some(d)) => default_text(d),
                (false, None) => "<optional_value>",
            };
            let _ = write!(s, " --{} {value}", p.name);
        }
        s
    };
    let _ = writeln!(
        doc,
        "\nHere are some examples of invocation command with yarpdev, with all params:\n{}",
        example(true)
    );
    let _ = writeln!(doc, "Using only mandatory params:\n{}", example(false));
    let _ = writeln!(doc, "{rule}");
    doc
}

/// `values` when there is one per joint (`joints` of them), else the error naming `key`
/// (a per-joint line of a robot's file: `GROUP::key v0 v1 ...`).
pub fn per_joint<T: std::fmt::Display>(
    device: &str,
    key: &str,
    values: Vec<T>,
    joints: usize,
) -> DevResult<Vec<T>> {
    if values.len() == joints {
        return Ok(values);
    }
    let got: Vec<String> = values.iter().map(T::to_string).collect();
    Err(DeviceError::BadParam {
        device: device.to_string(),
        param: key.to_string(),
        expected: "one number per joint",
        got: got.join(" "),
    })
}

/// Prints `device`'s table when `config` has `help`, as C++'s generated parsers do.
pub fn help_if_asked(device: &str, config: &Property, params: &[ParamSpec]) {
    if config.check("help") {
        println!("{}", documentation(device, params));
    }
}

/// Declares a device's parameters once; generates the struct, `read` (which, as C++'s
/// generated parsers, first prints the table when the configuration has `help`) and the
/// table itself (`PARAMS`, [`documentation`]).
///
/// Each parameter is `description`, then optionally its key when it is not the field's
/// name (`"GROUP::name"` for one inside a group), the field and its type, and after `=`
/// one of `required`, `optional` (the field is an `Option`) or a default (one token:
/// parenthesize an expression), then optionally `; "unit"`:
///
/// ```
/// yarp_devices::device_params! {
///     /// What `fakeThing` reads.
///     pub struct FakeThingParams for "fakeThing" {
///         /// Prefix of the ports the device opens.
///         name: String = required,
///         /// How often the state is published.
///         "period" period: std::time::Duration = 0.01; "s",
///         /// Joints of the simulated part.
///         "GENERAL::Joints" joints: usize = 4,
///         /// A label shown in the logs.
///         label: String = optional,
///     }
/// }
/// let config = yarp_proto::Property::from_text("(name /thing) (GENERAL (Joints 6))");
/// let p = FakeThingParams::read(&config).unwrap();
/// assert_eq!((p.name.as_str(), p.joints, p.label), ("/thing", 6, None));
/// assert_eq!(FakeThingParams::PARAMS[1].unit, "s");
/// ```
#[macro_export]
macro_rules! device_params {
    (
        $(#[$meta:meta])*
        $vis:vis struct $name:ident for $device:literal {
            $(
                $(#[doc = $doc:literal])+
                $($key:literal)? $field:ident : $ty:ty = $default:tt $(; $unit:literal)?
                    $(; in $lo:literal ..= $hi:literal)? $(; min $min:literal)?
                    $(; check $check:path)?
            ),* $(,)?
        }
    ) => {
        $(#[$meta])*
        #[derive(Debug, Clone, PartialEq)]
        $vis struct $name {
            $(
                $(#[doc = $doc])+
                pub $field: $crate::device_params!(@type $default $ty),
            )*
        }

        impl $name {
            /// The device these parameters are of.
            pub const DEVICE: &'static str = $device;

            /// The declared parameters, in declaration order.
            pub const PARAMS: &'static [$crate::params::ParamSpec] = &[$(
                $crate::params::ParamSpec {
                    name: $crate::device_params!(@key $field $($key)?),
                    ty: <$ty as $crate::params::ParamType>::TYPE,
                    unit: $crate::device_params!(@unit $($unit)?),
                    default: $crate::device_params!(@default_text $default),
                    required: $crate::device_params!(@required $default),
                    description: $crate::device_params!(@join $($doc)+),
                    range: $crate::device_params!(@range $($lo $hi)? $($min)?),
                },
            )*];

            /// Reads the parameters from `config`; an error names the first one missing
            /// or of the wrong type. With `help` in `config`, prints the table first.
            pub fn read(config: &yarp_proto::Property) -> $crate::error::DevResult<Self> {
                Self::read_as(Self::DEVICE, config)
            }

            /// As [`Self::read`], for a device that goes by another name too.
            pub fn read_as(
                device: &str,
                config: &yarp_proto::Property,
            ) -> $crate::error::DevResult<Self> {
                $crate::params::help_if_asked(device, config, Self::PARAMS);
                Self::parse(device, config)
            }

            /// As [`Self::read_as`] without printing the table: for a part of a device's
            /// parameters (the device prints its whole table with [`help_if_asked`]).
            ///
            /// [`help_if_asked`]: $crate::params::help_if_asked
            pub fn parse(
                device: &str,
                config: &yarp_proto::Property,
            ) -> $crate::error::DevResult<Self> {
                let p = $crate::params::Params::new(device, config);
                Ok(Self {$(
                    $field: {
                        let key = $crate::device_params!(@key $field $($key)?);
                        let found = <$ty as $crate::params::ParamType>::read(&p, key)?;
                        $(let found = $crate::params::check_range(
                            &p, key, found, $lo, $hi, concat!("a value in ", stringify!($lo), "..=", stringify!($hi)),
                        )?;)?
                        $(let found = $crate::params::check_min(
                            &p, key, found, $min, concat!("a value of at least ", stringify!($min)),
                        )?;)?
                        $(let found = $crate::params::check_with(&p, key, found, |v| $check(v))?;)?
                        $crate::device_params!(@value p key found $default $ty)
                    },
                )*})
            }
        }
    };
    (@type optional $ty:ty) => { Option<$ty> };
    (@type $default:tt $ty:ty) => { $ty };
    (@key $field:ident) => { stringify!($field) };
    (@key $field:ident $key:literal) => { $key };
    (@unit) => { "-" };
    (@unit $unit:literal) => { $unit };
    (@default_text required) => { None };
    (@default_text optional) => { None };
    (@default_text $default:tt) => { Some(stringify!($default)) };
    (@range) => { None };
    (@range $lo:literal $hi:literal) => { Some(concat!("in ", stringify!($lo), "..=", stringify!($hi))) };
    (@range $min:literal) => { Some(concat!("at least ", stringify!($min))) };
    (@required required) => { true };
    (@required $default:tt) => { false };
    (@join $($doc:literal)+) => { concat!($($doc),+).trim_ascii() };
    (@value $p:ident $key:ident $found:ident required $ty:ty) => {
        $found.ok_or_else(|| $p.missing($key))?
    };
    (@value $p:ident $key:ident $found:ident optional $ty:ty) => { $found };
    (@value $p:ident $key:ident $found:ident $default:tt $ty:ty) => {
        match $found {
            Some(v) => v,
            None => $crate::params::IntoDefault::<$ty>::into_default($default),
        }
    };
}

/// The table of a device whose parameters are read by hand (the `embObj*` devices, whose
/// files name groups at run time): the rows of [`device_params!`] without fields, for
/// `--help` and [`crate::DeviceDriver::parameters`]. A test keeps such a table equal to
/// what the device looks up.
///
/// ```
/// yarp_devices::param_table! {
///     /// What `fakeBoard` reads besides its network groups.
///     pub const FAKE_BOARD = [
///         /// Joints of the board
///         "GENERAL::Joints": usize = required,
///         /// Encoder units per degree, one per joint
///         "GENERAL::Encoder": Vec<f64> = optional; "units/deg",
///     ];
/// }
/// assert_eq!(FAKE_BOARD[1].ty, "vector<double>");
/// ```
#[macro_export]
macro_rules! param_table {
    (
        $(#[$meta:meta])*
        $vis:vis const $name:ident = [
            $(
                $(#[doc = $doc:literal])+
                $key:literal : $ty:ty = $default:tt $(; $unit:literal)?
            ),* $(,)?
        ];
    ) => {
        $(#[$meta])*
        $vis const $name: &[$crate::params::ParamSpec] = &[$(
            $crate::params::ParamSpec {
                name: $key,
                ty: <$ty as $crate::params::ParamType>::TYPE,
                unit: $crate::device_params!(@unit $($unit)?),
                default: $crate::device_params!(@default_text $default),
                required: $crate::device_params!(@required $default),
                description: $crate::device_params!(@join $($doc)+),
                range: None,
            },
        )*];
    };
}

#[cfg(test)]
mod tests {
    use super::*;

    crate::device_params! {
        /// A device of the tests.
        struct Example for "example" {
            /// Where it is.
            name: String = required,
            /// How often
            /// it runs.
            "period" period: Duration = 0.01; "s",
            /// Joints.
            "GENERAL::Joints" joints: u16 = 4; in 1..=1024,
            /// Names.
            "GENERAL::AxisName" axis_names: Vec<String> = optional,
            /// Offset.
            offset: f64 = (-1.5),
            /// Enabled.
            enabled: bool = true,
        }
    }

    #[test]
    fn reads_declared_types_defaults_and_groups() {
        let nested = Property::from_text("(A (B (c 7) (v 1 2)))");
        let p = Params::new("x", &nested);
        assert_eq!(p.int("A::B::c").unwrap(), Some(7));
        assert_eq!(
            p.vector("A::B::v", "ints", Value::as_i64).unwrap(),
            Some(vec![1, 2])
        );
        assert_eq!(p.int("A::C::c").unwrap(), None);
        let c =
            Property::from_text("(name /e) (GENERAL (Joints 2) (AxisName a b)) (enabled false)");
        let e = Example::read(&c).unwrap();
        assert_eq!(e.name, "/e");
        assert_eq!(e.period, Duration::from_millis(10));
        assert_eq!(e.joints, 2);
        assert_eq!(
            e.axis_names.as_deref(),
            Some(&["a".to_string(), "b".to_string()][..])
        );
        assert_eq!(e.offset, -1.5);
        assert!(!e.enabled);
        let err = |t: &str| {
            Example::read(&Property::from_text(t))
                .unwrap_err()
                .to_string()
        };
        assert!(
            err("(period 1)").contains("`name`"),
            "{}",
            err("(period 1)")
        );
        assert!(err("(name /e) (GENERAL (Joints -1))").contains("`GENERAL::Joints`"));
        assert!(err("(name /e) (period fast)").contains("`period`"));
        assert!(err("(name /e) (enabled maybe)").contains("`enabled`"));
        assert!(err("(name /e) (GENERAL (Joints 1025))").contains("1..=1024"));
        assert!(err("(name /e) (period -1)").contains("`period`"));
    }

    #[test]
    fn the_table_has_every_parameter_and_cpp_examples() {
        let doc = documentation("example", Example::PARAMS);
        assert!(
            doc.contains("This is the help for device: example"),
            "{doc}"
        );
        let row = doc.lines().find(|l| l.contains(" period ")).unwrap();
        let cells: Vec<&str> = row.split('|').map(str::trim).collect();
        assert_eq!(
            cells,
            [
                "",
                "-",
                "period",
                "double",
                "s",
                "0.01",
                "No",
                "How often it runs.",
                "",
                ""
            ]
        );
        let joints = doc.lines().find(|l| l.contains(" Joints ")).unwrap();
        assert!(joints.starts_with("| GENERAL "), "{joints}");
        assert!(
            doc.contains(" yarpdev --device example --name <mandatory_value>\n"),
            "{doc}"
        );
        assert!(doc.contains("--offset -1.5"), "{doc}");
        assert!(joints.contains("| in 1..=1024 |"), "{joints}");
        // every row is as wide as the header
        let widths: Vec<usize> = doc
            .lines()
            .filter(|l| l.starts_with('|'))
            .map(|l| l.chars().count())
            .collect();
        assert!(widths.windows(2).all(|w| w[0] == w[1]), "{doc}");
    }
}
