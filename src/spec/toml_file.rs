//! TOML files that report their faults where a user can find them: `path:line: key:
//! message`. `TomlText` keeps a file's text with its path and places a fault at a key
//! on the key's line; [`TomlFile`] reads a file into a type with it. The spec, its
//! `--set` overrides, its sweep values and the published values all locate keys here.
//! In: a path or a TOML text. Out: the value, or [`SpecError`]s.

use std::fmt;
use std::path::Path;
use toml::Spanned;
use toml::de::{DeTable, DeValue};

/// One fault in a spec, placed where a user can find it.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub struct SpecError {
    /// `path/to/spec.toml:14`, or `--set key=value`.
    pub location: String,
    /// Dotted key path such as `data.trajectories[2].samples`; empty for syntax errors.
    pub key: String,
    pub message: String,
}

impl fmt::Display for SpecError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.key.is_empty() {
            write!(f, "{}: {}", self.location, self.message)
        } else {
            write!(f, "{}: {}: {}", self.location, self.key, self.message)
        }
    }
}

/// Every fault found in a spec, one per line.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub struct SpecErrors(pub Vec<SpecError>);

/// The largest TOML file read: a spec with a hundred thousand values is a fraction of
/// it, and parsing it takes memory many times its size.
pub const MAX_TOML_BYTES: u64 = 4 << 20;

/// The most faults shown; the rest are counted, so that a spec with a hundred
/// thousand bad values gives a short answer.
pub const SHOWN_FAULTS: usize = 20;

impl fmt::Display for SpecErrors {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (i, fault) in self.0.iter().take(SHOWN_FAULTS).enumerate() {
            if i > 0 {
                f.write_str("\n")?;
            }
            write!(f, "{fault}")?;
        }
        match self.0.len().saturating_sub(SHOWN_FAULTS) {
            0 => Ok(()),
            1 => f.write_str("\n… and 1 more fault"),
            more => write!(f, "\n… and {more} more faults"),
        }
    }
}

/// `value` as a message shows it: whole when short, else its start and its length,
/// such as `[1, 2, 3, … (15000 values)]` for a long array.
pub fn shown_value(value: &str) -> String {
    const LONGEST: usize = 60;
    if value.chars().count() <= LONGEST {
        return value.to_string();
    }
    if let Ok(toml::Value::Array(items)) = value.parse::<toml::Value>().or_else(|_| {
        toml::from_str::<toml::Table>(&format!("value = {value}"))
            .map(|mut t| t.remove("value").unwrap_or(toml::Value::Boolean(false)))
    }) {
        let first: Vec<String> = items.iter().take(3).map(ToString::to_string).collect();
        let first = first.join(", ");
        if first.chars().count() <= LONGEST {
            return format!("[{first}, … ({} values)]", items.len());
        }
    }
    let start: String = value.chars().take(LONGEST / 2).collect();
    format!("{start}… ({} characters)", value.chars().count())
}

impl From<SpecError> for SpecErrors {
    fn from(fault: SpecError) -> Self {
        SpecErrors(vec![fault])
    }
}

/// A TOML text and the name its faults show it by (its path), which places a fault at
/// a key on the key's line.
#[derive(Debug, Clone)]
pub(super) struct TomlText {
    shown: String,
    text: String,
}

impl TomlText {
    /// Reads `path`; when it cannot, or it is larger than [`MAX_TOML_BYTES`], the fault
    /// reads `path: {unreadable}: {cause}`.
    pub fn read(path: &Path, unreadable: &str) -> Result<Self, SpecError> {
        use std::io::Read;
        let shown = path.display().to_string();
        let fault = |message: String| SpecError {
            location: shown.clone(),
            key: String::new(),
            message: format!("{unreadable}: {message}"),
        };
        let mut bytes = Vec::new();
        std::fs::File::open(path)
            .and_then(|file| file.take(MAX_TOML_BYTES + 1).read_to_end(&mut bytes))
            .map_err(|e| fault(e.to_string()))?;
        if bytes.len() as u64 > MAX_TOML_BYTES {
            return Err(fault(format!(
                "it is larger than {} MiB, the most a spec or published-values file may be (checking it would take memory many times its size); a spec lists values, not data: put recordings in files that data.trajectories names",
                MAX_TOML_BYTES >> 20
            )));
        }
        String::from_utf8(bytes)
            .map(|text| TomlText {
                shown: shown.clone(),
                text,
            })
            .map_err(|e| {
                let valid = e.utf8_error().valid_up_to();
                let bytes = e.as_bytes();
                let line = bytes[..valid].iter().filter(|&&b| b == b'\n').count() + 1;
                let column = valid - bytes[..valid].iter().rposition(|&b| b == b'\n').map_or(0, |i| i + 1) + 1;
                SpecError {
                    location: format!("{shown}:{line}"),
                    key: String::new(),
                    message: format!(
                        "{unreadable}: it is not UTF-8: byte 0x{:02x} at offset {valid} (line {line}, column {column}) starts no UTF-8 character; save the file as UTF-8",
                        bytes[valid]
                    ),
                }
            })
    }

