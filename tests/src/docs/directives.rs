//! What a `<!-- docs-test ... -->` comment says about the block after it.
//!
//! The comment's first line names the mode, the others add to it, one per line:
//!
//! ```text
//! <!-- docs-test: terminals
//! after 1: yarp name list
//! type 4: CONNECT foo\nd\n[get] [axes]\n
//! expect 4: [is] [axes] 2 [ok]
//! -->
//! ```
//!
//! Modes: `run` (the block is one shell script), `lines` (each line is a command of its
//! own, run one after the other), `terminals` (each line in a terminal of its own, all
//! running at once, as a user types them), `transcript` (`$ command` lines, each followed
//! by exactly what it prints), `example: WHY` (not run as written, e.g. it needs a real
//! robot: the `check:` commands are run instead), `text: WHY` (not a command: output, a
//! configuration fragment), `doctest: FILE` (Rust code that FILE's doc tests hold verbatim),
//! `synopsis` (a program's usage: its `--help` must name every `--flag` the block shows).
//!
//! Keys (`N` is a line of the block, from 1): `timeout: SECONDS` (the whole block, default
//! 90), `env: NAME=VALUE`, `stdin: TEXT` (piped, then closed), `type N: TEXT` (typed into
//! terminal N, which stays open), `after N: COMMAND` (retried until it succeeds before
//! the next line starts), `ready[ N]: TEXT` (a command that runs until stopped is up once
//! its output holds TEXT; it is then stopped with Ctrl-C and must exit cleanly),
//! `stop: SECONDS` (how long Ctrl-C may take, default 30: a robot parks first),
//! `expect[ N]: TEXT` (the output must hold TEXT), `check: COMMAND` (for `example`),
//! `replace: OLD => NEW` (the block is run with OLD replaced, e.g. a shorter duration),
//! `before: COMMAND` (run to completion first: what the surrounding prose has the reader
//! start), `follows: previous` (the block before this one in the file runs first, until
//! it is up, and stays up: this block is the next step of the same session).
//! TEXT takes `\n`; `/.../` is a regular expression. Lines starting with `#` are comments.

use std::collections::BTreeMap;
use std::fmt;
use std::time::Duration;

/// How a block is checked.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Mode {
    Run,
    Lines,
    Terminals,
    Transcript,
    Example { why: String },
    Text { why: String },
    Doctest { file: String },
    Synopsis,
}

/// Text a command's output must hold: a substring, or `/regex/`.
#[derive(Debug, Clone)]
pub enum Pattern {
    Contains(String),
    Regex(regex::Regex),
}

impl Pattern {
    fn parse(text: &str) -> Result<Pattern, String> {
        match text.strip_prefix('/').and_then(|t| t.strip_suffix('/')) {
            Some(re) if !re.is_empty() => regex::Regex::new(re)
                .map(Pattern::Regex)
                .map_err(|e| format!("bad regular expression {text}: {e}")),
            _ => Ok(Pattern::Contains(unescape(text))),
        }
    }

    /// Whether `output` holds the pattern.
    pub fn found_in(&self, output: &str) -> bool {
        match self {
            Pattern::Contains(s) => output.contains(s.as_str()),
            Pattern::Regex(re) => re.is_match(output),
        }
    }
}

impl fmt::Display for Pattern {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Pattern::Contains(s) => write!(f, "{s:?}"),
            Pattern::Regex(re) => write!(f, "/{re}/"),
        }
    }
}

/// A parsed `docs-test` comment.
#[derive(Debug, Clone)]
pub struct Directives {
    pub mode: Mode,
    pub timeout: Duration,
    pub stop: Duration,
    pub env: Vec<(String, String)>,
    pub stdin: Option<String>,
    /// Per line (1-based): text typed into that terminal.
    pub typed: BTreeMap<usize, String>,
    /// Per line: a command retried until it succeeds before the next line starts.
    pub after: BTreeMap<usize, String>,
    /// `None` key: every line (or the whole script).
    pub ready: BTreeMap<Option<usize>, Pattern>,
    pub expect: Vec<(Option<usize>, Pattern)>,
    pub checks: Vec<String>,
    pub replace: Vec<(String, String)>,
    pub before: Vec<String>,
    pub follows_previous: bool,
}

/// A comment that does not parse, with the reason.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DirectivesError(pub String);

impl fmt::Display for DirectivesError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "docs-test comment: {}", self.0)
    }
}

