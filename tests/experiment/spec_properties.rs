//! Property tests of the spec loader (`spec::load_experiment`): whatever TOML value a
//! spec holds at any of its keys, the loader returns — it never panics, never aborts
//! and never hangs — and every refusal names where to look: `file:line` (or the
//! `--set KEY=VALUE` it came from) and the key, only a TOML syntax error having no key.
//! The specs start from experiments/quick.toml, paper.toml (beside empty stand-ins for
//! its recordings) and own-recording.toml, and quick.toml with a `[sweep]`; each case
//! changes one or two of their keys (every table, array and value, found by walking the
//! parsed file) to a random TOML value, deletes one, adds a known or unknown key to a
//! table or an element to an array, or writes a grid axis as a random range; the `--set`
//! path gets random keys and raw values, and the text path random text on one line
//! (numbers beyond 64 bits and trajectories of 10¹² samples included).
//! `PROPTEST_CASES=20000` searches longer.

use dcnet_exp::spec::{SpecError, SpecErrors, load_experiment};
use proptest::prelude::*;
use proptest::sample::Index;
use proptest::test_runner::{Config, TestCaseError, TestRunner};
use std::path::{Path, PathBuf};
use std::sync::mpsc;
use std::time::Duration;
use toml::Value;

/// Longer than any load takes, on a machine as busy as CI's (a load takes
/// milliseconds); a load still running then is a hang.
const LOAD_LIMIT: Duration = Duration::from_secs(60);

