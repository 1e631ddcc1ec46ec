//! `Property`: YARP's key -> group dictionary (C++ `yarp::os::Property`, a `Searchable`),
//! with the readers C++ offers for it: Bottle text, `.ini` configuration files, command
//! lines and URL queries.
//!
//! Every key holds a *group*, a Bottle that starts with the key: `put("x", 1)` stores
//! `(x 1)`, a config line `size 10 20` stores `(size 10 20)`, and an `.ini` section stores
//! `(name (k v) (k2 v2))`, which is itself searchable with [`Bottle::find`]. Keys are kept
//! sorted by their bytes, as C++'s `std::map` keeps them, so printing matches C++.
//!
//! The readers follow C++ YARP 3.12 (`Property.cpp`) quirk for quirk, because a config file
//! must mean the same thing to a Rust module as to the C++ one next to it. Where C++ would
//! silently lose data (a quote never closed, an include that does not exist, an include
//! cycle) these readers return a [`ParseError`] instead.
//!
//! ```
//! use yarp_proto::Property;
//! let p = Property::from_config_text("robot icub\n[arm]\ngains (1 2 3)\n").unwrap();
//! assert_eq!(p.find("robot").and_then(|v| v.as_str()), Some("icub"));
//! let gains = p.find_group("arm").and_then(|arm| arm.find("gains"));
//! assert_eq!(gains.map(|g| g.to_string()), Some("(1 2 3)".to_string()));
//! assert_eq!(p.to_string(), "(arm (gains (1 2 3))) (robot icub)");
//!
//! let args = Property::from_args(["--robot", "icubSim", "--verbose"]);
//! assert!(args.check("verbose"));
//! ```

use crate::error::ParseError;
use crate::value::{Bottle, Value};
use std::collections::BTreeMap;
use std::ffi::OsString;
use std::fmt;
use std::path::{Path, PathBuf};

/// Includes nested deeper than this are refused (C++ has no limit and would recurse until
/// the stack overflows).
pub const MAX_INCLUDE_DEPTH: usize = 32;

/// At most this many files are read for one configuration load, so that a few files
/// including each other many times cannot multiply into an endless load.
pub const MAX_FILE_LOADS: usize = 4096;

/// A YARP Property: key -> group, where each group is a Bottle starting with its key.
#[derive(Clone, Default, PartialEq)]
pub struct Property {
    data: BTreeMap<Vec<u8>, Bottle>,
}

impl Property {
    pub fn new() -> Property {
        Property::default()
    }

    // ---- Searchable -------------------------------------------------------------------

    /// The first value after the key (C++ `find`). `None` when the key is absent or its
    /// group holds no value (a bare `--flag` or a config line with only the key).
    pub fn find(&self, key: impl AsRef<[u8]>) -> Option<&Value> {
        self.data.get(key.as_ref()).and_then(|g| g.get(1))
    }

    /// The whole group, key first (C++ `findGroup`): `(size 10 20)`, or for an `.ini`
    /// section `(name (k v) ...)`, which answers [`Bottle::find`] for its own keys.
    pub fn find_group(&self, key: impl AsRef<[u8]>) -> Option<&Bottle> {
        self.data.get(key.as_ref())
    }

    /// Whether the key is present, even without a value (C++ `check(key)`).
    pub fn check(&self, key: impl AsRef<[u8]>) -> bool {
        self.data.contains_key(key.as_ref())
    }

    /// `find(key)` or `default` when there is no value (C++ `check(key, fallback)`).
    pub fn find_or(&self, key: impl AsRef<[u8]>, default: impl Into<Value>) -> Value {
        self.find(key).cloned().unwrap_or_else(|| default.into())
    }

    /// Same as [`find_or`](Self::find_or), under the C++ name `check(key, fallback)`.
    pub fn check_or(&self, key: impl AsRef<[u8]>, default: impl Into<Value>) -> Value {
        self.find_or(key, default)
    }

    // ---- editing -----------------------------------------------------------------------

    /// Stores `(key value)`, replacing any previous group (C++ `put`).
    pub fn put(&mut self, key: impl AsRef<[u8]>, value: impl Into<Value>) {
        let key = key.as_ref().to_vec();
        let mut group = Bottle::with_capacity(2);
        group.push(Value::String(key.clone()));
        group.push(value.into());
        self.data.insert(key, group);
    }

    /// Stores `(key (k v) ...)` built from another Property, so that
    /// `find_group(key).find(k)` works (C++ `addGroup`, filled in advance).
    pub fn put_group(&mut self, key: impl AsRef<[u8]>, group: &Property) {
        let key = key.as_ref().to_vec();
        let mut bot = Bottle::with_capacity(group.len() + 1);
        bot.push(Value::String(key.clone()));
        bot.extend(group.data.values().cloned().map(Value::List));
        self.data.insert(key, bot);
    }

    /// Removes a key (C++ `unput`), returning its group.
    pub fn unput(&mut self, key: impl AsRef<[u8]>) -> Option<Bottle> {
        self.data.remove(key.as_ref())
    }

    pub fn clear(&mut self) {
        self.data.clear()
    }

    pub fn len(&self) -> usize {
        self.data.len()
    }

    pub fn is_empty(&self) -> bool {
        self.data.is_empty()
    }

