//! The one error type of scene and script loading. Every error names the file, and (except when the
//! file cannot be read) the line and column of the offending text, as `path:line:column: message`.

use std::path::PathBuf;

use thiserror::Error;

use super::locate::{Position, Seg, Tree};

/// Why a scene or script could not be loaded. A failed load returns nothing: never half a scene.
#[derive(Debug, Error)]
pub enum SceneError {
    /// The file could not be read.
    #[error("{}: cannot read the file: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// What the operating system said.
        source: std::io::Error,
    },
    /// The text is not RON, or not the shape of a scene (unknown field, wrong type, missing field).
    #[error("{}:{line}:{column}: {message}", path.display())]
    Parse {
        /// The file, or the name given to [`Scene::from_str`](super::Scene::from_str).
        path: PathBuf,
        /// Line, from 1.
        line: usize,
        /// Column in characters, from 1.
        column: usize,
        /// What is wrong and what is expected.
        message: String,
    },
    /// The scene has the right shape but a value is out of range or inconsistent.
    #[error("{}:{line}:{column}: {field} {message}", path.display())]
    Invalid {
        /// The file, or the name given to `from_str`.
        path: PathBuf,
        /// Line of the offending value, from 1 (where the value would go if it is a default).
        line: usize,
        /// Column in characters, from 1.
        column: usize,
        /// The offending field as a path, e.g. `tissue.layers[0].material.limits.max_stretch`.
        field: String,
        /// What is wrong and what is expected, phrased to follow the field: `is 0.5, expected ...`.
        message: String,
    },
}

impl SceneError {
    /// Line and column, when the error has them.
    pub fn line_column(&self) -> Option<(usize, usize)> {
        match self {
            SceneError::Io { .. } => None,
            SceneError::Parse { line, column, .. } | SceneError::Invalid { line, column, .. } => {
                Some((*line, *column))
            }
        }
    }
}

/// Turns RON's error into a [`SceneError::Parse`] with a message for people.
pub(crate) fn parse_error(path: &std::path::Path, src: &str, e: &ron::error::SpannedError) -> SceneError {
    use ron::error::Error as E;
    let mut line = e.position.line;
    let mut column = e.position.col;
    let message = match &e.code {
        E::NoSuchStructField { expected, found, outer } => {
            // RON points just after the name; point at its start.
            column = column.saturating_sub(found.chars().count()).max(1);
            format!(
                "unknown field `{found}`{}, expected one of: {}{}",
                outer.as_ref().map(|o| format!(" in `{o}`")).unwrap_or_default(),
                list(expected),
                did_you_mean(found, expected.iter().copied())
            )
        }
        E::MissingStructField { field, outer } => {
            let outer_text = outer.as_ref().map(|o| format!(" in `{o}`")).unwrap_or_default();
            // A misspelt field of a struct that ignores unknown fields shows up as a missing field
            // reported at the struct's end: point at the misspelling instead.
            let end = Position { line, column };
            let near = Tree::parse(src).struct_ending_at(end).and_then(|fields| {
                fields
                    .into_iter()
                    .filter(|(n, _)| n != field)
                    .map(|(n, p)| (edit_distance(&n, field), n, p))
                    .filter(|(d, n, _)| *d <= 2.max(n.chars().count() / 3))
                    .min_by_key(|(d, _, _)| *d)
            });
            match near {
                Some((_, name, p)) => {
                    line = p.line;
                    column = p.column;
                    format!("unknown field `{name}`{outer_text}, expected `{field}` (is it misspelt?)")
                }
                None => {
                    format!("missing field `{field}`{outer_text}: it has no default, so it must be given")
                }
            }
        }
        E::NoSuchEnumVariant { expected, found, outer } => {
            column = column.saturating_sub(found.chars().count()).max(1);
            format!(
                "unknown choice `{found}`{}, expected one of: {}{}",
                outer.as_ref().map(|o| format!(" for `{o}`")).unwrap_or_default(),
                list(expected),
                did_you_mean(found, expected.iter().copied())
            )
        }
        E::ExpectedComma if char_at(src, line, column) == Some('.') => {
            "expected a whole number here (no decimal point), or a comma".to_owned()
        }
        E::DuplicateStructField { field, outer } => format!(
            "field `{field}` is given twice{}, expected it once",
            outer.as_ref().map(|o| format!(" in `{o}`")).unwrap_or_default()
        ),
        E::InvalidValueForType { expected, found } => format!("found {found}, expected {expected}"),
        E::ExpectedFloat => "expected a number (such as 0.5)".to_owned(),
        E::ExpectedInteger => "expected a whole number (such as 48)".to_owned(),
        E::IntegerOutOfBounds => {
            "this whole number is too large (or negative where it may not be)".to_owned()
        }
        E::ExpectedString => "expected text in double quotes, such as \"Meninges\"".to_owned(),
        E::ExpectedOption => "expected `None`, `Some(...)` or a value".to_owned(),
        E::Eof => "the file ends too early: a closing bracket or a value is missing".to_owned(),
        E::TrailingCharacters => "unexpected text after the end of the scene".to_owned(),
        E::ExceededRecursionLimit => "nested too deeply".to_owned(),
        other => lower_first(&other.to_string()),
    };
    SceneError::Parse { path: path.to_path_buf(), line, column, message }
}