impl Directives {
    /// Parses the comment's text after `docs-test:`.
    pub fn parse(body: &str) -> Result<Directives, DirectivesError> {
        let err = |m: String| DirectivesError(m);
        // `# ...` lines are comments, for the reader of the Markdown source
        let mut lines = body
            .lines()
            .map(str::trim)
            .filter(|l| !l.is_empty() && !l.starts_with('#'));
        let first = lines.next().ok_or_else(|| err("no mode".into()))?;
        let (word, rest) = split_key(first);
        let rest = rest.unwrap_or("").to_string();
        let need = |what: &str| {
            if rest.is_empty() {
                Err(err(format!("`{word}` needs {what} after `{word}:`")))
            } else {
                Ok(rest.clone())
            }
        };
        let mode = match word {
            "run" => Mode::Run,
            "lines" => Mode::Lines,
            "terminals" => Mode::Terminals,
            "transcript" => Mode::Transcript,
            "synopsis" => Mode::Synopsis,
            "example" => Mode::Example {
                why: need("why it is not run as written")?,
            },
            "text" => Mode::Text {
                why: need("what the block is")?,
            },
            "doctest" => Mode::Doctest {
                file: need("the file whose doc tests hold it")?,
            },
            other => return Err(err(format!("unknown mode `{other}`"))),
        };
        let mut d = Directives {
            mode,
            timeout: Duration::from_secs(90),
            stop: Duration::from_secs(30),
            env: Vec::new(),
            stdin: None,
            typed: BTreeMap::new(),
            after: BTreeMap::new(),
            ready: BTreeMap::new(),
            expect: Vec::new(),
            checks: Vec::new(),
            replace: Vec::new(),
            before: Vec::new(),
            follows_previous: false,
        };
        for line in lines {
            let (key, value) = split_key(line);
            let value = value.ok_or_else(|| err(format!("`{line}`: no `:` after the key")))?;
            let (name, n) =
                match key.split_once(' ') {
                    Some((name, n)) => {
                        let n: usize =
                            n.trim().parse().ok().filter(|&n| n > 0).ok_or_else(|| {
                                err(format!("`{key}`: the line number is 1, 2, ..."))
                            })?;
                        (name, Some(n))
                    }
                    None => (key, None),
                };
            let needs_line =
                |n: Option<usize>| n.ok_or_else(|| err(format!("`{name}` needs a line number")));
            match name {
                "timeout" => {
                    let s: u64 = value
                        .parse()
                        .map_err(|_| err(format!("timeout `{value}`")))?;
                    d.timeout = Duration::from_secs(s);
                }
                "stop" => {
                    let s: u64 = value.parse().map_err(|_| err(format!("stop `{value}`")))?;
                    d.stop = Duration::from_secs(s);
                }
                "env" => {
                    let (k, v) = value
                        .split_once('=')
                        .ok_or_else(|| err(format!("env `{value}`: NAME=VALUE")))?;
                    d.env.push((k.to_string(), v.to_string()));
                }
                "stdin" => d.stdin = Some(unescape(value)),
                "type" => {
                    d.typed.insert(needs_line(n)?, unescape(value));
                }
                "after" => {
                    d.after.insert(needs_line(n)?, value.to_string());
                }
                "ready" => {
                    d.ready.insert(n, Pattern::parse(value).map_err(err)?);
                }
                "expect" => d.expect.push((n, Pattern::parse(value).map_err(err)?)),
                "check" => d.checks.push(value.to_string()),
                "before" => d.before.push(value.to_string()),
                "follows" if value == "previous" => d.follows_previous = true,
                "follows" => return Err(err(format!("follows `{value}`: only `previous`"))),
                "replace" => {
                    let (old, new) = value
                        .split_once(" => ")
                        .ok_or_else(|| err(format!("replace `{value}`: OLD => NEW")))?;
                    d.replace.push((old.to_string(), new.to_string()));
                }
                other => return Err(err(format!("unknown key `{other}`"))),
            }
        }
        if matches!(d.mode, Mode::Example { .. }) && d.checks.is_empty() {
            return Err(err("an example needs at least one `check:` command".into()));
        }
        Ok(d)
    }

    /// The pattern that says line `n` (or the script, `None`) is up.
    pub fn ready_for(&self, n: Option<usize>) -> Option<&Pattern> {
        self.ready.get(&n).or_else(|| self.ready.get(&None))
    }
}

/// `key: value` at the first `:` followed by a space or the end (so `a::b` is no key).
fn split_key(line: &str) -> (&str, Option<&str>) {
    let mut from = 0;
    while let Some(i) = line[from..].find(':').map(|i| i + from) {
        let next = line[i + 1..].chars().next();
        if next.is_none() || next == Some(' ') {
            return (line[..i].trim(), Some(line[i + 1..].trim()));
        }
        from = i + 1;
    }
    (line.trim(), None)
}

fn unescape(text: &str) -> String {
    text.replace("\\n", "\n").replace("\\t", "\t")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_a_terminals_comment() {
        let d = Directives::parse(
            " terminals\nafter 1: yarp name list\ntype 4: CONNECT foo\\nd\\n\nexpect 4: [is] [axes] 2 [ok]\nready: /up in [0-9.]+ s/\ntimeout: 30",
        )
        .unwrap();
        assert_eq!(d.mode, Mode::Terminals);
        assert_eq!(d.after[&1], "yarp name list");
        assert_eq!(d.typed[&4], "CONNECT foo\nd\n");
        assert!(d.expect[0].1.found_in("x [is] [axes] 2 [ok] y"));
        assert!(d
            .ready_for(Some(3))
            .unwrap()
            .found_in("demo is up in 1.5 s."));
        assert_eq!(d.timeout, Duration::from_secs(30));
    }

    #[test]
    fn refuses_what_it_does_not_know() {
        assert!(Directives::parse("rn").is_err());
        assert!(
            Directives::parse("example: needs a robot").is_err(),
            "no check"
        );
        assert!(Directives::parse("text").is_err(), "no reason");
        assert!(Directives::parse("run\nexpect 0: x").is_err());
        assert!(Directives::parse("run\nfoo: x").is_err());
        assert!(Directives::parse("run\nreplace: a -> b").is_err());
    }
}