    /// Keys in C++ order (bytewise sorted). Keys are bytes because YARP strings are.
    pub fn keys(&self) -> impl Iterator<Item = &[u8]> + '_ {
        self.data.keys().map(|k| k.as_slice())
    }

    /// `(key, group)` pairs in key order.
    pub fn iter(&self) -> impl Iterator<Item = (&[u8], &Bottle)> + '_ {
        self.data.iter().map(|(k, g)| (k.as_slice(), g))
    }

    /// Stores a group under `key` as is; the C++ `putBottle` every reader goes through.
    fn put_bottle(&mut self, key: Vec<u8>, group: Bottle) {
        self.data.insert(key, group);
    }

    /// C++ `putBottleCompat`: `(key = a b)` is stored as `(key a b)`.
    fn put_bottle_compat(&mut self, key: Vec<u8>, group: Bottle) {
        if is_equals_sign(group.get(1)) {
            let mut fixed = Bottle::with_capacity(group.len().saturating_sub(1));
            fixed.extend(group.iter().take(1).cloned());
            fixed.extend(group.iter().skip(2).cloned());
            self.put_bottle(key, fixed);
        } else {
            self.put_bottle(key, group);
        }
    }

    // ---- Bottle text -------------------------------------------------------------------

    /// Reads `(key v...) (key2 v...)` text (C++ `fromString`). Elements that are not lists
    /// are ignored and a repeated key keeps its last group, as in C++.
    pub fn from_text(text: impl AsRef<[u8]>) -> Property {
        let mut p = Property::new();
        p.merge_text(text);
        p
    }

    /// [`from_text`](Self::from_text) into an existing Property (C++ `fromString(.., false)`).
    pub fn merge_text(&mut self, text: impl AsRef<[u8]>) {
        self.merge_bottle(&Bottle::from_text(text));
    }

    /// Reads a Bottle of `(key v...)` groups (C++ `fromBottle`, used by `fromString`).
    pub fn from_bottle(bottle: &Bottle) -> Property {
        let mut p = Property::new();
        p.merge_bottle(bottle);
        p
    }

    /// [`from_bottle`](Self::from_bottle) into an existing Property.
    pub fn merge_bottle(&mut self, bottle: &Bottle) {
        for v in bottle {
            if let Value::List(group) = v {
                self.put_bottle(key_text(group.get(0)), group.clone());
            }
        }
    }

    /// All groups as one Bottle, in key order: what C++ `toString` prints and what a
    /// Property sends on the wire.
    pub fn to_bottle(&self) -> Bottle {
        self.data.values().cloned().map(Value::List).collect()
    }

    /// Text as C++ `Property::toString`: `(a 1) (b 2)`, keys sorted.
    pub fn to_text(&self) -> Vec<u8> {
        self.to_bottle().to_text()
    }

    // ---- command line ------------------------------------------------------------------

    /// Reads command-line arguments, all of them options (no program name first):
    /// `--key v1 v2` gives `(key v1 v2)`, a bare `--flag` gives `(flag)` (`check` true,
    /// `find` None), `--a::b 1` gives the nested `(a (b 1))`. Pass
    /// `std::env::args().skip(1)`, or use [`from_command`](Self::from_command).
    pub fn from_args<I>(args: I) -> Property
    where
        I: IntoIterator,
        I::Item: AsRef<[u8]>,
    {
        let mut p = Property::new();
        p.merge_args(args);
        p
    }

    /// C++ `fromCommand(argc, argv, skipFirst)`: as [`from_args`](Self::from_args), first
    /// dropping the program name when `skip_first`.
    pub fn from_command<I>(args: I, skip_first: bool) -> Property
    where
        I: IntoIterator,
        I::Item: AsRef<[u8]>,
    {
        let mut p = Property::new();
        p.merge_args(args.into_iter().skip(usize::from(skip_first)));
        p
    }

    /// [`from_args`](Self::from_args) over an existing Property, replacing the keys given
    /// (C++ `fromCommand(.., wipe = false)`, how command lines override config files).
    pub fn merge_args<I>(&mut self, args: I)
    where
        I: IntoIterator,
        I::Item: AsRef<[u8]>,
    {
        from_command(self, args.into_iter().map(|a| a.as_ref().to_vec()));
    }

    /// Splits one command string the way C++ `fromArguments` does (double quotes group
    /// words and are removed; arguments are separated by spaces only) and reads it as a
    /// command line. The first word is an argument too, not a program name.
    pub fn from_arguments(command: impl AsRef<[u8]>) -> Property {
        let mut p = Property::new();
        from_command(&mut p, split_arguments(command.as_ref()).into_iter());
        p
    }

    /// Reads `key=value&key2=value2` (C++ `fromQuery`): anything up to a `?` is skipped,
    /// `+` is a space and `%XX` a byte; values are stored as strings, empty ones dropped.
    pub fn from_query(url: impl AsRef<[u8]>) -> Property {
        let mut p = Property::new();
        let mut buf: Vec<u8> = Vec::new();
        let mut key: Vec<u8> = Vec::new();
        let mut code: u32 = 0;
        let mut coding = 0;
        for &c in url.as_ref().iter().chain(std::iter::once(&b'&')) {
            match c {
                b'=' => key = std::mem::take(&mut buf),
                b'&' => {
                    let val = std::mem::take(&mut buf);
                    if !key.is_empty() && !val.is_empty() {
                        p.put(&key, Value::String(val));
                    }
                    key.clear();
                }
                b'?' => buf.clear(),
                _ => {
                    let mut ch = c;
                    if ch == b'+' {
                        ch = b' ';
                    } else if ch == b'%' {
                        coding = 2;
                    } else if coding != 0 {
                        let hex = (ch as char).to_digit(16).unwrap_or(0);
                        code = code.wrapping_mul(16).wrapping_add(hex);
                        coding -= 1;
                        if coding == 0 {
                            ch = code as u8;
                        }
                    }
                    if coding == 0 {
                        buf.push(ch);
                    }
                }
            }
        }
        p
    }

    // ---- configuration files -----------------------------------------------------------

    /// Reads `.ini` text (C++ `fromConfig`). See [`ConfigOptions`] for `$VAR` lookup and
    /// include search; includes are looked for relative to the current directory.
    pub fn from_config_text(text: impl AsRef<[u8]>) -> Result<Property, ParseError> {
        Property::from_config_text_with(text, &ConfigOptions::default())
    }

    /// [`from_config_text`](Self::from_config_text) with explicit options.
    pub fn from_config_text_with(
        text: impl AsRef<[u8]>,
        options: &ConfigOptions,
    ) -> Result<Property, ParseError> {
        let mut p = Property::new();
        p.merge_config_text_with(text, options)?;
        Ok(p)
    }

    /// Reads `.ini` text over an existing Property (C++ `fromConfig(.., wipe = false)`).
    /// On error the Property keeps what was read before the faulty line.
    pub fn merge_config_text_with(
        &mut self,
        text: impl AsRef<[u8]>,
        options: &ConfigOptions,
    ) -> Result<(), ParseError> {
        let mut loader = Loader::new(options);
        loader.parse_config(self, text.as_ref(), &options.vars)
    }

    /// Reads an `.ini` file, or every `*.ini` file of a directory in name order (C++
    /// `fromConfigFile`). Includes are looked for as written, then along `CONFIG_PATH`,
    /// which gains the directory of each file read. A file that cannot be read is
    /// reported as [`ParseError::Include`] with line 0.
    pub fn from_config_file(path: impl AsRef<Path>) -> Result<Property, ParseError> {
        Property::from_config_file_with(path, &ConfigOptions::default())
    }

    /// [`from_config_file`](Self::from_config_file) with explicit options.
    pub fn from_config_file_with(
        path: impl AsRef<Path>,
        options: &ConfigOptions,
    ) -> Result<Property, ParseError> {
        let mut p = Property::new();
        p.merge_config_file_with(path, options)?;
        Ok(p)
    }

    /// Reads an `.ini` file over an existing Property (C++ `fromConfigFile(.., false)`).
    pub fn merge_config_file_with(
        &mut self,
        path: impl AsRef<Path>,
        options: &ConfigOptions,
    ) -> Result<(), ParseError> {
        let mut loader = Loader::new(options);
        let fname = path_to_bytes(path.as_ref());
        loader
            .load_file(self, &fname, &options.vars)
            .map_err(|e| e.into_parse_error(0, &fname))
    }

    /// C++ `fromConfigDir(dir, section)`: every `*.ini` file of `dir` becomes a group
    /// named by its path, and `section` lists those names. With an empty `section` this
    /// is [`from_config_file`](Self::from_config_file) on the directory.
    pub fn from_config_dir(dir: impl AsRef<Path>, section: &str) -> Result<Property, ParseError> {
        let options = ConfigOptions::default();
        if section.is_empty() {
            return Property::from_config_file_with(dir, &options);
        }
        let dirname = path_to_bytes(dir.as_ref());
        let mut text = Vec::new();
        for name in ini_files(dir.as_ref()).map_err(|reason| ParseError::Include {
            line: 0,
            path: lossy(&dirname),
            reason,
        })? {
            let fname = dir_entry_path(&dirname, &name);
            // C++ writes `[include section "file" "file"]` for each file.
            text.extend_from_slice(b"[include ");
            text.extend_from_slice(section.as_bytes());
            for _ in 0..2 {
                text.extend_from_slice(b" \"");
                text.extend_from_slice(&fname);
                text.push(b'"');
            }
            text.extend_from_slice(b"]\n");
        }
        let mut p = Property::new();
        Loader::new(&options).parse_config(&mut p, &text, &Property::new())?;
        Ok(p)
    }
}

impl fmt::Display for Property {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&String::from_utf8_lossy(&self.to_text()))
    }
}

impl fmt::Debug for Property {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "Property({self})")
    }
}

/// Like C++'s `Property{{"one", Value(1)}, ...}`: each pair is `put`.
impl<K: AsRef<[u8]>, V: Into<Value>> FromIterator<(K, V)> for Property {
    fn from_iter<I: IntoIterator<Item = (K, V)>>(iter: I) -> Self {
        let mut p = Property::new();
        for (k, v) in iter {
            p.put(k, v);
        }
        p
    }
}