/// The specs the cases start from, written into a temporary folder with the files
/// they name.
struct Fixture {
    _dir: tempfile::TempDir,
    /// experiments/ in the temporary folder, where every case's spec is written.
    folder: PathBuf,
    bases: Vec<(&'static str, toml::Table)>,
    /// The bases' texts as written, for the text path.
    texts: Vec<String>,
    /// Every key name the bases use, and the optional ones they leave out.
    names: Vec<String>,
}

/// Keys of the spec that no base writes.
const OPTIONAL_KEYS: &[&str] = &[
    "file",
    "samples",
    "columns",
    "synthetic_duration_s",
    "published_windows",
    "early_stopping",
    "patience_epochs",
    "min_improvement",
    "report",
    "published",
    "tolerance_pct",
    "velocity_trajectories",
    "start",
    "stop",
    "step",
    "values",
    "sweep",
    "sample",
    "sample_seed",
    "EM1",
    "EM5",
];

const SWEEP: &str = "\n[sweep]\nsample = 3\n[sweep.values]\n\"model.conv_channels\" = [8, 16]\ntraining.learning_rate = [1e-4, 1e-3]\n";

impl Fixture {
    fn new() -> Fixture {
        let repo = Path::new(env!("CARGO_MANIFEST_DIR"));
        let dir = tempfile::tempdir().unwrap();
        let folder = dir.path().join("experiments");
        std::fs::create_dir_all(folder.join("published")).unwrap();
        std::fs::create_dir_all(folder.join("recordings")).unwrap();
        std::fs::create_dir_all(dir.path().join("data/snapir")).unwrap();
        for file in ["published/dcnet-paper.toml", "recordings/auv-survey.csv"] {
            std::fs::copy(repo.join("experiments").join(file), folder.join(file)).unwrap();
        }
        // The loader checks that a recording exists; it reads it only to run.
        for file in ["V.npy", "V_test.npy"] {
            std::fs::write(dir.path().join("data/snapir").join(file), "").unwrap();
        }
        let read =
            |name: &str| std::fs::read_to_string(repo.join("experiments").join(name)).unwrap();
        let texts = vec![
            read("quick.toml"),
            read("paper.toml"),
            read("own-recording.toml"),
            read("quick.toml") + SWEEP,
        ];
        let labels = ["quick", "paper", "own-recording", "quick-sweep"];
        let bases: Vec<(&'static str, toml::Table)> = labels
            .into_iter()
            .zip(&texts)
            .map(|(label, text)| (label, toml::from_str(text).unwrap()))
            .collect();
        let mut names: Vec<String> = OPTIONAL_KEYS.iter().map(ToString::to_string).collect();
        for (_, table) in &bases {
            for path in node_paths(&Value::Table(table.clone())) {
                if let Some(Seg::Key(name)) = path.last() {
                    names.push(name.clone());
                }
            }
        }
        names.sort();
        names.dedup();
        let fixture = Fixture {
            _dir: dir,
            folder,
            bases,
            texts,
            names,
        };
        for (i, text) in fixture.texts.iter().enumerate() {
            let path = fixture.write(&format!("base-{i}"), text);
            if let Err(errors) = load_experiment(&path, &[]) {
                panic!("base {} does not load:\n{errors}", fixture.bases[i].0);
            }
        }
        fixture
    }

    /// Writes `text` as `<name>.toml` beside the bases.
    fn write(&self, name: &str, text: &str) -> PathBuf {
        let path = self.folder.join(format!("{name}.toml"));
        std::fs::write(&path, text).unwrap();
        path
    }
}

/// One step of a path into a TOML value.
#[derive(Debug, Clone, PartialEq)]
enum Seg {
    Key(String),
    Index(usize),
}

/// `path` as `--set` and the loader's messages write it: `data.trajectories[2].name`.
fn render(path: &[Seg]) -> String {
    let mut text = String::new();
    for seg in path {
        match seg {
            Seg::Key(k) if text.is_empty() => text.push_str(k),
            Seg::Key(k) => text.push_str(&format!(".{k}")),
            Seg::Index(i) => text.push_str(&format!("[{i}]")),
        }
    }
    text
}

/// The path of every table, array and value below `root`, parents first.
fn node_paths(root: &Value) -> Vec<Vec<Seg>> {
    fn walk(value: &Value, path: &mut Vec<Seg>, found: &mut Vec<Vec<Seg>>) {
        let children: Vec<(Seg, &Value)> = match value {
            Value::Table(t) => t.iter().map(|(k, v)| (Seg::Key(k.clone()), v)).collect(),
            Value::Array(a) => a
                .iter()
                .enumerate()
                .map(|(i, v)| (Seg::Index(i), v))
                .collect(),
            _ => Vec::new(),
        };
        for (seg, child) in children {
            path.push(seg);
            found.push(path.clone());
            walk(child, path, found);
            path.pop();
        }
    }
    let mut found = Vec::new();
    walk(root, &mut Vec::new(), &mut found);
    found
}

fn get_mut<'a>(mut value: &'a mut Value, path: &[Seg]) -> Option<&'a mut Value> {
    for seg in path {
        value = match (seg, value) {
            (Seg::Key(k), Value::Table(t)) => t.get_mut(k)?,
            (Seg::Index(i), Value::Array(a)) => a.get_mut(*i)?,
            _ => return None,
        };
    }
    Some(value)
}

/// A change to a spec; each index picks among the paths the spec has when it applies.
#[derive(Debug, Clone)]
enum Mutation {
    Replace(Index, Value),
    Delete(Index),
    /// A key added to a table (the whole spec included).
    Add(Index, String, Value),
    /// An element added to an array.
    Push(Index, Value),
    /// A grid axis written as `{ start, stop, step }`.
    Range(Index, Value, Value, Value),
}

