//! Scene errors: a field path plus a message, located in the source (file, line, column) by
//! the loader that read it.

use toml::de::{DeTable, DeValue};

/// A problem with a field of a scene description, before it is located in a file.
#[derive(Debug, Clone, PartialEq)]
pub struct PathError {
    /// Field path such as `objects[2].material.color` (empty for the whole scene).
    pub path: String,
    /// What is wrong, e.g. `expected 3 numbers, got 2`.
    pub message: String,
}

impl PathError {
    /// A new error at `path`.
    pub fn new(path: impl Into<String>, message: impl Into<String>) -> Self {
        PathError {
            path: path.into(),
            message: message.into(),
        }
    }
}

/// Rewrites serde's "unknown variant/field `x`, expected one of `a`, `b`" into
/// `unknown <what> "x" (did you mean "a"?)`, naming the closest candidate when it is close.
pub fn friendly_message(message: &str, path: &str) -> String {
    let ticked: Vec<&str> = message.split('`').skip(1).step_by(2).collect();
    let kind = if message.starts_with("unknown variant") {
        let last = path.rsplit(['.', ']']).next().unwrap_or("");
        let what = if last.is_empty() || last.chars().all(|c| c.is_ascii_digit()) {
            "value"
        } else {
            last
        };
        Some(what.to_string())
    } else if message.starts_with("unknown field") {
        Some("key".to_string())
    } else {
        None
    };
    match (kind, ticked.split_first()) {
        (Some(what), Some((bad, candidates))) => {
            let mut out = format!("unknown {what} \"{bad}\"");
            if let Some(best) = closest(bad, candidates) {
                out.push_str(&format!(" (did you mean \"{best}\"?)"));
            } else if !candidates.is_empty() {
                let list: Vec<String> = candidates.iter().map(|c| format!("\"{c}\"")).collect();
                out.push_str(&format!(" (expected one of {})", list.join(", ")));
            }
            out
        }
        // pythonize's message for a negative or too large Python int in an unsigned field.
        _ if message.contains("out of range integral type conversion")
            || message.contains("can't convert negative int to unsigned") =>
        {
            "integer out of range: expected a non-negative integer of sensible size".to_string()
        }
        // pyo3's conversion errors passed on by pythonize: "TypeError: 'float' object cannot be
        // interpreted as an integer", "TypeError: must be real number, not str".
        _ if message.contains("object cannot be interpreted as an integer") => {
            let got = message.split('\'').nth(1).unwrap_or("something else");
            format!("expected an integer, got {got}")
        }
        _ if message.contains("must be real number, not ") => {
            let got = message.rsplit("not ").next().unwrap_or("something else");
            format!("expected a number, got {got}")
        }
        _ => message.to_string(),
    }
}

/// The candidate within edit distance ⌈len/3⌉ of `word`, if any.
fn closest<'a>(word: &str, candidates: &[&'a str]) -> Option<&'a str> {
    let best = candidates
        .iter()
        .map(|c| (levenshtein(word, c), *c))
        .min()?;
    (best.0 <= word.chars().count().div_ceil(3).max(1)).then_some(best.1)
}

fn levenshtein(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut prev: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut cur = vec![i + 1; b.len() + 1];
        for (j, cb) in b.iter().enumerate() {
            cur[j + 1] = (prev[j] + usize::from(ca != *cb))
                .min(prev[j + 1] + 1)
                .min(cur[j] + 1);
        }
        prev = cur;
    }
    prev[b.len()]
}

/// One step of a field path.
enum Step<'a> {
    Key(&'a str),
    Index(usize),
}

fn parse_path(path: &str) -> Vec<Step<'_>> {
    let mut steps = vec![];
    for part in path.split('.').filter(|p| !p.is_empty()) {
        let mut rest = part;
        if let Some(b) = rest.find('[') {
            if b > 0 {
                steps.push(Step::Key(&rest[..b]));
            }
            rest = &rest[b..];
            while let Some(stripped) = rest.strip_prefix('[') {
                let end = stripped.find(']').unwrap_or(stripped.len());
                if let Ok(i) = stripped[..end].parse() {
                    steps.push(Step::Index(i));
                }
                rest = stripped.get(end + 1..).unwrap_or("");
            }
        } else {
            steps.push(Step::Key(rest));
        }
    }
    steps
}

/// Byte span of the deepest existing value along `path` in a parsed TOML document.
pub fn span_of(root: &toml::Spanned<DeTable<'_>>, path: &str) -> std::ops::Range<usize> {
    let mut span = root.span();
    let mut table: Option<&DeTable<'_>> = Some(root.get_ref());
    let mut value: Option<&DeValue<'_>> = None;
    for step in parse_path(path) {
        let next = match (step, table, value) {
            (Step::Key(k), Some(t), _) => t.get(k),
            (Step::Key(k), None, Some(DeValue::Table(t))) => t.get(k),
            (Step::Index(i), None, Some(DeValue::Array(a))) => a.get(i),
            _ => None,
        };
        match next {
            Some(v) => {
                span = v.span();
                table = None;
                value = Some(v.get_ref());
            }
            None => break,
        }
    }
    span
}

/// 1-based line and column of a byte offset.
pub fn line_col(text: &str, offset: usize) -> (usize, usize) {
    let offset = offset.min(text.len());
    let before = &text[..offset];
    let line = before.matches('\n').count() + 1;
    let col = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
    (line, col)
}

#[cfg(test)]
mod tests;