impl From<&Bottle> for Property {
    fn from(b: &Bottle) -> Self {
        Property::from_bottle(b)
    }
}

/// A Property inside a Bottle travels as a dictionary of its groups.
impl From<Property> for Value {
    fn from(p: Property) -> Value {
        Value::Dict(p.to_bottle())
    }
}

// ---- configuration options ----------------------------------------------------------------

/// Resolves `[import context file]` to a file path (C++ asks a `ResourceFinder`).
pub type ImportResolver = dyn Fn(&str, &str) -> Option<PathBuf> + Send + Sync;

/// Where `$VAR` references and includes are looked up when reading configuration.
///
/// `$VAR`, `${VAR}` and `$(VAR)` are replaced by, in order: the process environment, the
/// variables given here, keys already read from the same text, and `__YARP__` = 1 (C++
/// `fromConfig`'s `expand`). An unknown variable becomes empty text, as in C++.
pub struct ConfigOptions {
    vars: Property,
    process_env: bool,
    import: Option<Box<ImportResolver>>,
}

impl Default for ConfigOptions {
    fn default() -> Self {
        ConfigOptions {
            vars: Property::new(),
            process_env: true,
            import: None,
        }
    }
}

impl fmt::Debug for ConfigOptions {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("ConfigOptions")
            .field("vars", &self.vars)
            .field("process_env", &self.process_env)
            .field("import", &self.import.as_ref().map(|_| "<resolver>"))
            .finish()
    }
}

impl ConfigOptions {
    pub fn new() -> Self {
        ConfigOptions::default()
    }

    /// A variable for `$name` (C++ passes these as the `env` Searchable).
    pub fn var(mut self, name: &str, value: impl Into<Value>) -> Self {
        self.vars.put(name, value);
        self
    }

    /// Adds a directory to `CONFIG_PATH`, searched for files not found as written.
    pub fn search_path(mut self, dir: impl AsRef<Path>) -> Self {
        let mut path = self
            .vars
            .find("CONFIG_PATH")
            .map(|v| v.to_text_bare())
            .unwrap_or_default();
        if !path.is_empty() {
            path.push(b';');
        }
        path.extend(path_to_bytes(dir.as_ref()));
        self.vars.put("CONFIG_PATH", Value::String(path));
        self
    }

    /// Whether `$VAR` consults the process environment first (default true, as C++).
    /// Turn off for results that do not depend on the caller's environment.
    pub fn process_env(mut self, on: bool) -> Self {
        self.process_env = on;
        self
    }

    /// How to find `[import context file]`. Without one, an import is an error.
    pub fn import_resolver(
        mut self,
        f: impl Fn(&str, &str) -> Option<PathBuf> + Send + Sync + 'static,
    ) -> Self {
        self.import = Some(Box::new(f));
        self
    }
}

// ---- helpers shared by the readers --------------------------------------------------------

/// C++ keys are `Value::toString()`: bare text, empty for a missing element.
fn key_text(v: Option<&Value>) -> Vec<u8> {
    v.map(Value::to_text_bare).unwrap_or_default()
}

/// C++ `get(1).asString() == "="` (only a string answers `asString`).
fn is_equals_sign(v: Option<&Value>) -> bool {
    matches!(v, Some(Value::String(s)) if s == b"=")
}

fn lossy(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

#[cfg(unix)]
fn bytes_to_path(b: &[u8]) -> PathBuf {
    use std::os::unix::ffi::OsStrExt;
    PathBuf::from(std::ffi::OsStr::from_bytes(b))
}

#[cfg(not(unix))]
fn bytes_to_path(b: &[u8]) -> PathBuf {
    PathBuf::from(lossy(b))
}

#[cfg(unix)]
fn path_to_bytes(p: &Path) -> Vec<u8> {
    use std::os::unix::ffi::OsStrExt;
    p.as_os_str().as_bytes().to_vec()
}

#[cfg(not(unix))]
fn path_to_bytes(p: &Path) -> Vec<u8> {
    p.to_string_lossy().into_owned().into_bytes()
}

#[cfg(unix)]
fn os_to_bytes(s: OsString) -> Vec<u8> {
    use std::os::unix::ffi::OsStringExt;
    s.into_vec()
}

#[cfg(not(unix))]
fn os_to_bytes(s: OsString) -> Vec<u8> {
    s.to_string_lossy().into_owned().into_bytes()
}

fn find_sub(hay: &[u8], needle: &[u8]) -> Option<usize> {
    hay.windows(needle.len()).position(|w| w == needle)
}

/// Doubles every backslash: C++ does this to command-line words and expanded variables
/// so that Windows paths survive the Bottle reader's escapes.
fn double_backslashes(s: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(s.len());
    for &c in s {
        out.push(c);
        if c == b'\\' {
            out.push(c);
        }
    }
    out
}

// ---- command line -------------------------------------------------------------------------

/// C++ `Value::makeValue`: one token keeps its type, several become one string. An empty
/// word (C++: a null value) is kept as an empty string.
fn make_value(word: &[u8]) -> Value {
    let mut b = Bottle::from_text(word);
    match b.len() {
        0 => Value::String(Vec::new()),
        1 => b.pop().unwrap_or_else(|| Value::String(Vec::new())),
        _ => Value::String(word.to_vec()),
    }
}

/// C++ `Property::Private::fromCommand` with `wipe = false`.
fn from_command(p: &mut Property, args: impl Iterator<Item = Vec<u8>>) {
    let mut tag: Option<Vec<u8>> = None;
    let mut accum = Bottle::new();
    let mut total: Vec<Bottle> = Vec::new();
    let mut qualified = false;
    for arg in args {
        if arg.len() >= 2 && arg.starts_with(b"--") {
            let work = arg[2..].to_vec();
            qualified |= find_sub(&work, b"::").is_some();
            if tag.as_ref().is_some_and(|t| !t.is_empty()) {
                total.push(std::mem::take(&mut accum));
            }
            accum.clear();
            accum.push(make_value(&work));
            tag = Some(work);
        } else {
            // Words before the first `--key` are dropped when that key starts, as in C++.
            accum.push(make_value(&double_backslashes(&arg)));
        }
    }
    if tag.as_ref().is_some_and(|t| !t.is_empty()) {
        total.push(accum);
    }
    if !qualified {
        for group in total {
            p.put_bottle(key_text(group.get(0)), group);
        }
        return;
    }
    for term in total {
        // C++ uses `asString` here: a key that is not a string is skipped.
        let key = match term.get(0) {
            Some(Value::String(s)) => s.clone(),
            _ => continue,
        };
        let parts = qualified_parts(&key);
        let Some((first, rest)) = parts.split_first() else {
            continue;
        };
        let top = p.data.entry(first.clone()).or_insert_with(|| {
            let mut b = Bottle::new();
            b.push(Value::String(first.clone()));
            b
        });
        let mut cursor: &mut Bottle = top;
        for part in rest {
            cursor = child_group(cursor, part);
        }
        let base = parts.last().cloned().unwrap_or_default();
        let mut replaced = term.clone();
        if let Some(head) = replaced.get_mut(0) {
            *head = Value::String(base);
        }
        *cursor = replaced;
    }
}

/// Splits `a::b::c` as C++ does: a trailing `::` adds nothing, an inner empty part stays.
fn qualified_parts(key: &[u8]) -> Vec<Vec<u8>> {
    let mut parts = Vec::new();
    let mut rest = key;
    while !rest.is_empty() {
        match find_sub(rest, b"::") {
            Some(at) => {
                parts.push(rest[..at].to_vec());
                rest = &rest[at + 2..];
            }
            None => {
                parts.push(rest.to_vec());
                rest = &[];
            }
        }
    }
    parts
}

/// The nested group `name` inside `group`, created empty (`(name)`) when C++'s
/// `findGroup` would fail: the first element matching `name` is not a list, or none does.
fn child_group<'a>(group: &'a mut Bottle, name: &[u8]) -> &'a mut Bottle {
    let found = group.iter().position(|v| match v {
        Value::List(l) => key_text(l.get(0)) == name,
        other => other.to_text_bare() == name,
    });
    let index = match found {
        Some(i) if group.get(i).is_some_and(Value::is_list) => i,
        _ => {
            let mut fresh = Bottle::new();
            fresh.push(Value::String(name.to_vec()));
            group.push(Value::List(fresh));
            group.len() - 1
        }
    };
    match group.get_mut(index) {
        Some(Value::List(l)) => l,
        _ => unreachable!("index {index} was just checked or pushed as a list"),
    }
}