impl Mutation {
    /// Applies the change to `spec`; what it did, for the report of a failing case.
    fn apply(&self, spec: &mut Value) -> String {
        let paths = node_paths(spec);
        let kind = |want: fn(&Value) -> bool, spec: &Value| -> Vec<Vec<Seg>> {
            let mut found = vec![Vec::new()];
            found.extend(paths.iter().cloned());
            found
                .into_iter()
                .filter(|p| get_path(spec, p).is_some_and(want))
                .collect()
        };
        match self {
            Mutation::Replace(at, value) => {
                let path = &paths[at.index(paths.len())];
                *get_mut(spec, path).unwrap() = value.clone();
                format!("{} = {value}", render(path))
            }
            Mutation::Delete(at) => {
                let path = &paths[at.index(paths.len())];
                let (last, parent) = path.split_last().unwrap();
                match (get_mut(spec, parent).unwrap(), last) {
                    (Value::Table(t), Seg::Key(k)) => drop(t.remove(k)),
                    (Value::Array(a), Seg::Index(i)) => drop(a.remove(*i)),
                    _ => unreachable!(),
                }
                format!("{} deleted", render(path))
            }
            Mutation::Add(at, name, value) => {
                let tables = kind(Value::is_table, spec);
                let path = &tables[at.index(tables.len())];
                let table = get_mut(spec, path).unwrap().as_table_mut().unwrap();
                table.insert(name.clone(), value.clone());
                format!("{:?} added to [{}] = {value}", name, render(path))
            }
            Mutation::Push(at, value) => {
                let arrays = kind(Value::is_array, spec);
                if arrays.is_empty() {
                    return "no array to push to".into();
                }
                let path = &arrays[at.index(arrays.len())];
                let array = get_mut(spec, path).unwrap().as_array_mut().unwrap();
                array.push(value.clone());
                format!("{value} pushed to {}", render(path))
            }
            Mutation::Range(at, start, stop, step) => {
                let axis = ["scale_pct", "bias_cm_s", "noise_cm_s"][at.index(3)];
                let Some(Value::Table(grid)) = get_mut(spec, &[Seg::Key("grid".into())]) else {
                    return "no grid".into();
                };
                let range: toml::Table = [("start", start), ("stop", stop), ("step", step)]
                    .into_iter()
                    .map(|(k, v)| (k.to_string(), v.clone()))
                    .collect();
                grid.insert(axis.into(), Value::Table(range));
                format!("grid.{axis} = {{ start = {start}, stop = {stop}, step = {step} }}")
            }
        }
    }
}

fn get_path<'a>(mut value: &'a Value, path: &[Seg]) -> Option<&'a Value> {
    for seg in path {
        value = match (seg, value) {
            (Seg::Key(k), Value::Table(t)) => t.get(k)?,
            (Seg::Index(i), Value::Array(a)) => a.get(*i)?,
            _ => return None,
        };
    }
    Some(value)
}

fn integer() -> impl Strategy<Value = i64> {
    prop_oneof![
        prop::sample::select(vec![
            i64::MIN,
            i64::MIN + 1,
            -1,
            0,
            1,
            2,
            3,
            16,
            64,
            i64::MAX
        ]),
        -1000i64..100_000,
        any::<i64>(),
    ]
}

fn float() -> impl Strategy<Value = f64> {
    prop_oneof![
        prop::sample::select(vec![
            0.0,
            -0.0,
            f64::MIN_POSITIVE,
            5e-324,
            1e-300,
            1e-8,
            0.5,
            0.999_999_9,
            1.0,
            89.999,
            1e300,
            -1e300,
            f64::MAX,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
        ]),
        -1e4..1e4f64,
        any::<f64>(),
    ]
}

fn number() -> impl Strategy<Value = Value> {
    prop_oneof![
        integer().prop_map(Value::Integer),
        float().prop_map(Value::Float)
    ]
}

/// Text of `length` characters drawn from `chars`.
fn text(
    chars: impl Strategy<Value = char>,
    length: std::ops::RangeInclusive<usize>,
) -> impl Strategy<Value = String> {
    prop::collection::vec(chars, length).prop_map(String::from_iter)
}

/// Any character that is not a control character.
fn printable() -> impl Strategy<Value = char> {
    any::<char>().prop_filter("a control character", |c| !c.is_control())
}

