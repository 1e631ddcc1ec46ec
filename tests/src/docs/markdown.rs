//! The code blocks of a Markdown file, with the `docs-test` comment that says how each is
//! checked: indented blocks (four spaces after a blank line) and fenced ones (```).

use super::directives::{Directives, DirectivesError};

/// One code block of a Markdown file.
#[derive(Debug, Clone)]
pub struct Block {
    /// 1-based line of the block's first line of code.
    pub line: usize,
    /// The fence's info string (`sh`, `rust`, ...); empty for an indented block.
    pub lang: String,
    /// The code, without the indentation or the fences.
    pub code: String,
    /// The `<!-- docs-test ... -->` comment right before the block, if any.
    pub directives: Option<Result<Directives, DirectivesError>>,
}

/// Every code block of `markdown`, in order.
pub fn blocks(markdown: &str) -> Vec<Block> {
    let lines: Vec<&str> = markdown.lines().collect();
    let mut out = Vec::new();
    let mut i = 0;
    let mut after_blank = true;
    while i < lines.len() {
        let line = lines[i];
        if let Some(info) = fence(line) {
            let end = (i + 1..lines.len())
                .find(|&j| fence(lines[j]).is_some())
                .unwrap_or(lines.len());
            out.push(Block {
                line: i + 2,
                lang: info.to_string(),
                code: lines[i + 1..end].join("\n"),
                directives: comment_before(&lines, i),
            });
            i = end + 1;
            after_blank = false;
            continue;
        }
        if after_blank && line.starts_with("    ") && !line.trim().is_empty() {
            // The block runs on over blank lines while indented lines follow.
            let mut end = i;
            while end < lines.len() {
                let indented = lines[end].starts_with("    ");
                let blank_inside = lines[end].trim().is_empty()
                    && lines[end + 1..]
                        .iter()
                        .find(|l| !l.trim().is_empty())
                        .is_some_and(|l| l.starts_with("    "));
                if !(indented || blank_inside) {
                    break;
                }
                end += 1;
            }
            let code: Vec<&str> = lines[i..end]
                .iter()
                .map(|l| l.get(4..).unwrap_or(""))
                .collect();
            out.push(Block {
                line: i + 1,
                lang: String::new(),
                code: code.join("\n").trim_end().to_string(),
                directives: comment_before(&lines, i),
            });
            i = end;
            after_blank = false;
            continue;
        }
        after_blank = line.trim().is_empty();
        i += 1;
    }
    out
}

fn fence(line: &str) -> Option<&str> {
    line.strip_prefix("```").map(str::trim)
}

/// The `<!-- docs-test ... -->` comment that ends on the last non-blank line before line
/// `start` (0-based), parsed.
fn comment_before(lines: &[&str], start: usize) -> Option<Result<Directives, DirectivesError>> {
    let end = (0..start).rev().find(|&j| !lines[j].trim().is_empty())?;
    if !lines[end].trim_end().ends_with("-->") {
        return None;
    }
    let begin = (0..=end)
        .rev()
        .find(|&j| lines[j].trim_start().starts_with("<!--"))?;
    let text = lines[begin..=end].join("\n");
    let body = text
        .trim()
        .strip_prefix("<!--")?
        .strip_suffix("-->")?
        .trim();
    let body = body.strip_prefix("docs-test")?;
    let body = body.strip_prefix(':').unwrap_or(body);
    Some(Directives::parse(body))
}

#[cfg(test)]
mod tests {
    use super::*;

    const DOC: &str = "# Title\n\
        \n\
        Run it:\n\
        \n\
        <!-- docs-test: run -->\n\
        \n\
            \x20   yarp version\n\
            \x20   yarp name list\n\
        \n\
        - a list item\n\
        \n\
        ```sh\n\
        echo hi\n\
        ```\n\
        \n\
        text\n\
        \x20   not a block: no blank line before\n";

    #[test]
    fn finds_indented_and_fenced_blocks_and_their_comments() {
        let b = blocks(DOC);
        assert_eq!(b.len(), 2, "{b:#?}");
        assert_eq!(b[0].line, 7);
        assert_eq!(b[0].code, "yarp version\nyarp name list");
        assert!(matches!(b[0].directives, Some(Ok(_))));
        assert_eq!(b[1].lang, "sh");
        assert_eq!(b[1].line, 13);
        assert_eq!(b[1].code, "echo hi");
        assert!(b[1].directives.is_none());
    }
}