/// C++ `parseArguments`: quotes protect spaces and vanish, words split at single spaces;
/// the text before the first space is a word even when empty.
fn split_arguments(command: &[u8]) -> Vec<Vec<u8>> {
    const PROTECTED: u8 = 1;
    let mut text = command.to_vec();
    let mut quoted = false;
    for c in text.iter_mut() {
        if *c == b'"' {
            quoted = !quoted;
            *c = b' ';
        } else if quoted && *c == b' ' {
            *c = PROTECTED;
        }
    }
    let restore = |w: &[u8]| -> Vec<u8> {
        w.iter()
            .map(|&c| if c == PROTECTED { b' ' } else { c })
            .collect()
    };
    let mut words = Vec::new();
    let mut rest: &[u8] = &text;
    loop {
        match rest.iter().position(|&c| c == b' ') {
            None => {
                words.push(restore(rest));
                break;
            }
            Some(sp) => {
                words.push(restore(&rest[..sp]));
                let after = &rest[sp..];
                let skip = after.iter().take_while(|&&c| c == b' ').count();
                rest = &after[skip..];
                if rest.is_empty() {
                    break;
                }
            }
        }
    }
    words
}

// ---- configuration text -------------------------------------------------------------------

/// C++ `InputStream::readLine` over the config text, counting physical lines.
struct LineReader<'a> {
    text: &'a [u8],
    pos: usize,
    /// 1-based number of the physical line at `pos`.
    line: usize,
}

impl<'a> LineReader<'a> {
    fn new(text: &'a [u8]) -> Self {
        LineReader {
            text,
            pos: 0,
            line: 1,
        }
    }

    /// One logical line: `\r` and NUL dropped, a backslash before the newline joins the
    /// next line directly, other backslashes kept. `None` at the end of the text. (C++
    /// drops a line cut short by the end of the text; it is kept here.)
    fn read_line(&mut self) -> Option<Vec<u8>> {
        if self.pos >= self.text.len() {
            return None;
        }
        let mut buf = Vec::new();
        let mut esc = 0usize;
        while let Some(&c) = self.text.get(self.pos) {
            self.pos += 1;
            if c == b'\\' {
                esc += 1;
            }
            if c != 0 && c != b'\r' && c != b'\n' {
                if c != b'\\' || esc >= 2 {
                    buf.resize(buf.len() + esc, b'\\');
                    esc = 0;
                }
                if c != b'\\' {
                    buf.push(c);
                }
            }
            if c == b'\n' {
                self.line += 1;
                if esc == 0 {
                    return Some(buf);
                }
                esc = 0;
            }
        }
        Some(buf)
    }
}

/// C++ `BottleImpl::isComplete`: quotes closed and brackets balanced. `Err` says what is
/// open.
fn completeness(text: &[u8]) -> Result<(), &'static str> {
    let mut quoted = false;
    let mut back = false;
    let mut nested = 0i64;
    let mut nested_alt = 0i64;
    for &c in text {
        if back {
            back = false;
            continue;
        }
        if c == b'"' {
            quoted = !quoted;
        }
        if !quoted {
            match c {
                b'(' => nested += 1,
                b')' => nested -= 1,
                b'{' => nested_alt += 1,
                b'}' => nested_alt -= 1,
                _ => {}
            }
        }
        if c == b'\\' {
            back = true;
        }
    }
    if quoted {
        Err("unterminated quote")
    } else if nested != 0 {
        Err("unbalanced parentheses")
    } else if nested_alt != 0 {
        Err("unbalanced braces")
    } else {
        Ok(())
    }
}

/// C++ comment stripping: `//` anywhere outside double quotes, `#` at the start or after
/// a space or tab (so `10#15` is a value). The character before the comment goes too.
fn strip_comment(buf: &mut Vec<u8>) {
    if find_sub(buf, b"//").is_none() && !buf.contains(&b'#') {
        return;
    }
    let mut quoted = false;
    let mut prespace = true;
    let mut slashes = 0;
    for i in 0..buf.len() {
        let c = buf[i];
        if c == b'"' {
            quoted = !quoted;
        }
        if quoted {
            slashes = 0;
            prespace = false;
            continue;
        }
        if c == b'/' {
            slashes += 1;
            if slashes == 2 {
                buf.truncate(i - 1);
                return;
            }
        } else {
            slashes = 0;
            if c == b'#' && prespace {
                buf.truncate(i.saturating_sub(1));
                return;
            }
        }
        prespace = c == b' ' || c == b'\t';
    }
}

/// How many bytes `$VAR` substitutions may add over one configuration load. Each line may
/// name earlier values several times, so a few hundred bytes of text could otherwise grow
/// to gigabytes (the billion-laughs shape); real robots' files substitute a few kilobytes.
const EXPANSION_BUDGET: usize = 16 << 20;

/// The text of a line grew past [`EXPANSION_BUDGET`] through variable substitution.
struct ExpansionTooLarge;

/// C++ `expand`: replaces `$VAR`, `${VAR}`, `$(VAR)`; a backslash protects the next byte
/// (and stays in the text). Substituted bytes are taken from `budget`.
fn expand(
    input: &[u8],
    env: &Property,
    owner: &Property,
    process_env: bool,
    budget: &mut usize,
) -> Result<Vec<u8>, ExpansionTooLarge> {
    if !input.contains(&b'$') {
        return Ok(input.to_vec());
    }
    let mut out = Vec::with_capacity(input.len());
    let mut var: Vec<u8> = Vec::new();
    let mut in_var = false;
    let mut paren = false;
    let mut escaped = false;
    // C++ walks one byte past the end (a NUL) so that a trailing variable is resolved.
    for i in 0..=input.len() {
        let c = input.get(i).copied().unwrap_or(0);
        if escaped {
            if in_var {
                if c != 0 {
                    var.push(c);
                }
            } else {
                out.push(b'\\');
                if c != 0 {
                    out.push(c);
                }
            }
            escaped = false;
            continue;
        }
        if c == b'\\' {
            escaped = true;
            continue;
        }
        if in_var {
            if c.is_ascii_alphanumeric() || c == b'_' {
                var.push(c);
                continue;
            }
            if (c == b'(' || c == b'{') && var.is_empty() {
                paren = true;
                continue;
            }
            in_var = false;
            let value = double_backslashes(&lookup_var(&var, env, owner, process_env));
            *budget = budget.checked_sub(value.len()).ok_or(ExpansionTooLarge)?;
            out.extend(value);
            var.clear();
            if paren && (c == b'}' || c == b')') {
                continue;
            }
        }
        if c == b'$' {
            in_var = true;
            paren = false;
            continue;
        }
        if c != 0 {
            out.push(c);
        }
    }
    Ok(out)
}

