//! Text taken from files, made safe to show and to write.
//!
//! - [`escape_control`]: for a terminal or a line-oriented text file. Keys,
//!   values, messages and column names read from a file are printed with
//!   their control characters escaped, so that a file cannot move the
//!   cursor, clear the screen, retitle the terminal (ANSI escape sequences),
//!   forge extra lines of output, or reorder what is shown (Unicode
//!   bidirectional overrides).
//! - [`csv_cell`]: for a CSV cell written from untrusted text (a column or
//!   topic name found in a file): a cell that a spreadsheet would take as a
//!   formula is prefixed with `'`, as OWASP's guidance on CSV injection
//!   recommends; numbers are left as they are.

use std::borrow::Cow;
use std::fmt::Write as _;

/// Characters shown escaped: C0 and C1 control characters and DEL
/// (`char::is_control`), and the Unicode bidirectional embeddings,
/// overrides and isolates (U+202A–U+202E, U+2066–U+2069) and marks
/// (U+200E, U+200F, U+061C).
fn needs_escape(c: char) -> bool {
    c.is_control()
        || matches!(c, '\u{202A}'..='\u{202E}' | '\u{2066}'..='\u{2069}')
        || matches!(c, '\u{200E}' | '\u{200F}' | '\u{061C}')
}

/// `s` with each control character escaped as Rust writes it in a string
/// literal (`\n`, `\t`, `\r`, `\0`, `\u{1b}`, `\u{202e}`); other text,
/// backslashes included, as it is. Borrowed when nothing needs escaping.
pub fn escape_control(s: &str) -> Cow<'_, str> {
    if !s.chars().any(needs_escape) {
        return Cow::Borrowed(s);
    }
    let mut out = String::with_capacity(s.len() + 8);
    for c in s.chars() {
        if needs_escape(c) {
            match c {
                '\n' => out.push_str("\\n"),
                '\r' => out.push_str("\\r"),
                '\t' => out.push_str("\\t"),
                '\0' => out.push_str("\\0"),
                _ => {
                    let _ = write!(out, "\\u{{{:x}}}", u32::from(c));
                }
            }
        } else {
            out.push(c);
        }
    }
    Cow::Owned(out)
}

/// `s` made safe as a CSV cell: prefixed with `'` when it starts with `=`,
/// `+`, `-`, `@`, a tab or a carriage return and is not a number
/// (`-1.5`, `+2e3` stay as they are). Borrowed when unchanged.
pub fn csv_cell(s: &str) -> Cow<'_, str> {
    let risky = s
        .chars()
        .next()
        .is_some_and(|c| matches!(c, '=' | '+' | '-' | '@' | '\t' | '\r'));
    if risky && s.parse::<f64>().is_err() {
        Cow::Owned(format!("'{s}"))
    } else {
        Cow::Borrowed(s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn control_characters_are_escaped_and_plain_text_borrowed() {
        assert!(matches!(escape_control("roll_rad"), Cow::Borrowed(_)));
        assert_eq!(escape_control("é C:\\x ✓"), "é C:\\x ✓");
        assert_eq!(
            escape_control("a\nb\rc\td\0e\u{1b}[2J\u{7f}\u{9b}"),
            "a\\nb\\rc\\td\\0e\\u{1b}[2J\\u{7f}\\u{9b}"
        );
        assert_eq!(escape_control("x\u{202e}gpj.exe"), "x\\u{202e}gpj.exe");
        assert_eq!(escape_control("\u{2066}\u{200f}"), "\\u{2066}\\u{200f}");
    }

    #[test]
    fn formula_cells_get_a_quote_and_numbers_do_not() {
        for (cell, want) in [
            ("=cmd|'/c calc'!A1", "'=cmd|'/c calc'!A1"),
            ("+x", "'+x"),
            ("-x", "'-x"),
            ("@SUM(A1)", "'@SUM(A1)"),
            ("\tx", "'\tx"),
            ("\rx", "'\rx"),
            ("-", "'-"),
            ("-1.5", "-1.5"),
            ("+2e3", "+2e3"),
            ("-inf", "-inf"),
            ("a=b", "a=b"),
            ("", ""),
            ("esc[0].rpm", "esc[0].rpm"),
        ] {
            assert_eq!(csv_cell(cell), want, "{cell:?}");
        }
    }
}
