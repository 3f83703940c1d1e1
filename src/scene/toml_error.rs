//! A TOML error in a scene file as a short report: where (line, column, key), what, and the line
//! quoted around the column. The toml crate's own report quotes the whole line and underlines
//! all of it, so a 1 MB one-line scene gave a 2 MB message; and a few of its errors (a dotted key
//! nested past its recursion limit) carry no position at all, which is found here instead.

use std::ops::Range;

/// The most characters of the offending line quoted, centred on the error's column.
const QUOTED_CHARS: usize = 200;

/// The most characters of the error's own message: serde quotes offending values whole (an
/// unknown key, a string where a number belongs).
const MESSAGE_CHARS: usize = 300;

/// Describes `error`, met while reading `text`.
pub(super) fn describe(error: &toml::de::Error, text: &str) -> String {
    let mut report = String::new();
    let start = error.span().map(|span| span.start).or_else(|| locate(error.message(), text));
    if let Some(start) = start {
        let (line, column) = position(text, start);
        report.push_str(&format!("line {}, column {}: ", line.number, column + 1));
        report.push_str(&clip(error.message(), MESSAGE_CHARS));
        if let Some(key) = key_path(error) {
            report.push_str(&format!(" (key {key})"));
        }
        let (quoted, caret) = quote(&text[line.range], column);
        let gutter = " ".repeat(line.number.to_string().len());
        report.push_str(&format!("\n{} | {quoted}\n{gutter} | {}^", line.number, " ".repeat(caret)));
    } else {
        report.push_str(&clip(error.message(), MESSAGE_CHARS));
        if let Some(key) = key_path(error) {
            report.push_str(&format!(" (key {key})"));
        }
    }
    report
}

struct Line {
    /// 1-based.
    number: usize,
    /// Byte range in the text, without the newline.
    range: Range<usize>,
}

/// The line holding byte `offset` and the offset's column in characters (0-based).
fn position(text: &str, offset: usize) -> (Line, usize) {
    let offset = floor_char_boundary(text, offset.min(text.len()));
    let start = text[..offset].rfind('\n').map_or(0, |n| n + 1);
    let end = text[offset..].find('\n').map_or(text.len(), |n| offset + n);
    let number = text[..start].bytes().filter(|&b| b == b'\n').count() + 1;
    let column = text[start..offset].chars().count();
    (Line { number, range: start..end.max(start) }, column)
}

/// At most [`QUOTED_CHARS`] of `line` around character `column`, with `…` where it was cut, and
/// where the caret goes below it.
fn quote(line: &str, column: usize) -> (String, usize) {
    let line = line.trim_end_matches('\r');
    let length = line.chars().count();
    if length <= QUOTED_CHARS {
        return (line.to_owned(), column.min(length));
    }
    let first = column.saturating_sub(QUOTED_CHARS / 2).min(length - QUOTED_CHARS);
    let shown: String = line.chars().skip(first).take(QUOTED_CHARS).collect();
    let before = if first > 0 { "…" } else { "" };
    let after = if first + QUOTED_CHARS < length { "…" } else { "" };
    (format!("{before}{shown}{after}"), column - first + before.chars().count())
}

/// `message` cut to `limit` characters, saying how much was left out.
fn clip(message: &str, limit: usize) -> String {
    let message = message.trim_end();
    let length = message.chars().count();
    if length <= limit {
        return message.to_owned();
    }
    let kept: String = message.chars().take(limit).collect();
    format!("{kept}… ({} more characters)", length - limit)
}

/// The dotted key the error is under, when the toml crate knows it. It keeps the key path
/// private but prints it (`in `a.b``) when it has no source text to quote instead.
fn key_path(error: &toml::de::Error) -> Option<String> {
    let mut bare = error.clone();
    bare.set_input(None);
    let shown = bare.to_string();
    let key = shown.lines().last()?.strip_prefix("in `")?.strip_suffix('`')?;
    Some(clip(key, MESSAGE_CHARS))
}

/// Where a parse error without a position occurs: the end of the shortest run of whole lines
/// that already fails with the same message. (The parser reports the first error in the text;
/// lines after it cannot change whether a prefix fails with it, so the search can bisect.)
fn locate(message: &str, text: &str) -> Option<usize> {
    let ends: Vec<usize> = text.match_indices('\n').map(|(i, _)| i).chain([text.len()]).collect();
    let fails_by = |line: usize| {
        text[..ends[line]].parse::<toml::Table>().is_err_and(|e| e.span().is_none() && e.message() == message)
    };
    let last = ends.len() - 1;
    if !fails_by(last) {
        return None;
    }
    let (mut good, mut bad) = (None::<usize>, last);
    while good.map_or(0, |g| g + 1) < bad {
        let middle = (good.map_or(0, |g| g + 1) + bad) / 2;
        if fails_by(middle) {
            bad = middle;
        } else {
            good = Some(middle);
        }
    }
    // The start of the failing line.
    Some(if bad == 0 { 0 } else { ends[bad - 1] + 1 })
}

fn floor_char_boundary(text: &str, mut offset: usize) -> usize {
    while !text.is_char_boundary(offset) {
        offset -= 1;
    }
    offset
}

#[cfg(test)]
mod tests {
    use super::*;

    fn error_of(text: &str) -> String {
        #[derive(serde::Deserialize, Debug)]
        #[allow(dead_code)]
        struct Camera {
            camera: Position,
        }
        #[derive(serde::Deserialize, Debug)]
        #[allow(dead_code)]
        struct Position {
            position: f32,
        }
        let error = toml::from_str::<Camera>(text).unwrap_err();
        describe(&error, text)
    }

    #[test]
    fn a_long_line_is_quoted_around_the_error_only() {
        let text = format!("[camera]\nposition = \"{}\"\n", "x".repeat(1 << 20));
        let report = error_of(&text);
        assert!(report.starts_with("line 2, column 12: invalid type: string"), "{report}");
        assert!(report.contains("(key camera.position)"), "{report}");
        assert!(report.len() < 1200, "{} bytes: {report}", report.len());
        assert!(report.contains("more characters"), "{report}");
    }

    #[test]
    fn the_caret_points_at_the_column() {
        let report = error_of("[camera]\nposition = true\n");
        let lines: Vec<&str> = report.lines().collect();
        assert_eq!(lines[1], "2 | position = true", "{report}");
        assert_eq!(lines[2], "  |            ^", "{report}");
        let text = format!("[camera]\nposition = [{} @]", "1, ".repeat(300));
        let report = error_of(&text);
        let lines: Vec<&str> = report.lines().collect();
        assert!(lines[1].chars().count() <= QUOTED_CHARS + 6, "{report}");
        let caret = lines[2].find('^').unwrap();
        assert_eq!(lines[1].chars().nth(caret), Some('@'), "\n{report}");
    }

    #[test]
    fn a_nesting_error_without_a_position_is_given_its_line() {
        let deep = vec!["a"; 5000].join(".");
        let text = format!("[camera]\nposition = 1\n\n[{deep}]\nx = 1\n");
        let report = error_of(&text);
        assert!(report.starts_with("line 4, column 1: recursion limit"), "{report}");
        assert!(report.len() < 1200, "{report}");
    }

    #[test]
    fn positions_count_lines_and_characters() {
        let text = "ab\né = 1\nxyz";
        let (line, column) = position(text, text.find('=').unwrap());
        assert_eq!((line.number, &text[line.range], column), (2, "é = 1", 2));
        assert_eq!(position(text, text.len()).0.number, 3);
        assert_eq!(clip("abcdef", 3), "abc… (3 more characters)");
    }
}
