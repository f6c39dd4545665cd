//! "Did you mean": the valid name nearest to a misspelt one.
//!
//! The TOML reader refuses an unknown field with the list of the valid ones
//! (``unknown field `duraton_s`, expected one of `name`, `duration_s`, …``);
//! [`with_suggestion`] adds the nearest of them to that message, and
//! [`nearest`] finds it for a reader with its own list of names.

/// The candidate nearest to `given` by edit distance (insertions,
/// deletions, substitutions, and swaps of two neighbours, letter case
/// ignored), if near enough to be a misspelling: at most a third of the
/// longer name's letters, and at least one. `None` when nothing is that
/// near, or `given` is itself a candidate.
pub fn nearest<'a>(given: &str, candidates: impl IntoIterator<Item = &'a str>) -> Option<&'a str> {
    let g: Vec<char> = given.to_lowercase().chars().collect();
    let mut best: Option<(usize, &'a str)> = None;
    for c in candidates {
        if c == given {
            return None;
        }
        let cc: Vec<char> = c.to_lowercase().chars().collect();
        let d = distance(&g, &cc);
        let limit = (g.len().max(cc.len()) / 3).max(1);
        if d <= limit && best.is_none_or(|(b, _)| d < b) {
            best = Some((d, c));
        }
    }
    best.map(|(_, c)| c)
}

/// Optimal string alignment distance between `a` and `b`.
fn distance(a: &[char], b: &[char]) -> usize {
    // rows i-2, i-1 and i of the table
    let mut prev2 = vec![0usize; b.len() + 1];
    let mut prev: Vec<usize> = (0..=b.len()).collect();
    let mut row = vec![0usize; b.len() + 1];
    for i in 1..=a.len() {
        row[0] = i;
        for j in 1..=b.len() {
            let cost = usize::from(a[i - 1] != b[j - 1]);
            let mut d = (prev[j] + 1).min(row[j - 1] + 1).min(prev[j - 1] + cost);
            if i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1] {
                d = d.min(prev2[j - 2] + 1);
            }
            row[j] = d;
        }
        std::mem::swap(&mut prev2, &mut prev);
        std::mem::swap(&mut prev, &mut row);
    }
    prev[b.len()]
}

/// `message` with ``; did you mean `NAME`?`` after each line that refuses an
/// unknown field or variant (``unknown field `X`, expected one of `A`, `B` ``,
/// as the TOML reader says it) when one of the expected names is near `X`
/// ([`nearest`]); any other message unchanged.
pub fn with_suggestion(message: &str) -> String {
    let mut out = String::with_capacity(message.len() + 32);
    for (i, line) in message.split('\n').enumerate() {
        if i > 0 {
            out.push('\n');
        }
        out.push_str(line);
        if let Some(name) = suggestion(line) {
            out.push_str("; did you mean `");
            out.push_str(name);
            out.push_str("`?");
        }
    }
    out
}

/// The suggestion for one line of a parser's message.
fn suggestion(line: &str) -> Option<&str> {
    if line.contains("did you mean") {
        return None;
    }
    let start = ["unknown field `", "unknown variant `"]
        .iter()
        .find_map(|p| line.find(p).map(|i| i + p.len()))?;
    let rest = &line[start..];
    let end = rest.find('`')?;
    let given = &rest[..end];
    let expected = &rest[end + 1..];
    let list = &expected[expected.find("expected")?..];
    // the backquoted names: every second piece between backquotes
    let names = list.split('`').skip(1).step_by(2);
    nearest(given, names)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_nearest_name_within_a_third_of_its_letters() {
        let keys = ["name", "duration_s", "params", "seed"];
        assert_eq!(nearest("duraton_s", keys), Some("duration_s"));
        assert_eq!(nearest("Duration_S", keys), Some("duration_s"));
        assert_eq!(nearest("duration", keys), Some("duration_s"));
        assert_eq!(nearest("sede", keys), Some("seed")); // a swap is one edit
        assert_eq!(nearest("wind", keys), None);
        assert_eq!(nearest("seed", keys), None);
        assert_eq!(distance(&['a', 'b'], &[]), 2);
    }

    #[test]
    fn a_parser_message_gets_the_suggestion_on_its_line() {
        let m = "TOML parse error at line 3, column 1\n  |\n3 | duraton_s = 5\n  | ^^^^^^^^^\nunknown field `duraton_s`, expected one of `name`, `duration_s`, `seed`\n";
        let s = with_suggestion(m);
        assert!(
            s.ends_with(
                "unknown field `duraton_s`, expected one of `name`, `duration_s`, `seed`; did you mean `duration_s`?\n"
            ),
            "{s}"
        );
        assert!(s.starts_with("TOML parse error at line 3, column 1\n"));
        // one expected name, and a variant
        assert_eq!(
            with_suggestion("unknown field `rat_hz`, expected `rate_hz`"),
            "unknown field `rat_hz`, expected `rate_hz`; did you mean `rate_hz`?"
        );
        assert_eq!(
            with_suggestion("unknown variant `ekf`, expected `eskf` or `complementary`"),
            "unknown variant `ekf`, expected `eskf` or `complementary`; did you mean `eskf`?"
        );
        // nothing near, or another error: unchanged (and never twice)
        for m in [
            "unknown field `zzz`, expected one of `name`, `seed`",
            "invalid type: string \"a\", expected f64",
            "unknown field `sed`, expected `seed`; did you mean `seed`?",
        ] {
            assert_eq!(with_suggestion(m), m);
        }
    }

    #[test]
    fn the_config_error_names_file_field_and_suggestion() {
        let e = crate::ConfigError::Parse {
            file: "s.toml".into(),
            message: "unknown field `sede`, expected one of `name`, `seed`".into(),
        };
        assert_eq!(
            e.to_string(),
            "s.toml: unknown field `sede`, expected one of `name`, `seed`; did you mean `seed`?"
        );
    }
}