fn lookup_var(var: &[u8], env: &Property, owner: &Property, process_env: bool) -> Vec<u8> {
    // Names std::env cannot look up (empty, `=`, NUL) are simply not in the environment.
    if process_env && !var.is_empty() && !var.contains(&b'=') && !var.contains(&0) {
        if let Some(v) = std::env::var_os(bytes_to_path(var).as_os_str()) {
            let v = os_to_bytes(v);
            if !v.is_empty() {
                return v;
            }
        }
    }
    for source in [env, owner] {
        let v = key_text(source.find(var));
        if !v.is_empty() {
            return v;
        }
    }
    if var == b"__YARP__" {
        return b"1".to_vec();
    }
    Vec::new()
}

/// Parses one config line as Bottle text; only absurd nesting fails.
fn parse_line(text: &[u8], line: usize) -> Result<Bottle, ParseError> {
    crate::text::try_parse(text).map_err(|e| ParseError::Syntax {
        line,
        message: e.to_string(),
    })
}

/// `*.ini` names in a directory, sorted bytewise (C++ `scandir` + `alphasort`).
fn ini_files(dir: &Path) -> Result<Vec<Vec<u8>>, String> {
    let mut names = Vec::new();
    for entry in std::fs::read_dir(dir).map_err(|e| e.to_string())? {
        let entry = entry.map_err(|e| e.to_string())?;
        let name = os_to_bytes(entry.file_name());
        if name.len() >= 4 && name.ends_with(b".ini") {
            names.push(name);
        }
    }
    names.sort();
    Ok(names)
}

/// `dir/name` with backslashes turned into slashes, as C++ `readDir` builds it.
fn dir_entry_path(dir: &[u8], name: &[u8]) -> Vec<u8> {
    let mut p = dir.to_vec();
    p.push(b'/');
    p.extend_from_slice(name);
    for c in p.iter_mut() {
        if *c == b'\\' {
            *c = b'/';
        }
    }
    p
}

/// Why a file could not be loaded.
enum LoadError {
    /// Not found, unreadable, a cycle or too deep: `reason` says which.
    Open { reason: String },
    /// The file was read but its text is faulty.
    Parse(ParseError),
}

impl LoadError {
    /// The error as seen from the line that asked for the file (0: the caller).
    fn into_parse_error(self, line: usize, fname: &[u8]) -> ParseError {
        match self {
            LoadError::Open { reason } => ParseError::Include {
                line,
                path: lossy(fname),
                reason,
            },
            LoadError::Parse(e) if line == 0 => e,
            LoadError::Parse(e) => ParseError::Include {
                line,
                path: lossy(fname),
                reason: e.to_string(),
            },
        }
    }
}

/// One configuration load: the include stack (for cycles and depth), the file budget and
/// what `$VAR` substitution may still add.
struct Loader<'o> {
    options: &'o ConfigOptions,
    stack: Vec<PathBuf>,
    loads: usize,
    expansion_budget: usize,
}

impl<'o> Loader<'o> {
    fn new(options: &'o ConfigOptions) -> Self {
        Loader {
            options,
            stack: Vec::new(),
            loads: 0,
            expansion_budget: EXPANSION_BUDGET,
        }
    }

    /// C++ `fromConfigFile(fname, env, wipe = false)`: the file as written, else along
    /// `CONFIG_PATH`; its directory is added to `CONFIG_PATH` for its own includes.
    fn load_file(
        &mut self,
        prop: &mut Property,
        fname: &[u8],
        env: &Property,
    ) -> Result<(), LoadError> {
        let search = key_text(env.find("CONFIG_PATH"));
        let mut failures = Vec::new();
        let mut found = None;
        match read_source(fname) {
            Ok(text) => found = Some((bytes_to_path(fname), text, Vec::new())),
            Err(e) => failures.push(format!("{}: {e}", lossy(fname))),
        }
        if found.is_none() {
            // C++ would try "/fname" for an empty entry; empty entries are skipped here.
            for dir in search.split(|&c| c == b';').filter(|d| !d.is_empty()) {
                let mut trial = dir.to_vec();
                trial.push(b'/');
                trial.extend_from_slice(fname);
                match read_source(&trial) {
                    Ok(text) => {
                        let mut prefix = dir.to_vec();
                        prefix.push(b'/');
                        found = Some((bytes_to_path(&trial), text, prefix));
                        break;
                    }
                    Err(e) => failures.push(format!("{}: {e}", lossy(&trial))),
                }
            }
        }
        let Some((path, text, prefix)) = found else {
            return Err(LoadError::Open {
                reason: format!("not found ({})", failures.join("; ")),
            });
        };
        let canonical = std::fs::canonicalize(&path).unwrap_or(path);
        if self.stack.contains(&canonical) {
            return Err(LoadError::Open {
                reason: "include cycle: the file is already being read".into(),
            });
        }
        if self.stack.len() >= MAX_INCLUDE_DEPTH {
            return Err(LoadError::Open {
                reason: format!("includes nested deeper than {MAX_INCLUDE_DEPTH}"),
            });
        }
        if self.loads >= MAX_FILE_LOADS {
            return Err(LoadError::Open {
                reason: format!("more than {MAX_FILE_LOADS} files read for one configuration"),
            });
        }
        self.loads += 1;

        // The directory part of the name as written, as C++ finds it.
        let dir = match fname.iter().rposition(|&c| c == b'/') {
            Some(i) => &fname[..i],
            None => match fname.iter().rposition(|&c| c == b'\\') {
                Some(i) => &fname[..i],
                None => &[][..],
            },
        };
        let mut extended = env.clone();
        if !dir.is_empty() {
            let mut path = search;
            if !path.is_empty() {
                path.push(b';');
            }
            path.extend_from_slice(&prefix);
            path.extend_from_slice(dir);
            extended.put("CONFIG_PATH", Value::String(path));
        }
        self.stack.push(canonical);
        let result = self.parse_config(prop, &text, &extended);
        self.stack.pop();
        result.map_err(LoadError::Parse)
    }