fn string() -> impl Strategy<Value = String> {
    prop_oneof![
        prop::sample::select(vec![
            "",
            " ",
            "\n",
            "ü名🚀",
            "a/b",
            "../..",
            "/",
            ".",
            "..",
            ".cache",
            "a.b",
            "x.csv",
            "S1",
            "SCal",
            "T10Cal",
            "dcnet",
            "floor",
            "EM3",
            "EM6",
            "flex",
            "ndarray",
            "tanh",
            "leaky_relu",
        ])
        .prop_map(String::from),
        Just("x".repeat(1000)),
        text(printable(), 0..=16),
    ]
}

fn datetime() -> impl Strategy<Value = toml::value::Datetime> {
    prop::sample::select(vec![
        "1979-05-27T07:32:00Z",
        "1979-05-27T00:32:00.999999-07:00",
        "1979-05-27T07:32:00",
        "1979-05-27",
        "07:32:00",
    ])
    .prop_map(|text| text.parse().unwrap())
}

fn scalar() -> impl Strategy<Value = Value> {
    prop_oneof![
        3 => number(),
        2 => string().prop_map(Value::String),
        1 => any::<bool>().prop_map(Value::Boolean),
        1 => datetime().prop_map(Value::Datetime),
    ]
}

/// A key name: one a spec uses, or any other.
fn key_name(names: &[String]) -> BoxedStrategy<String> {
    prop_oneof![
        3 => prop::sample::select(names.to_vec()),
        1 => text(prop_oneof![prop::char::range('a', 'z'), Just('_')], 1..=10),
        // Not "": a fault at a key named "" has no key to name.
        1 => prop::sample::select(vec![" ", "a.b", "ü", "EM6"]).prop_map(String::from),
    ]
    .boxed()
}

/// Any TOML value: scalars, and arrays (empty, mixed, nested) and inline tables of them.
fn value(names: &[String]) -> BoxedStrategy<Value> {
    let key = key_name(names);
    scalar()
        .prop_recursive(3, 24, 4, move |inner| {
            prop_oneof![
                prop::collection::vec(inner.clone(), 0..4).prop_map(Value::Array),
                prop::collection::vec((key.clone(), inner), 0..4)
                    .prop_map(|entries| Value::Table(entries.into_iter().collect())),
            ]
        })
        .boxed()
}

fn mutation(names: &[String]) -> impl Strategy<Value = Mutation> + use<> {
    let value = value(names);
    prop_oneof![
        6 => (any::<Index>(), value.clone()).prop_map(|(at, v)| Mutation::Replace(at, v)),
        1 => any::<Index>().prop_map(Mutation::Delete),
        2 => (any::<Index>(), key_name(names), value.clone())
            .prop_map(|(at, name, v)| Mutation::Add(at, name, v)),
        1 => (any::<Index>(), value).prop_map(|(at, v)| Mutation::Push(at, v)),
        1 => (any::<Index>(), number(), number(), number())
            .prop_map(|(at, start, stop, step)| Mutation::Range(at, start, stop, step)),
    ]
}

/// What loading `path` with `overrides` came to: its result, or how it failed to
/// return one.
fn load_in_time(path: &Path, overrides: &[String]) -> Result<Result<(), SpecErrors>, String> {
    let (send, receive) = mpsc::channel();
    let (path, overrides) = (path.to_path_buf(), overrides.to_vec());
    std::thread::spawn(move || {
        let loaded = std::panic::catch_unwind(|| load_experiment(&path, &overrides).map(|_| ()));
        let _ = send.send(loaded.map_err(|panic| {
            panic
                .downcast_ref::<String>()
                .cloned()
                .or_else(|| panic.downcast_ref::<&str>().map(ToString::to_string))
                .unwrap_or_default()
        }));
    });
    match receive.recv_timeout(LOAD_LIMIT) {
        Ok(Ok(loaded)) => Ok(loaded),
        Ok(Err(panic)) => Err(format!("the loader panicked: {panic}")),
        Err(_) => Err(format!("the loader took more than {LOAD_LIMIT:?}")),
    }
}

