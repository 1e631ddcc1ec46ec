//! The docs test: every code block of the user-facing Markdown files is run as its reader
//! would run it, or checked as its `docs-test` comment says (`directives`). A block with
//! no comment fails, so a new command cannot go unchecked.

mod directives;
mod driver;
mod markdown;

pub use directives::{Directives, DirectivesError, Mode, Pattern};
pub use driver::{logical_lines, run_session, Setting};
pub use markdown::{blocks, Block};

use std::path::{Path, PathBuf};

/// The user-facing Markdown files under `root`: every `.md` but build outputs, vendored
/// code and dated reports (records of past runs, not instructions).
pub fn user_docs(root: &Path) -> Vec<PathBuf> {
    const SKIP: &[&str] = &[
        "target",
        "third_party",
        "reports",
        "corpus",
        "artifacts",
        "node_modules",
    ];
    let mut out = Vec::new();
    let mut dirs = vec![root.to_path_buf()];
    while let Some(dir) = dirs.pop() {
        let Ok(entries) = std::fs::read_dir(&dir) else {
            continue;
        };
        for e in entries.flatten() {
            let path = e.path();
            let name = e.file_name().to_string_lossy().into_owned();
            if name.starts_with('.') || SKIP.contains(&name.as_str()) {
                continue;
            }
            if path.is_dir() {
                dirs.push(path);
            } else if name.ends_with(".md") {
                out.push(path);
            }
        }
    }
    out.sort();
    out
}

/// Runs the block of `markdown` that starts at `line`, as the docs test does: its
/// comment must say how (and the blocks it follows are brought up first); the result is
/// what it printed, or why it failed.
pub fn check_block(markdown: &str, line: usize, s: &Setting) -> Result<String, String> {
    let all = blocks(markdown);
    let mut at = all
        .iter()
        .position(|b| b.line == line)
        .ok_or_else(|| format!("no code block starts at line {line}"))?;
    let mut steps = Vec::new();
    loop {
        let block = &all[at];
        let d = match &block.directives {
            None => {
                return Err(format!(
                    "line {}: no `<!-- docs-test: ... -->` comment before the block: say how it \
                     is checked (run, lines, terminals, transcript, synopsis, example, text, \
                     doctest; see tests/src/docs/directives.rs)",
                    block.line
                ))
            }
            Some(Err(e)) => return Err(format!("line {}: {e}", block.line)),
            Some(Ok(d)) => d,
        };
        steps.push((block, d));
        if !d.follows_previous {
            break;
        }
        at = at.checked_sub(1).ok_or_else(|| {
            format!(
                "line {}: `follows: previous`, but no block is before it",
                block.line
            )
        })?;
    }
    steps.reverse();
    run_session(&steps, s)
}

/// The docs test's own units: each breaks a documented command on purpose and checks that
/// the block then fails, saying why.
#[cfg(test)]
mod tests {
    use super::*;

    fn check(markdown: &str) -> Result<String, String> {
        let root = Path::new(env!("CARGO_MANIFEST_DIR"))
            .parent()
            .expect("repository");
        let scratch = tempfile::tempdir().expect("scratch");
        let line = blocks(markdown).first().expect("a block").line;
        check_block(markdown, line, &Setting::new(root, scratch.path()))
    }

    const TRANSCRIPT: &str = "<!-- docs-test: transcript -->\n\n    $ yarp bottle decode 0a01000001000000000000000000f03f\n    1.0\n";

    #[test]
    fn a_transcript_passes_and_a_wrong_output_fails() {
        check(TRANSCRIPT).expect("the README's transcript");
        let broken = TRANSCRIPT.replace("    1.0", "    2.0");
        let why = check(&broken).expect_err("the output differs");
        assert!(why.contains("where the block shows"), "{why}");
    }

    #[test]
    fn a_failing_command_fails_its_block() {
        let why =
            check("<!-- docs-test: run -->\n\n    yarp bottle decode zz\n").expect_err("bad hex");
        assert!(
            why.contains("failed") && why.contains("yarp bottle decode zz"),
            "{why}"
        );
        let why = check("<!-- docs-test: lines -->\n\n    true\n    yarp no-such-command\n")
            .expect_err("line 2");
        assert!(why.contains("line 2"), "{why}");
    }

    #[test]
    fn a_block_without_a_comment_fails() {
        let why = check("text\n\n    yarp version\n").expect_err("no comment");
        assert!(why.contains("no `<!-- docs-test"), "{why}");
        let why = check("<!-- docs-test: example: no check -->\n\n    x\n").expect_err("no check");
        assert!(why.contains("check"), "{why}");
    }

    #[test]
    fn a_program_that_never_comes_up_or_never_stops_fails() {
        let up = "<!-- docs-test: lines\nready: up\ntimeout: 20\n-->\n\n    true\n    bash -c 'echo up; sleep 100'\n";
        check(up).expect("a line that ends, then one up and stopped by Ctrl-C");
        let never = up
            .replace("ready: up", "ready: down")
            .replace("timeout: 20", "timeout: 2");
        let why = check(&never).expect_err("never up");
        assert!(why.contains("never printed \"down\""), "{why}");
        let deaf = "<!-- docs-test: lines\nready: up\nstop: 1\n-->\n\n    bash -c 'trap \"\" INT; echo up; sleep 100'\n";
        let why = check(deaf).expect_err("ignores Ctrl-C");
        assert!(why.contains("did not stop"), "{why}");
    }

    #[test]
    fn a_terminal_that_never_prints_what_the_block_promises_fails() {
        let t = "<!-- docs-test: terminals\ntype 1: hello\\n\nexpect 1: hello\ntimeout: 3\n-->\n\n    cat\n";
        check(t).expect("cat echoes what is typed");
        let why =
            check(&t.replace("expect 1: hello", "expect 1: goodbye")).expect_err("no goodbye");
        assert!(why.contains("line 1 never printed \"goodbye\""), "{why}");
    }

    #[test]
    fn the_repository_has_user_docs_and_every_block_a_comment() {
        let root = Path::new(env!("CARGO_MANIFEST_DIR"))
            .parent()
            .expect("repository");
        let files = user_docs(root);
        assert!(files.iter().any(|f| f.ends_with("README.md")));
        for f in files {
            let text = std::fs::read_to_string(&f).expect("read");
            for b in blocks(&text) {
                match &b.directives {
                    Some(Ok(_)) => {}
                    Some(Err(e)) => panic!("{}:{}: {e}", f.display(), b.line),
                    None => panic!("{}:{}: no docs-test comment", f.display(), b.line),
                }
            }
        }
    }
}