    /// The name faults show the text by.
    pub fn shown(&self) -> &str {
        &self.shown
    }

    /// `path:line`, where a fault on `line` is shown.
    pub fn at_line(&self, line: usize) -> String {
        format!("{}:{line}", self.shown)
    }

    /// Whether the text is TOML; its syntax error is placed on the line it is found on.
    pub fn check_syntax(&self) -> Result<(), SpecError> {
        let Err(e) = DeTable::parse(&self.text) else {
            return Ok(());
        };
        let location = match e.span() {
            Some(span) => self.at_line(line_of(&self.text, span.start)),
            None => self.shown.clone(),
        };
        Err(SpecError {
            location,
            key: String::new(),
            message: e.message().trim().to_string(),
        })
    }

    /// The text as a TOML table; a value TOML cannot hold (an integer beyond 2⁶³ − 1)
    /// is a fault placed on its line and at its key.
    pub fn table(&self) -> Result<toml::Table, SpecError> {
        self.check_syntax()?;
        toml::from_str(&self.text).map_err(|e| {
            let Some(span) = e.span() else {
                return self.fault_of_file(e.message().trim());
            };
            let written = self.text[span.clone()].trim();
            let message = if written.replace('_', "").parse::<i128>().is_ok() {
                format!(
                    "{written} is larger than TOML's largest integer, {}",
                    i64::MAX
                )
            } else {
                e.message().trim().to_string()
            };
            let key = DeTable::parse(&self.text)
                .map(|root| key_at(root.get_ref(), span.start))
                .unwrap_or_default();
            SpecError {
                location: self.at_line(line_of(&self.text, span.start)),
                key,
                message,
            }
        })
    }

    /// A fault of the whole text, placed on no line and at no key.
    pub fn fault_of_file(&self, message: impl fmt::Display) -> SpecError {
        SpecError {
            location: self.shown.clone(),
            key: String::new(),
            message: message.to_string(),
        }
    }

    /// A fault at `key`, placed on the key's line (or its deepest parent's that is
    /// written; line 1 when the text is not TOML).
    pub fn fault(&self, key: &str, message: impl fmt::Display) -> SpecError {
        self.placer().fault(key, message)
    }

    /// The text parsed once, to place any number of faults without parsing it again.
    pub fn placer(&self) -> Placer<'_> {
        Placer {
            text: self,
            root: DeTable::parse(&self.text).ok(),
            line_starts: std::iter::once(0)
                .chain(self.text.match_indices('\n').map(|(i, _)| i + 1))
                .collect(),
        }
    }

    /// The line of the key at exactly `names` (one table key a step, dots and all),
    /// when the text writes it.
    pub fn written_line(&self, names: &[&str]) -> Option<usize> {
        let spans = DeTable::parse(&self.text).ok()?;
        let path: Vec<Step<'_>> = names.iter().map(|name| Step::Key(name)).collect();
        match find(&spans, &path) {
            (start, true) => Some(line_of(&self.text, start)),
            (_, false) => None,
        }
    }
}

/// A [`TomlText`] parsed once, with where its lines start: places each fault at a key
/// in time proportional to the key's depth, so many faults cost one parse.
pub(super) struct Placer<'a> {
    text: &'a TomlText,
    /// `None` when the text is not TOML.
    root: Option<Spanned<DeTable<'a>>>,
    /// The byte offset of each line's start, the first line's (0) first.
    line_starts: Vec<usize>,
}

