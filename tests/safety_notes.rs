//! Every `unsafe` in the library says why it is sound where it stands: an `unsafe { ... }` block or
//! `unsafe impl` has a `// SAFETY:` note (a comment, of one or more lines) on one of the three lines
//! above it, and an `unsafe fn`
//! (an `unsafe extern "system" fn` callback too) has a `# Safety` section in its doc comment, or a
//! `// SAFETY:` comment as a block has. This test reads src/ (unit tests included) and fails
//! naming each site without one.

mod common;

use common::rust_files;
use std::path::Path;

/// How many lines above an `unsafe` its `// SAFETY:` note may stand.
const NOTE_REACH: usize = 3;

/// What follows `unsafe` (as a whole word) on a line of code without its comment: `{`, `fn`,
/// `extern` or `impl`. `None` where the line has no such `unsafe` (an attribute such as
/// `#[allow(unused_unsafe)]`, a word in a string).
fn unsafe_kind(line: &str) -> Option<&'static str> {
    let code = line.split("//").next().unwrap_or("");
    for (at, _) in code.match_indices("unsafe") {
        let before = code[..at].chars().next_back();
        if before.is_some_and(|c| c.is_ascii_alphanumeric() || c == '_' || c == '"') {
            continue;
        }
        let rest = code[at + "unsafe".len()..].trim_start();
        for kind in ["{", "fn", "extern", "impl"] {
            if rest.starts_with(kind) {
                return Some(if kind == "extern" { "fn" } else { kind });
            }
        }
    }
    None
}

/// Whether one of the `NOTE_REACH` lines above line `at` belongs to a `// SAFETY:` note: a block of
/// `//` comment lines whose first line starts with `// SAFETY:` (a note may run over several lines).
fn has_note(lines: &[&str], at: usize) -> bool {
    let comment = |k: usize| lines[k].trim_start().starts_with("//");
    (at.saturating_sub(NOTE_REACH)..at).any(|k| {
        if !comment(k) {
            return false;
        }
        let first = (0..=k).rev().take_while(|&j| comment(j)).last().unwrap_or(k);
        lines[first].trim_start().starts_with("// SAFETY:")
    })
}

/// Whether the doc comment above line `at` (attributes may stand between them) has a `# Safety`
/// section.
fn has_safety_doc(lines: &[&str], at: usize) -> bool {
    for line in lines[..at].iter().rev().map(|l| l.trim_start()) {
        if line.starts_with("#[") {
            continue;
        }
        if !line.starts_with("///") {
            return false;
        }
        if line.trim_start_matches('/').trim() == "# Safety" {
            return true;
        }
    }
    false
}

/// The sites of `text` (as `line: code`) whose `unsafe` has no note.
fn unnoted(text: &str) -> Vec<String> {
    let lines: Vec<&str> = text.lines().collect();
    let mut missing = Vec::new();
    for (at, line) in lines.iter().enumerate() {
        let noted = match unsafe_kind(line) {
            None => continue,
            Some("fn") => has_safety_doc(&lines, at) || has_note(&lines, at),
            Some(_) => has_note(&lines, at),
        };
        if !noted {
            missing.push(format!("{}: {}", at + 1, line.trim()));
        }
    }
    missing
}

#[test]
fn every_unsafe_in_src_says_why_it_is_sound() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    files.sort();
    let mut missing = Vec::new();
    for path in &files {
        let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        let relative = path.strip_prefix(env!("CARGO_MANIFEST_DIR")).unwrap().display().to_string();
        missing.extend(unnoted(&text).into_iter().map(|site| format!("{relative}:{site}")));
    }
    assert!(
        missing.is_empty(),
        "{} unsafe site(s) without a `// SAFETY:` note on the {NOTE_REACH} lines above (or a `# Safety` doc on an unsafe fn):\n{}",
        missing.len(),
        missing.join("\n")
    );
}

#[test]
fn the_check_finds_a_block_without_a_note_and_accepts_the_ones_with() {
    let without = "fn f(p: *const u8) -> u8 {\n    unsafe { *p }\n}\n";
    assert_eq!(unnoted(without), ["2: unsafe { *p }"]);
    let far = "// SAFETY: too far above\n\n\n\nlet x = unsafe { *p };\n";
    assert_eq!(unnoted(far).len(), 1, "a note four lines up does not count");
    let long = "// SAFETY: p points into `bytes`,\n// which lives to the end of the function,\n// and is aligned\n// for u8.\nlet x = unsafe { *p };\n";
    assert!(unnoted(long).is_empty(), "a note of several lines ending above the block counts");
    let other =
        "// SAFETY: about something else\nlet y = 1;\n// A plain comment.\nlet z = 2;\nlet x = unsafe { *p };\n";
    assert_eq!(unnoted(other).len(), 1, "a plain comment is no note");
    let with = "    // SAFETY: p points into the live slice `bytes`.\n    let x = unsafe { *p };\n";
    assert!(unnoted(with).is_empty());
    let split = "    // SAFETY: the device is idle and owns the pool.\n    let pools = device\n        .and(unsafe { destroy() });\n";
    assert!(unnoted(split).is_empty(), "a note two lines up counts");
    let callback = "/// Called by the layer.\n///\n/// # Safety\n/// `data` is null or points to the layer's message.\nunsafe extern \"system\" fn on(data: *const u8) {}\n";
    assert!(unnoted(callback).is_empty(), "an unsafe fn documented with # Safety");
    let bare_fn = "/// Called by the layer.\nunsafe fn on() {}\n";
    assert_eq!(unnoted(bare_fn).len(), 1);
    let impl_without = "unsafe impl Send for Handle {}\n";
    assert_eq!(unnoted(impl_without).len(), 1);
    let not_code = "#[allow(unused_unsafe)]\nlet s = \"unsafe { no }\"; // unsafe { commented }\n";
    assert!(unnoted(not_code).is_empty(), "attributes, strings and comments are no sites");
}