/// Whether `fault` is placed where a user can find it: on a line of `text` written at
/// `path`, or at the `--set` it came from; and at a key, unless `text` is not TOML.
fn placed(fault: &SpecError, path: &Path, text: &str, overrides: &[String]) -> bool {
    let SpecError { location, key, .. } = fault;
    if let Some(assignment) = location.strip_prefix("--set ") {
        // A long value is shown by its start, `…` and its length, after its key.
        let key_of = |a: &str| a.split_once('=').map(|(key, _)| key.to_string());
        return overrides.iter().any(|o| {
            o == assignment
                || (assignment.contains('…') && o.len() > 60 && key_of(o) == key_of(assignment))
        });
    }
    let syntax_error = text.parse::<toml::Table>().is_err();
    let Some(rest) = location.strip_prefix(&format!("{}:", path.display())) else {
        return false;
    };
    let digits = rest.len() - rest.trim_start_matches(|c: char| c.is_ascii_digit()).len();
    let (line, after) = rest.split_at(digits);
    let on_a_line = line
        .parse::<usize>()
        .is_ok_and(|line| line >= 1 && line <= text.lines().count().max(1));
    let point = after.is_empty() || after.starts_with(" (sweep point ");
    let well_formed = !key.contains("..") && !key.ends_with('.');
    on_a_line && point && well_formed && (syntax_error || !key.is_empty())
}

/// Loads `text` with `overrides`: the case fails on a panic, a hang, or a fault not
/// placed on a line and a key.
fn check(
    fixture: &Fixture,
    name: &str,
    text: &str,
    overrides: &[String],
    done: &str,
) -> Result<(), TestCaseError> {
    let path = fixture.write(name, text);
    let describe = || format!("after {done}, with --set {overrides:?}, the spec\n{text}\n");
    match load_in_time(&path, overrides) {
        Err(failure) => Err(TestCaseError::fail(format!("{failure} {}", describe()))),
        Ok(Ok(())) => Ok(()),
        Ok(Err(SpecErrors(faults))) => {
            match faults.iter().find(|f| !placed(f, &path, text, overrides)) {
                Some(fault) => Err(TestCaseError::fail(format!(
                    "a fault names no line or key: {fault:?} {}",
                    describe()
                ))),
                None => Ok(()),
            }
        }
    }
}

/// A runner of `cases` cases, or of `PROPTEST_CASES` for a longer search.
fn runner(cases: u32) -> TestRunner {
    let cases = std::env::var("PROPTEST_CASES")
        .ok()
        .and_then(|n| n.parse().ok())
        .unwrap_or(cases);
    TestRunner::new(Config {
        cases,
        failure_persistence: None,
        max_shrink_iters: 10_000,
        ..Config::default()
    })
}

fn run<S: Strategy>(cases: u32, strategy: S, test: impl Fn(S::Value) -> Result<(), TestCaseError>) {
    if let Err(failure) = runner(cases).run(&strategy, test) {
        panic!("{failure}");
    }
}

#[test]
fn any_value_at_any_key_loads_or_is_refused_at_its_line_and_key() {
    let fixture = Fixture::new();
    let bases = fixture.bases.len();
    let strategy = (
        0..bases,
        prop::collection::vec(mutation(&fixture.names), 1..=2),
    );
    run(300, strategy, |(base, mutations)| {
        let mut spec = Value::Table(fixture.bases[base].1.clone());
        let done: Vec<String> = mutations.iter().map(|m| m.apply(&mut spec)).collect();
        let text = toml::to_string(&spec).unwrap();
        let done = format!("{} on {}", done.join("; "), fixture.bases[base].0);
        check(&fixture, "values", &text, &[], &done)
    });
}

/// A raw `--set` value: any TOML value as written, or any text.
fn raw_value(names: &[String]) -> impl Strategy<Value = String> + use<> {
    prop_oneof![
        2 => value(names).prop_map(|v| v.to_string()),
        1 => prop::sample::select(vec![
            "", "=", "[", "]]", "{", "\"", "'''", "1e400", "a=b", "0x10", "1_000", "+inf",
            "-nan", "[1,", "{a=1", "1\n[data]", "\"open",
        ])
        .prop_map(String::from),
        1 => text(printable(), 0..=20),
    ]
}