impl Placer<'_> {
    /// A fault at `key`, placed on the key's line (or its deepest parent's that is
    /// written; line 1 when the text is not TOML).
    pub fn fault(&self, key: &str, message: impl fmt::Display) -> SpecError {
        let line = self
            .root
            .as_ref()
            .map_or(1, |root| self.line_at(span_of(root, key)));
        SpecError {
            location: self.text.at_line(line),
            key: key.to_string(),
            message: message.to_string(),
        }
    }

    /// Whether the text writes `key` (a dotted key path with indices).
    pub fn writes(&self, key: &str) -> bool {
        let Some(root) = &self.root else {
            return false;
        };
        steps(key).is_ok_and(|path| find(root, &path).1)
    }

    /// The 1-based line that byte `offset` is on, as [`line_of`] counts it.
    fn line_at(&self, offset: usize) -> usize {
        let text = &self.text.text;
        let offset = offset.min(text.len());
        let line = self.line_starts.partition_point(|&start| start <= offset);
        // `lines()` counts no empty line after a final newline.
        let lines = self.line_starts.len() - usize::from(text.ends_with('\n'));
        line.min(lines.max(1))
    }
}

/// `value` read into `T`; a value that does not fit comes back as its dotted key path
/// (empty for the whole value) and message.
pub(super) fn deserialize<T: serde::de::DeserializeOwned>(
    value: toml::Value,
) -> Result<T, (String, String)> {
    serde_path_to_error::deserialize(value).map_err(|e| {
        let key = e.path().to_string();
        let key = if key == "." { String::new() } else { key };
        let message = shortened_quotes(e.into_inner().message());
        (with_missing_field(key, &message), message)
    })
}

/// `message` with each value it quotes from the file (`"…"` or `` `…` ``) longer than
/// [`shown_value`] shows whole cut to its start and its length, so that a long string
/// in a spec gives a short message.
fn shortened_quotes(message: &str) -> String {
    let mut shortened = String::with_capacity(message.len().min(1024));
    let mut rest = message;
    while let Some(open) = rest.find(['"', '`']) {
        let quote = rest[open..].chars().next().unwrap_or('"');
        let inner = &rest[open + 1..];
        // A quote inside a `"…"` value is written escaped, `\"`.
        let mut escaped = false;
        let close = inner.char_indices().find_map(|(i, c)| {
            let end = c == quote && !escaped;
            escaped = quote == '"' && c == '\\' && !escaped;
            end.then_some(i)
        });
        let Some(close) = close else { break };
        shortened.push_str(&rest[..=open]);
        shortened.push_str(&shown_value(&inner[..close]));
        shortened.push(quote);
        rest = &inner[close + 1..];
    }
    shortened.push_str(rest);
    shortened
}

/// `key` with the field that `message` says is missing appended (`calibration` and
/// ``missing field `trajectory` `` give `calibration.trajectory`): the key to add.
fn with_missing_field(key: String, message: &str) -> String {
    let field = message
        .strip_prefix("missing field `")
        .and_then(|rest| rest.strip_suffix('`'));
    match field {
        None => key,
        Some(field) if key.is_empty() => field.to_string(),
        Some(field) => format!("{key}.{field}"),
    }
}

/// A TOML data file read into `T`, kept with its text so that later checks can name
/// the line of a key.
pub struct TomlFile<T> {
    pub value: T,
    source: TomlText,
}

impl<T: serde::de::DeserializeOwned> TomlFile<T> {
    /// Reads `path`; a fault reads `path:line: key: message`.
    pub fn read(path: &Path) -> Result<Self, SpecError> {
        let source = TomlText::read(path, "cannot read it")?;
        let table = source.table()?;
        let value = deserialize(toml::Value::Table(table))
            .map_err(|(key, message)| source.fault(&key, message))?;
        Ok(TomlFile { value, source })
    }
}

impl<T> TomlFile<T> {
    /// A fault at `key`, placed on the key's line.
    pub fn fault(&self, key: &str, message: impl fmt::Display) -> SpecError {
        self.source.fault(key, message)
    }
}

/// One step of a key path.
#[derive(Debug, PartialEq)]
pub(super) enum Step<'a> {
    Key(&'a str),
    Index(usize),
}

/// Splits `data.trajectories[2].samples` (or `data.trajectories.2.samples`) into steps.
pub(super) fn steps(key: &str) -> Result<Vec<Step<'_>>, String> {
    let mut steps = Vec::new();
    for part in key.split('.') {
        let (name, indices) = part
            .split_once('[')
            .map_or((part, ""), |(name, rest)| (name, rest));
        if let Ok(index) = name.parse::<usize>() {
            steps.push(Step::Index(index));
        } else if !name.is_empty() {
            steps.push(Step::Key(name));
        } else if indices.is_empty() {
            return Err(format!("{key:?} has an empty key segment"));
        }
        for index in indices.split('[').filter(|s| !s.is_empty()) {
            let index = index
                .strip_suffix(']')
                .and_then(|i| i.parse().ok())
                .ok_or_else(|| format!("{key:?}: bad index [{index}"))?;
            steps.push(Step::Index(index));
        }
    }
    Ok(steps)
}