fn char_at(src: &str, line: usize, column: usize) -> Option<char> {
    src.split('\n').nth(line.checked_sub(1)?)?.chars().nth(column.checked_sub(1)?)
}

/// `; did you mean `x`?` for the closest name, when one is close.
fn did_you_mean<'a>(found: &str, names: impl Iterator<Item = &'a str>) -> String {
    names
        .map(|n| (edit_distance(found, n), n))
        .filter(|(d, n)| *d <= 2.max(n.chars().count() / 3))
        .min_by_key(|(d, _)| *d)
        .map(|(_, n)| format!("; did you mean `{n}`?"))
        .unwrap_or_default()
}

/// Levenshtein distance between two short names, ignoring case.
fn edit_distance(a: &str, b: &str) -> usize {
    let a: Vec<char> = a.to_lowercase().chars().collect();
    let b: Vec<char> = b.to_lowercase().chars().collect();
    let mut prev: Vec<usize> = (0..=b.len()).collect();
    let mut cur = vec![0; b.len() + 1];
    for (i, ca) in a.iter().enumerate() {
        cur[0] = i + 1;
        for (j, cb) in b.iter().enumerate() {
            let sub = prev[j] + usize::from(ca != cb);
            cur[j + 1] = sub.min(prev[j + 1] + 1).min(cur[j] + 1);
        }
        std::mem::swap(&mut prev, &mut cur);
    }
    prev[b.len()]
}

fn list(names: &[&str]) -> String {
    names.iter().map(|n| format!("`{n}`")).collect::<Vec<_>>().join(", ")
}

fn lower_first(s: &str) -> String {
    let mut c = s.chars();
    match c.next() {
        Some(f) => f.to_lowercase().chain(c).collect(),
        None => String::new(),
    }
}

/// A path to a value in a scene or script, with its text for messages (`a.b[2].c`).
#[derive(Clone, Debug, Default)]
pub(crate) struct FieldPath {
    segs: Vec<Seg>,
    text: String,
}

impl FieldPath {
    /// A field of this value.
    pub(crate) fn f(&self, name: &'static str) -> Self {
        let mut p = self.clone();
        p.segs.push(Seg::Field(name));
        if !p.text.is_empty() {
            p.text.push('.');
        }
        p.text.push_str(name);
        p
    }

    /// An item of this list or tuple.
    pub(crate) fn i(&self, index: usize) -> Self {
        let mut p = self.clone();
        p.segs.push(Seg::Index(index));
        p.text.push_str(&format!("[{index}]"));
        p
    }

    /// Into the single item of a newtype (`Name(..)`), without changing the text.
    pub(crate) fn inner(&self) -> Self {
        let mut p = self.clone();
        p.segs.push(Seg::Inner);
        p
    }

    /// A path that reads as `text` in messages.
    pub(crate) fn with_text(&self, text: String) -> Self {
        Self { segs: self.segs.clone(), text }
    }

    /// The text for messages.
    pub(crate) fn text(&self) -> &str {
        &self.text
    }
}

/// A semantic problem found by validation: which value, and what is wrong with it.
#[derive(Clone, Debug)]
pub(crate) struct Problem {
    pub(crate) at: FieldPath,
    pub(crate) message: String,
}

/// Shorthand for a failed check.
pub(crate) fn problem<T>(at: &FieldPath, message: impl Into<String>) -> Result<T, Problem> {
    Err(Problem { at: at.clone(), message: message.into() })
}

impl Problem {
    /// The error for `src`, read from `path`, with the position of the offending value.
    pub(crate) fn into_error(self, path: &std::path::Path, src: &str) -> SceneError {
        let Position { line, column } = Tree::parse(src).position(&self.at.segs);
        SceneError::Invalid {
            path: path.to_path_buf(),
            line,
            column,
            field: self.at.text,
            message: self.message,
        }
    }
}