    /// C++ `fromConfig(txt, env, wipe = false)`.
    fn parse_config(
        &mut self,
        prop: &mut Property,
        text: &[u8],
        env: &Property,
    ) -> Result<(), ParseError> {
        let mut reader = LineReader::new(text);
        // The open `[section]`, empty at top level, and the groups read for it so far.
        let mut tag: Vec<u8> = Vec::new();
        let mut accum = Bottle::new();
        loop {
            let line = reader.line;
            let mut is_tag = false;
            let mut including = false;
            let mut buf = Vec::new();
            let done = match reader.read_line() {
                None => true,
                Some(first) => {
                    buf = first;
                    // A statement continues over lines until quotes and brackets close.
                    while let Err(why) = completeness(&buf) {
                        match reader.read_line() {
                            Some(more) => buf.extend(more),
                            None => {
                                return Err(ParseError::Syntax {
                                    line,
                                    message: format!("{why}: not closed by the end of the text"),
                                })
                            }
                        }
                    }
                    false
                }
            };
            if !done {
                strip_comment(&mut buf);
                buf = expand(
                    &buf,
                    env,
                    prop,
                    self.options.process_env,
                    &mut self.expansion_budget,
                )
                .map_err(|ExpansionTooLarge| ParseError::Syntax {
                    line,
                    message: format!(
                        "$variables expand to more than {} MiB over this configuration",
                        EXPANSION_BUDGET >> 20
                    ),
                })?;
                if buf.first() == Some(&b'[') {
                    if let Some(stop) = buf.iter().position(|&c| c == b']') {
                        buf = buf[1..stop].to_vec();
                        if buf.contains(&b' ') {
                            let bot = parse_line(&buf, line)?;
                            if bot.len() > 1 {
                                let head = key_text(bot.get(0));
                                if head == b"import" || head == b"include" {
                                    including = true;
                                    // An include closes the open section.
                                    if !tag.is_empty() && !accum.is_empty() {
                                        prop.put_bottle_compat(
                                            std::mem::take(&mut tag),
                                            accum.clone(),
                                        );
                                    }
                                    tag.clear();
                                    if head == b"import" {
                                        self.import(prop, &bot, env, line)?;
                                    } else {
                                        self.include(prop, &bot, env, line)?;
                                    }
                                }
                            }
                            if bot.len() == 2 && !including {
                                // `[list name]`: adds `name` to the group `list` and opens
                                // section `name`.
                                let key = key_text(bot.get(0));
                                buf = key_text(bot.get(1));
                                match prop.data.get_mut(&key) {
                                    Some(target) => {
                                        target.push(Value::String(buf.clone()));
                                    }
                                    None => {
                                        let mut init = Bottle::new();
                                        init.push(Value::String(key.clone()));
                                        init.push(Value::String(buf.clone()));
                                        prop.put_bottle_compat(key, init);
                                    }
                                }
                            }
                        }
                        if !including {
                            is_tag = true;
                        }
                    }
                }
            }
            if !is_tag && !including {
                let bot = parse_line(&buf, line)?;
                if !bot.is_empty() {
                    if tag.is_empty() {
                        // Top level: a repeated key replaces the earlier line.
                        prop.put_bottle_compat(key_text(bot.get(0)), bot);
                    } else if is_equals_sign(bot.get(1)) {
                        let fixed: Bottle = bot
                            .iter()
                            .enumerate()
                            .filter(|&(i, _)| i != 1)
                            .map(|(_, v)| v.clone())
                            .collect();
                        accum.push(Value::List(fixed));
                    } else {
                        // In a section repeated keys accumulate and `find` sees the first.
                        accum.push(Value::List(bot));
                    }
                }
            }
            if is_tag || done {
                if !tag.is_empty() && !accum.is_empty() {
                    prop.put_bottle_compat(std::mem::take(&mut tag), accum.clone());
                }
                tag = buf;
                accum = Bottle::new();
                accum.push(Value::String(tag.clone()));
                if !tag.is_empty() {
                    // A section seen before (or a key of that name) is reopened and merged.
                    if let Some(existing) = prop.data.get(&tag) {
                        accum.extend(existing.iter().skip(1).cloned());
                    }
                }
            }
            if done {
                return Ok(());
            }
        }
    }

    /// `[include file]`, `[include section file]`, `[include list section file]`.
    fn include(
        &mut self,
        prop: &mut Property,
        bot: &Bottle,
        env: &Property,
        line: usize,
    ) -> Result<(), ParseError> {
        let word = |i: usize| key_text(bot.get(i));
        let (section, fname) = match bot.len() {
            2 => {
                // The file's keys join this Property at top level.
                let fname = word(1);
                return self
                    .load_file(prop, &fname, env)
                    .map_err(|e| e.into_parse_error(line, &fname));
            }
            3 => (word(1), word(2)),
            4 => {
                let (list, section) = (word(1), word(2));
                match prop.data.get_mut(&list) {
                    Some(target) => {
                        target.push(Value::String(section.clone()));
                    }
                    None => {
                        let mut init = Bottle::new();
                        init.push(Value::String(list.clone()));
                        init.push(Value::String(section.clone()));
                        prop.put_bottle_compat(list, init);
                    }
                }
                (section, word(3))
            }
            n => {
                return Err(ParseError::Syntax {
                    line,
                    message: format!(
                        "bad include: {n} words; expected [include file], \
                         [include section file] or [include list section file]"
                    ),
                })
            }
        };
        // The file is read into its own Property, seeded with the section's earlier
        // content, and stored back as `(section (k v) ...)`. C++ copies through text.
        let mut sub = Property::new();
        if let Some(prior) = prop.data.get(&section) {
            let tail: Bottle = prior.iter().skip(1).cloned().collect();
            sub.merge_text(tail.to_text());
        }
        self.load_file(&mut sub, &fname, env)
            .map_err(|e| e.into_parse_error(line, &fname))?;
        let content = Bottle::from_text(sub.to_text());
        if !section.is_empty() && !content.is_empty() {
            let mut group = Bottle::with_capacity(content.len() + 1);
            group.push(Value::String(section.clone()));
            group.extend(content);
            prop.put_bottle_compat(section, group);
        }
        Ok(())
    }

    /// `[import context file]`: C++ asks a ResourceFinder; here the options' resolver.
    fn import(
        &mut self,
        prop: &mut Property,
        bot: &Bottle,
        env: &Property,
        line: usize,
    ) -> Result<(), ParseError> {
        let context = lossy(&key_text(bot.get(1)));
        let file = lossy(&key_text(bot.get(2)));
        let Some(resolve) = self.options.import.as_ref() else {
            return Err(ParseError::Include {
                line,
                path: file,
                reason: format!(
                    "[import {context} ...] needs a resource finder \
                     (ConfigOptions::import_resolver)"
                ),
            });
        };
        let Some(path) = resolve(&context, &file) else {
            return Err(ParseError::Include {
                line,
                path: file,
                reason: format!("not found in context {context:?}"),
            });
        };
        let fname = path_to_bytes(&path);
        self.load_file(prop, &fname, env)
            .map_err(|e| e.into_parse_error(line, &fname))
    }
}