/// The value the loader reads from a raw `--set` value: its TOML, or the text itself.
fn read_as_the_loader_does(raw: &str) -> Value {
    toml::from_str::<toml::Table>(&format!("value = {raw}"))
        .ok()
        .and_then(|mut t| t.remove("value"))
        .unwrap_or_else(|| Value::String(raw.to_string()))
}

#[test]
fn any_set_loads_or_is_refused_at_its_set_and_key() {
    let fixture = Fixture::new();
    let bases = fixture.bases.len();
    let names = fixture.names.clone();
    let assignment = (
        any::<Index>(),
        prop_oneof![4 => Just(None), 1 => text(printable(), 0..=12).prop_map(Some)],
        raw_value(&names),
    );
    let strategy = (0..bases, prop::collection::vec(assignment, 1..=2));
    run(150, strategy, |(base, assignments)| {
        let table = &fixture.bases[base].1;
        let paths = node_paths(&Value::Table(table.clone()));
        let mut spec = Value::Table(table.clone());
        let mut overrides = Vec::new();
        for (at, key, raw) in assignments {
            let path = &paths[at.index(paths.len())];
            if key.is_none()
                && let Some(place) = get_mut(&mut spec, path)
            {
                *place = read_as_the_loader_does(&raw);
            }
            let key = key.unwrap_or_else(|| render(path));
            overrides.push(format!("{key}={raw}"));
        }
        let text = &fixture.texts[base];
        check(&fixture, "set", text, &overrides, fixture.bases[base].0)
    });
}

/// Text for a line: pieces of TOML, or any text.
fn raw_line() -> impl Strategy<Value = String> {
    let piece = prop_oneof![
        prop::sample::select(vec![
            "[",
            "]",
            "[[",
            "]]",
            "=",
            "\"",
            "'''",
            "\"\"\"",
            "{",
            "}",
            ",",
            ".",
            "#",
            "1e400",
            "inf",
            "nan",
            "x",
            "data",
            "name",
            "1979-05-27",
            "\\u0000",
            "\t",
            "[data]",
            "[[dvl]]",
            "S1",
        ])
        .prop_map(String::from),
        text(prop::char::range('0', '9'), 1..=18),
        text(printable(), 0..=8),
    ];
    prop::collection::vec(piece, 0..6).prop_map(|pieces| pieces.concat())
}

#[test]
fn any_text_on_a_line_loads_or_is_refused_at_its_line() {
    let fixture = Fixture::new();
    let bases = fixture.bases.len();
    let strategy = (0..bases, any::<Index>(), any::<bool>(), raw_line());
    run(150, strategy, |(base, at, whole, raw)| {
        let text = &fixture.texts[base];
        let mut lines: Vec<String> = text.lines().map(String::from).collect();
        let line = at.index(lines.len());
        let replaced = match lines[line].split_once('=') {
            Some((key, _)) if !whole => format!("{key}= {raw}"),
            _ => raw.clone(),
        };
        lines[line] = replaced.clone();
        let text = lines.join("\n") + "\n";
        let done = format!("line {} written as {replaced:?}", line + 1);
        check(&fixture, "text", &text, &[], &done)
    });
}

/// Base `base` with `edit` applied to its text, written beside the bases; the faults
/// loading it gives, as `(location line, key, message)`.
fn faults_in(
    fixture: &Fixture,
    base: usize,
    edit: impl Fn(&str) -> String,
) -> Vec<(usize, String, String)> {
    let text = edit(&fixture.texts[base]);
    let path = fixture.write("regression", &text);
    let SpecErrors(faults) = load_experiment(&path, &[]).unwrap_err();
    let prefix = format!("{}:", path.display());
    faults
        .into_iter()
        .map(|f| {
            let line = f.location.strip_prefix(&prefix).unwrap().parse().unwrap();
            (line, f.key, f.message)
        })
        .collect()
}