/// Byte offset where `key` (or its deepest existing parent) is written in the spec.
fn span_of(root: &Spanned<DeTable<'_>>, key: &str) -> usize {
    steps(key).map_or(0, |path| find(root, &path).0)
}

/// Where `path` is written: the byte offset of its deepest step that the text has (0
/// for none), and whether the text has every step.
fn find(root: &Spanned<DeTable<'_>>, path: &[Step<'_>]) -> (usize, bool) {
    let mut best = 0;
    let mut table = Some(root.get_ref());
    let mut array: Option<&[Spanned<DeValue<'_>>]> = None;
    for step in path {
        let found = match (step, table, array) {
            (Step::Key(k), Some(t), _) => t
                .iter()
                .find(|(name, _)| name.get_ref() == k)
                .map(|(name, value)| (name.span().start, value)),
            (Step::Index(i), _, Some(a)) => a.get(*i).map(|value| (value.span().start, value)),
            _ => None,
        };
        let Some((start, value)) = found else {
            return (best, false);
        };
        best = start;
        (table, array) = match value.get_ref() {
            DeValue::Table(t) => (Some(t), None),
            DeValue::Array(a) => (None, Some(&a[..])),
            _ => (None, None),
        };
    }
    (best, true)
}

/// The dotted key path of the value written at byte `offset`: at each level the
/// entry that starts last before it (a table's keys follow its header, an array's
/// items follow each other).
fn key_at(table: &DeTable<'_>, offset: usize) -> String {
    let Some((name, mut value)) = table
        .iter()
        .filter(|(name, _)| name.span().start <= offset)
        .max_by_key(|(name, _)| name.span().start)
    else {
        return String::new();
    };
    let mut path = name.get_ref().to_string();
    loop {
        match value.get_ref() {
            DeValue::Table(t) => {
                let inner = key_at(t, offset);
                if !inner.is_empty() {
                    path = format!("{path}.{inner}");
                }
                return path;
            }
            DeValue::Array(items) => {
                let Some(i) = items.iter().rposition(|item| item.span().start <= offset) else {
                    return path;
                };
                path = format!("{path}[{i}]");
                value = &items[i];
            }
            _ => return path,
        }
    }
}

/// The 1-based line that byte `offset` of `text` is on; the last line for the end of
/// a text that ends with a newline.
fn line_of(text: &str, offset: usize) -> usize {
    let line = text[..offset.min(text.len())].matches('\n').count() + 1;
    line.min(text.lines().count().max(1))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn long_quoted_values_are_cut_short_and_short_ones_kept() {
        let long = "x".repeat(5_000);
        let message = format!("invalid type: string \"{long}\", expected f64");
        assert_eq!(
            shortened_quotes(&message),
            format!(
                "invalid type: string \"{}… (5000 characters)\", expected f64",
                "x".repeat(30)
            )
        );
        let message = format!("unknown variant `{long}`, expected `relu` or `tanh`");
        assert!(
            shortened_quotes(&message).ends_with("… (5000 characters)`, expected `relu` or `tanh`")
        );
        let escaped = format!("string \"a\\\"{long}\", expected f64");
        assert!(shortened_quotes(&escaped).ends_with("(5003 characters)\", expected f64"));
        for kept in [
            "invalid type: string \"S1\", expected f64",
            "an \"unclosed quote",
            "",
        ] {
            assert_eq!(shortened_quotes(kept), kept);
        }
    }

    #[test]
    fn keys_are_found_on_their_lines() {
        let text = "name = \"x\"\n\n[calibration]\nruns = 3\nwindow_sizes_s = [1, 2]\n\n[[dvl]]\nname = \"a\"\n[[dvl]]\nname = \"b\"\nnoise = 1\n";
        let spans = DeTable::parse(text).unwrap();
        assert_eq!(
            line_of(text, span_of(&spans, "calibration.window_sizes_s")),
            5
        );
        assert_eq!(line_of(text, span_of(&spans, "dvl[1].noise")), 11);
        // A missing key points at its deepest parent that exists.
        assert_eq!(line_of(text, span_of(&spans, "calibration.missing")), 3);
    }
}