/// C++ `readFile(.., allowDir = true)`: a file's bytes, or for a directory its `*.ini`
/// files in name order, each followed by `[]` to close any section it left open.
fn read_source(fname: &[u8]) -> Result<Vec<u8>, String> {
    let path = bytes_to_path(fname);
    if path.is_dir() {
        let mut text = Vec::new();
        for name in ini_files(&path)? {
            let file = dir_entry_path(fname, &name);
            let bytes = std::fs::read(bytes_to_path(&file))
                .map_err(|e| format!("{}: {e}", lossy(&file)))?;
            text.extend(bytes);
            text.extend_from_slice(b"\n[]\n");
        }
        return Ok(text);
    }
    std::fs::read(&path).map_err(|e| e.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::vocab::Vocab32;

    fn opts() -> ConfigOptions {
        ConfigOptions::new().process_env(false)
    }

    fn cfg(text: &str) -> Property {
        match Property::from_config_text_with(text, &opts()) {
            Ok(p) => p,
            Err(e) => panic!("config {text:?} failed: {e}"),
        }
    }

    fn args(list: &[&str]) -> Property {
        Property::from_args(list.iter().copied())
    }

    fn text_of(v: Option<&Value>) -> String {
        v.map(|v| lossy(&v.to_text_bare())).unwrap_or_default()
    }

    #[test]
    fn put_find_check() {
        let mut p = Property::new();
        p.put("hello", "there");
        p.put("hello", "friend");
        p.put("x", "y");
        assert!(p.check("hello") && p.check("x") && !p.check("y"));
        assert_eq!(p.find("hello").and_then(Value::as_str), Some("friend"));
        assert_eq!(p.to_string(), "(hello friend) (x y)");
        p.put("ten", 10);
        p.put("pi", 2.5);
        assert_eq!(p.find("ten"), Some(&Value::Int32(10)));
        assert_eq!(p.find("pi"), Some(&Value::Float64(2.5)));
        assert_eq!(p.unput("ten").map(|g| g.to_string()), Some("ten 10".into()));
        assert_eq!(p.find("ten"), None);
        assert!(p.find_group("twelve").is_none());
        assert_eq!(p.find_or("nope", 7), Value::Int32(7));
        assert_eq!(p.check_or("pi", 7), Value::Float64(2.5));
        assert_eq!(p.len(), 3);
        p.clear();
        assert!(p.is_empty());
        assert_eq!(p.to_string(), "");
    }

    #[test]
    fn flag_without_value_is_checked_but_not_found() {
        let p = Property::from_text("(hello)");
        assert!(p.check("hello"));
        assert_eq!(p.find("hello"), None);
        assert_eq!(p.find_or("hello", false), Value::Vocab32(Vocab32::FALSE));
    }

    #[test]
    fn from_text_and_printing() {
        let p = Property::from_text("(testing left right) (foo 12) junk (foo 13)");
        assert_eq!(p.find("foo"), Some(&Value::Int32(13)));
        assert_eq!(p.find("testing").and_then(Value::as_str), Some("left"));
        assert_eq!(
            p.find_group("testing").map(|g| g.to_string()),
            Some("testing left right".into())
        );
        // sorted by key, as std::map
        assert_eq!(p.to_string(), "(foo 13) (testing left right)");
        assert_eq!(Property::from_text(p.to_text()), p);
        let hex = Property::from_text("(CanAddress 0x0C) (b 0xff)");
        assert_eq!(hex.find("CanAddress"), Some(&Value::Int32(12)));
        assert_eq!(hex.find("b"), Some(&Value::Int32(255)));
        // keys sort bytewise: uppercase before lowercase, `B` < `a`
        let order = Property::from_text("(b 1) (a 2) (B 3) (\"é\" 4) (1 5)");
        let keys: Vec<&[u8]> = order.keys().collect();
        assert_eq!(
            keys,
            vec![&b"1"[..], b"B", b"a", b"b", "é".as_bytes()],
            "{order}"
        );
    }

    #[test]
    fn put_group_and_from_iter() {
        let mut p = Property::new();
        p.put("x", 1);
        let sub: Property = [("y", 2)].into_iter().collect();
        p.put_group("psub", &sub);
        assert_eq!(
            p.find_group("psub").and_then(|g| g.find("y")),
            Some(&Value::Int32(2))
        );
        assert_eq!(p.to_string(), "(psub (y 2)) (x 1)");
        let v: Value = p.clone().into();
        assert!(matches!(v, Value::Dict(ref b) if b.len() == 2));
        let q: Property = vec![("one", Value::Int32(1)), ("two", Value::Float64(2.0))]
            .into_iter()
            .collect();
        assert!(q.find("two").is_some_and(Value::is_float));
    }

    #[test]
    fn command_line() {
        let p = Property::from_command(["CMD", "--size", "10", "20", "--mono", "on"], true);
        assert_eq!(p.to_string(), "(mono on) (size 10 20)");
        assert_eq!(
            p.find_group("size").and_then(|g| g.get(2)),
            Some(&Value::Int32(20))
        );
        let p = args(&["--on", "/server", "--cmd", "\"ls foo\""]);
        assert_eq!(p.to_string(), "(cmd \"ls foo\") (on \"/server\")");
        // bare flag, value with spaces, words before the first key dropped
        let p = args(&[
            "stray",
            "--verbose",
            "--name",
            "my robot",
            "--list",
            "(1 2 3)",
        ]);
        assert!(p.check("verbose") && p.find("verbose").is_none());
        assert_eq!(p.find("name").and_then(Value::as_str), Some("my robot"));
        assert_eq!(text_of(p.find("list")), "1 2 3");
        assert!(!p.check("stray"));
        // later key wins
        assert_eq!(
            args(&["--a", "1", "--a", "2"]).find("a"),
            Some(&Value::Int32(2))
        );
        // a bare `--` swallows what follows
        assert_eq!(
            args(&["--a", "1", "--", "x", "--b", "2"]).to_string(),
            "(a 1) (b 2)"
        );
        // an empty word is kept as an empty string
        assert_eq!(args(&["--p", ""]).find("p"), Some(&Value::String(vec![])));
        // Windows paths survive
        let p = args(&["--file", "conf\\brains-brains.ini"]);
        assert_eq!(
            p.find("file").and_then(Value::as_str),
            Some("conf\\brains-brains.ini")
        );
        // too-large hex stays a string
        let p = args(&["--longlonghex", "0xFEDCBA9876543210"]);
        assert_eq!(
            p.find("longlonghex").and_then(Value::as_str),
            Some("0xFEDCBA9876543210")
        );
    }

    #[test]
    fn qualified_command_line() {
        let argv = ["--on", "/server", "--cmd", "\"ls foo\"", "--x::y::z", "10"];
        let p = args(&argv);
        let z = p
            .find_group("x")
            .and_then(|x| x.find_group("y"))
            .and_then(|y| y.find("z"));
        assert_eq!(z, Some(&Value::Int32(10)));
        assert_eq!(p.find("on").and_then(Value::as_str), Some("/server"));
        let mut p2 = Property::from_text("(x (y (z 45) (r 92))) (winding roads)");
        p2.merge_args(argv);
        let y = p2.find_group("x").and_then(|x| x.find_group("y"));
        assert_eq!(y.and_then(|y| y.find("z")), Some(&Value::Int32(10)));
        assert_eq!(y.and_then(|y| y.find("r")), Some(&Value::Int32(92)));
        assert!(p2.check("winding"));
        // nested into an existing plain value; trailing `::` adds nothing
        let p = args(&["--a", "5", "--a::b", "1", "--c::", "2"]);
        assert_eq!(p.to_string(), "(a 5 (b 1)) (c 2)");
        assert_eq!(
            qualified_parts(b"a::::b"),
            vec![b"a".to_vec(), vec![], b"b".to_vec()]
        );
    }

    #[test]
    fn arguments_string_and_query() {
        let p = Property::from_arguments("--name \"my robot\"  --x 1 2");
        assert_eq!(p.find("name").and_then(Value::as_str), Some("my robot"));
        assert_eq!(
            p.find_group("x").map(|g| g.to_string()),
            Some("x 1 2".into())
        );
        assert_eq!(
            split_arguments(b" a  b"),
            vec![b"".to_vec(), b"a".to_vec(), b"b".to_vec()]
        );
        let q = Property::from_query("prop1=val1&prop2=val2");
        assert_eq!(q.find("prop2").and_then(Value::as_str), Some("val2"));
        let q = Property::from_query("http://foo.bar.org/link?prop3=val3&prop4=val4");
        assert_eq!(q.to_string(), "(prop3 val3) (prop4 val4)");
        let q = Property::from_query("prop1=val+one&prop2=val%2Ftwo%2C&empty=");
        assert_eq!(q.find("prop1").and_then(Value::as_str), Some("val one"));
        assert_eq!(q.find("prop2").and_then(Value::as_str), Some("val/two,"));
        assert!(!q.check("empty"));
    }

    #[test]
    fn config_basics() {
        let p = cfg("size 10 20\nmono on\n");
        assert_eq!(p.to_string(), "(mono on) (size 10 20)");
        let p = cfg("[cat1]\nsize 10 20\nmono on\n[cat2]\nfoo\t100\n");
        assert_eq!(p.len(), 2);
        let size = p.find_group("cat1").and_then(|g| g.find_group("size"));
        assert_eq!(size.and_then(|s| s.get(1)), Some(&Value::Int32(10)));
        assert_eq!(
            p.to_string(),
            "(cat1 (size 10 20) (mono on)) (cat2 (foo 100))"
        );
        // the last line needs no newline; `key = value` drops the `=`
        let p = cfg("a = 1\n[s]\nb = 2 3\nc=4");
        assert_eq!(p.to_string(), "(a 1) (s (b 2 3) (\"c=4\"))");
        // top level: later line wins; in a section both stay and find sees the first
        let p = cfg("x 1\nx 2\n[s]\ny 1\ny 2\n");
        assert_eq!(p.find("x"), Some(&Value::Int32(2)));
        assert_eq!(
            p.find_group("s").map(|g| g.to_string()),
            Some("s (y 1) (y 2)".into())
        );
        assert_eq!(
            p.find_group("s").and_then(|g| g.find("y")),
            Some(&Value::Int32(1))
        );
        // `[]` returns to top level
        let p = cfg("[s]\na 1\n[]\nb 2\n");
        assert_eq!(p.to_string(), "(b 2) (s (a 1))");
    }

    #[test]
    fn config_sections_merge_and_lists() {
        let p = cfg("[base]\nw 4\n[other]\nq 0\n[base]\nz 3\n");
        assert_eq!(
            p.find_group("base").map(|g| g.to_string()),
            Some("base (w 4) (z 3)".into())
        );
        let p = cfg("[sect a]\nhello there\n[sect b]\nx 10\n");
        let sects: Bottle = p
            .find_group("sect")
            .map(|g| g.iter().skip(1).cloned().collect())
            .unwrap_or_default();
        assert_eq!(sects.to_string(), "a b");
        assert_eq!(
            text_of(p.find_group("a").and_then(|g| g.find("hello"))),
            "there"
        );
        // an empty section still creates its group
        assert_eq!(cfg("[empty]\n").to_string(), "(empty)");
    }

    #[test]
    fn config_comments() {
        assert_eq!(cfg("x 10\n// x 11\n").find("x"), Some(&Value::Int32(10)));
        let p = cfg("url \"http://www.robotcub.org\"\n");
        assert_eq!(
            p.find("url").and_then(Value::as_str),
            Some("http://www.robotcub.org")
        );
        assert_eq!(cfg("x 10 # 15").find_group("x").map(Bottle::len), Some(2));
        assert_eq!(cfg("x 10 // 15").find_group("x").map(Bottle::len), Some(2));
        assert_eq!(
            cfg("x \"# 1 // 2\" 4 5").find_group("x").map(Bottle::len),
            Some(4)
        );
        assert_eq!(cfg("x 10#15 4 5").find_group("x").map(Bottle::len), Some(4));
        let p = cfg("robotName icub \n urdf_file model.urdf \n # this is trash \n");
        assert!(!p.check("#"));
        assert_eq!(p.len(), 2);
        // unquoted `//` cuts even inside a word, as in C++
        assert_eq!(text_of(cfg("url http://x.org\n").find("url")), "http:");
        // `%` is no comment: C++ stores it as a key
        assert!(cfg("% note\n").check("%"));
    }

    #[test]
    fn config_line_joining() {
        let p = cfg("x to\\\ny 20\n");
        assert!(!p.check("y"));
        assert_eq!(text_of(p.find("x")), "toy");
        let p = cfg("l (1 2\n 3)\nz 1\n");
        assert_eq!(text_of(p.find("l")), "1 2 3");
        assert_eq!(p.find("z"), Some(&Value::Int32(1)));
        // CRLF and double backslashes
        let p = cfg("a 1\r\nb c\\\\d\r\n");
        assert_eq!(p.find("a"), Some(&Value::Int32(1)));
        assert_eq!(text_of(p.find("b")), "c\\d");
        let p = cfg("torso_yaw = ((0.275,\"0B3M0\") ,(0.275,\"0B3M1\") ,(0.55,\"0B4M0\"))\n");
        assert_eq!(
            p.find("torso_yaw")
                .and_then(Value::as_list)
                .map(Bottle::len),
            Some(3)
        );
    }

    #[test]
    fn config_errors_name_the_line() {
        let e = Property::from_config_text_with("a 1\nb \"open\nc 3\n", &opts());
        assert!(
            matches!(e, Err(ParseError::Syntax { line: 2, ref message }) if message.contains("quote")),
            "{e:?}"
        );
        let e = Property::from_config_text_with("a 1\n\n# oops :)\nc 3\n", &opts());
        assert!(
            matches!(e, Err(ParseError::Syntax { line: 3, .. })),
            "{e:?}"
        );
        let e = Property::from_config_text_with("[include a b c d]\n", &opts());
        assert!(
            matches!(e, Err(ParseError::Syntax { line: 1, .. })),
            "{e:?}"
        );
        let e = Property::from_config_text_with("x 1\n[import ctx f.ini]\n", &opts());
        assert!(
            matches!(e, Err(ParseError::Include { line: 2, .. })),
            "{e:?}"
        );
        let deep = format!("x {}{}", "(".repeat(3000), ")".repeat(3000));
        assert!(Property::from_config_text_with(deep, &opts()).is_err());
    }

    #[test]
    fn config_expansion() {
        let p = cfg("color red\nyarp1 $__YARP__\nyarp2 ${__YARP__}\nyarp3 pre_${__YARP__}_post\n");
        assert_eq!(p.find("yarp1"), Some(&Value::Int32(1)));
        assert_eq!(p.find("yarp2"), Some(&Value::Int32(1)));
        assert_eq!(text_of(p.find("yarp3")), "pre_1_post");
        let o = opts().var("TARGET", "Earth").var("WIN_PATH", "c:\\foo");
        let p = Property::from_config_text_with("targ $TARGET\npath $WIN_PATH\n", &o);
        let p = p.unwrap_or_default();
        assert_eq!(text_of(p.find("targ")), "Earth");
        assert_eq!(text_of(p.find("path")), "c:\\foo");
        let p = cfg("x 10\ny 20\ncheck $x $(y) $nothing \\$x\n");
        assert_eq!(
            p.find_group("check").map(|g| g.to_string()),
            Some("check 10 20 \"$x\"".into())
        );
        let mut budget = 100;
        let expanded = expand(
            b"a$$b",
            &Property::new(),
            &Property::new(),
            false,
            &mut budget,
        );
        assert_eq!(expanded.ok(), Some(b"a".to_vec()));
    }

    #[test]
    fn config_expansion_is_bounded() {
        // Each line names the one before twice: 40 lines would be 2^40 bytes.
        let mut text = String::from("k0 (xxxxxxxxxxxxxxxx)\n");
        for i in 1..40 {
            text.push_str(&format!("k{i} ($k{} $k{})\n", i - 1, i - 1));
        }
        let err = Property::from_config_text(&text)
            .err()
            .map(|e| e.to_string());
        let err = err.unwrap_or_default();
        assert!(err.contains("expand to more than 16 MiB"), "{err}");
        // Ordinary use stays well within it.
        let p = cfg("a 1 2 3\nb $a $a $a\n");
        assert_eq!(text_of(p.find("b")), "1");
    }

    #[test]
    fn config_process_env() {
        // cargo sets CARGO_PKG_NAME for test binaries
        let Some(name) = std::env::var_os("CARGO_PKG_NAME") else {
            return;
        };
        let p = Property::from_config_text("n $CARGO_PKG_NAME\n").unwrap_or_default();
        assert_eq!(text_of(p.find("n")), name.to_string_lossy());
    }

    #[test]
    fn never_panics_on_odd_text() {
        let samples = [
            "",
            "\n",
            "[",
            "]",
            "[]",
            "[ ]",
            "[ a b c ]",
            "[include]",
            "[include ]",
            "\\",
            "\\\\\n",
            "$",
            "${",
            "$(",
            "#",
            "//",
            "/",
            "\"",
            "\u{0}",
            "[a b]\n[a c]",
            "a = ",
            "= =",
            "[include x y]",
            "(",
            ")",
            "{",
            "}",
            "[x]]]",
            "\r\r\n",
        ];
        for s in samples {
            let _ = Property::from_config_text_with(s, &opts());
            let _ = Property::from_text(s);
            let _ = Property::from_arguments(s);
            let _ = Property::from_query(s);
            let _ = args(&[s, "--", s]);
        }
    }
}