/// The faults of quick.toml with `edit` applied, as [`faults_in`] gives them.
fn faults_of(fixture: &Fixture, edit: impl Fn(&str) -> String) -> Vec<(usize, String, String)> {
    faults_in(fixture, 0, edit)
}

fn line_of(text: &str, needle: &str) -> usize {
    text.lines().position(|l| l.contains(needle)).unwrap() + 1
}

// Found by the properties above: a grid range of more values than memory holds
// panicked (capacity overflow) or aborted (allocation failure) while expanding.
#[test]
fn a_grid_range_of_too_many_values_is_refused() {
    let fixture = Fixture::new();
    let axis = "scale_pct = { values = [0.5, 1.0, 1.5] }";
    let line = line_of(&fixture.texts[0], axis);
    for range in [
        "{ start = -1e300, stop = -9223372036854775808, step = 1 }",
        "{ start = 0, stop = 1e12, step = 1 }",
        "{ start = 0, stop = 1e300, step = 1e-300 }",
    ] {
        let faults = faults_of(&fixture, |t| {
            t.replace(axis, &format!("scale_pct = {range}"))
        });
        assert_eq!(faults.len(), 1, "{faults:?}");
        let (at, key, message) = &faults[0];
        assert_eq!((*at, key.as_str()), (line, "grid.scale_pct"), "{message}");
        assert!(
            message.contains("values is above 10000 values"),
            "{message}"
        );
    }
}

// Found by the properties above: a missing key was reported at its table's key (no key
// at all for a top-level one) and a missing `[sweep]` key as `sweep..`.
#[test]
fn a_missing_key_is_named() {
    let fixture = Fixture::new();
    let quick = &fixture.texts[0];
    let faults = faults_of(&fixture, |t| t.replace("name = \"quick\"\n", ""));
    assert_eq!(faults, [(1, "name".into(), "missing field `name`".into())]);
    let faults = faults_of(&fixture, |t| t.replace("trajectory = \"SCal\"\n", ""));
    let calibration = line_of(quick, "[calibration]");
    assert_eq!(faults[0].0, calibration);
    assert_eq!(faults[0].1, "calibration.trajectory");
    let faults = faults_of(&fixture, |t| format!("{t}\n[sweep]\nsample = 1\n"));
    let sweep = line_of(&format!("{quick}\n[sweep]\n"), "[sweep]");
    assert_eq!(
        faults,
        [(
            sweep,
            "sweep.values".into(),
            "missing field `values`".into()
        )]
    );
}

// Found by the properties above: a syntax error found at the end of the text was placed
// on the line after the last.
#[test]
fn a_syntax_error_at_the_end_is_placed_on_the_last_line() {
    let fixture = Fixture::new();
    let faults = faults_of(&fixture, |t| format!("\'\'\'\n{t}"));
    let lines = fixture.texts[0].lines().count() + 1;
    assert_eq!(faults.len(), 1, "{faults:?}");
    assert_eq!(faults[0].0, lines, "{faults:?}");
    assert_eq!(faults[0].1, "");
}

// Found by the properties above: the length of a recording's sample range that ends
// before it starts wrapped around to nearly 2^64 samples, whose windows the split check
// then counted one by one (for ever, in effect; a panic in a debug build).
#[test]
fn a_sample_range_that_ends_before_it_starts_is_refused() {
    let fixture = Fixture::new();
    let faults = faults_in(&fixture, 1, |t| t.replace("[1339, 2566]", "[2566, 1339]"));
    let line = line_of(&fixture.texts[1], "[1339, 2566]");
    assert_eq!(
        faults,
        [(
            line,
            "data.trajectories[1].samples".into(),
            "[2566, 1339] is empty: start must be below end".into()
        )]
    );
}
