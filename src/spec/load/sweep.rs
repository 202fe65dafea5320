//! A spec's `[sweep]`. In: the spec's table without its `[sweep]`, the sweep table,
//! and where each key was written or set. Out: an [`Experiment`] of the chosen points
//! (the whole product of the swept values in order, or a sample drawn from a seed),
//! each point's spec checked and named `<name>/<point>` by its values; or the faults of
//! all points, each once and placed on the line of the sweep value that caused it.

use super::overrides::set_in;
use super::source::{Assigned, SpecSource};
use super::{Experiment, Point};
use crate::spec::file::SweepFile;
use crate::spec::toml_file::{SpecError, SpecErrors, TomlText, deserialize, steps};
use std::collections::HashSet;

/// Every chosen point of `sweep` over `table`, each checked; the faults of all points,
/// each once.
pub(super) fn load_sweep<S>(
    source: SpecSource,
    table: toml::Table,
    sweep: toml::Value,
    assigned: Assigned,
    check: impl Fn(&SpecSource, toml::Table, &Assigned) -> Result<S, SpecErrors>,
) -> Result<Experiment<S>, SpecErrors> {
    let sweep: SweepFile = deserialize(sweep).map_err(|(key, message)| {
        let key = if key.is_empty() {
            "sweep".into()
        } else {
            format!("sweep.{key}")
        };
        source.locate(&assigned, key, message)
    })?;
    let axes = sweep_axes(&sweep.values, &source.text).map_err(|SpecErrors(faults)| {
        // Values given with `--set` are placed there, not on a line of the file.
        SpecErrors(
            faults
                .into_iter()
                .map(|fault| match assigned.origin(&fault.key) {
                    Some(origin) => SpecError {
                        location: origin.to_string(),
                        ..fault
                    },
                    None => fault,
                })
                .collect(),
        )
    })?;
    let chosen = chosen_points(&sweep, &axes, &table)
        .map_err(|message| source.locate(&assigned, "sweep.sample".into(), message))?;
    let name = table
        .get("name")
        .and_then(|n| n.as_str())
        .unwrap_or_default()
        .to_string();
    let mut points = SweepPoints::new(&check);
    for index in chosen {
        let picks = picks_at(index, &axes);
        points.add(&source, &table, &assigned, &axes, &picks, &name);
    }
    if !points.errors.is_empty() {
        return Err(SpecErrors(points.errors));
    }
    Ok(Experiment {
        name,
        swept: axes.into_iter().map(|a| a.key).collect(),
        points: points.points,
        source,
        assigned,
    })
}

/// The grid indices a sweep runs, in grid order: all of them, or `sample` of them drawn
/// from `sample_seed` (the spec's `seed` when absent).
fn chosen_points(
    sweep: &SweepFile,
    axes: &[Axis],
    table: &toml::Table,
) -> Result<Vec<usize>, String> {
    let total = axes
        .iter()
        .try_fold(1usize, |total, a| total.checked_mul(a.values.len()));
    let limit = &crate::spec::ranges::SWEEP_POINTS;
    let Some(total) = total else {
        return Err(format!(
            "the grid's points do not fit in a count: {}",
            limit.why
        ));
    };
    let runs = sweep.sample.unwrap_or(total);
    if let Some(why) = limit.exceeded(runs as f64) {
        return Err(format!("{runs} points of a grid of {total}: {why}"));
    }
    match sweep.sample {
        None => Ok((0..total).collect()),
        Some(n) if n == 0 || n > total => Err(format!(
            "{n} points: choose between 1 and the grid's {total}"
        )),
        Some(n) => {
            let seed = sweep
                .sample_seed
                .or_else(|| {
                    table
                        .get("seed")
                        .and_then(|s| s.as_integer())
                        .map(|s| s as u64)
                })
                .unwrap_or(0);
            let mut rng = crate::rng::task_rng(seed, &[&"sweep"]);
            let mut chosen = rand::seq::index::sample(&mut rng, total, n).into_vec();
            chosen.sort_unstable();
            Ok(chosen)
        }
    }
}

/// Which value of each axis grid point `index` takes: mixed radix, the first axis
/// outermost.
fn picks_at(index: usize, axes: &[Axis]) -> Vec<usize> {
    let mut rest = index;
    let mut picks = vec![0; axes.len()];
    for (axis, size) in axes.iter().map(|a| a.values.len()).enumerate().rev() {
        picks[axis] = rest % size;
        rest /= size;
    }
    picks
}

/// A sweep's points as they are checked: the good ones with their names, and the
/// faults of all, each once (the sets make that linear in the number of faults).
struct SweepPoints<'a, S> {
    /// Deserializes and checks a point's table into its spec.
    check: &'a dyn Fn(&SpecSource, toml::Table, &Assigned) -> Result<S, SpecErrors>,
    points: Vec<Point<S>>,
    names: HashSet<String>,
    errors: Vec<SpecError>,
    seen: HashSet<SpecError>,
}

impl<'a, S> SweepPoints<'a, S> {
    fn new(
        check: &'a dyn Fn(&SpecSource, toml::Table, &Assigned) -> Result<S, SpecErrors>,
    ) -> Self {
        SweepPoints {
            check,
            points: Vec::new(),
            names: HashSet::new(),
            errors: Vec::new(),
            seen: HashSet::new(),
        }
    }

    /// Checks, with `check`, the point of `table` that takes value `picks[i]` of axis `i`, keeping
    /// the point or its faults.
    fn add(
        &mut self,
        source: &SpecSource,
        table: &toml::Table,
        assigned: &Assigned,
        axes: &[Axis],
        picks: &[usize],
        name: &str,
    ) {
        let values: Vec<toml::Value> = axes
            .iter()
            .zip(picks)
            .map(|(axis, &pick)| axis.values[pick].clone())
            .collect();
        let point_name = point_name(axes, picks);
        let (mut point_table, point_assigned) =
            self.place(source, table, assigned, axes, &values, &point_name);
        point_table.insert("name".into(), format!("{name}/{point_name}").into());
        match (self.check)(source, point_table, &point_assigned) {
            Ok(spec) => {
                if !self.names.insert(point_name.clone()) {
                    self.errors.push(SpecError {
                        location: source.text.shown().to_string(),
                        key: "sweep.values".into(),
                        message: format!("two points are both named {point_name:?}: make the values differ as text"),
                    });
                }
                self.points.push(Point { values, spec });
            }
            Err(SpecErrors(faults)) => {
                for fault in faults {
                    if self.seen.insert(fault.clone()) {
                        self.errors.push(fault);
                    }
                }
            }
        }
    }

    /// `table` with each axis's key set to the point's value, and `assigned` with each
    /// key set placed on its axis's line; a key that cannot be set is a fault.
    fn place(
        &mut self,
        source: &SpecSource,
        table: &toml::Table,
        assigned: &Assigned,
        axes: &[Axis],
        values: &[toml::Value],
        point_name: &str,
    ) -> (toml::Table, Assigned) {
        let mut point_table = table.clone();
        let mut point_assigned = assigned.clone();
        for (axis, value) in axes.iter().zip(values) {
            let path = steps(&axis.key).expect("sweep keys were checked");
            let placed = set_in(&mut point_table, &path, value.clone());
            // Values given with `--set` are placed there, not on a line of the file.
            let written = source.text.at_line(axis.line);
            let origin = assigned
                .origin(&format!("sweep.values.{}", axis.key))
                .map_or(written, str::to_string);
            let location = format!("{origin} (sweep point {point_name})");
            if let Err(message) = placed {
                self.errors.push(SpecError {
                    location,
                    key: axis.key.clone(),
                    message,
                });
                continue;
            }
            point_assigned.0.push((axis.key.clone(), location));
        }
        (point_table, point_assigned)
    }
}

/// One swept key, its values and the line they are written on.
struct Axis {
    key: String,
    values: Vec<toml::Value>,
    line: usize,
}

/// A fault in `[sweep.values]`: the key below it, its line, and the message.
type ValuesFault = (String, usize, String);

/// The lists of `[sweep.values]`, found at any depth: `"model.conv_channels" = [..]`
/// and `model.conv_channels = [..]` are the same key.
fn sweep_axes(values: &toml::Table, text: &TomlText) -> Result<Vec<Axis>, SpecErrors> {
    let mut axes = Vec::new();
    let mut faults = Vec::new();
    collect_axes(values, &[], text, &mut axes, &mut faults);
    if axes.is_empty() && faults.is_empty() {
        let line = sweep_line(text);
        faults.push((
            String::new(),
            line,
            "names no key: list at least one, such as \"training.learning_rate\" = [1e-4, 1e-3]"
                .into(),
        ));
    }
    if faults.is_empty() {
        return Ok(axes);
    }
    Err(SpecErrors(
        faults
            .into_iter()
            .map(|(key, line, message)| SpecError {
                location: text.at_line(line),
                key: if key.is_empty() {
                    "sweep.values".into()
                } else {
                    format!("sweep.values.{key}")
                },
                message,
            })
            .collect(),
    ))
}

/// The line `[sweep.values]` (or `[sweep]`) is written on; 1 when neither is, as when
/// `--set` gives the sweep.
fn sweep_line(text: &TomlText) -> usize {
    text.written_line(&["sweep", "values"])
        .or_else(|| text.written_line(&["sweep"]))
        .unwrap_or(1)
}

/// Adds the lists in `table`, which is at `names` below `[sweep.values]`, to `axes`;
/// what is neither a list nor a table to `faults`.
fn collect_axes<'a>(
    table: &'a toml::Table,
    names: &[&'a str],
    text: &TomlText,
    axes: &mut Vec<Axis>,
    faults: &mut Vec<ValuesFault>,
) {
    for (name, value) in table {
        let names = [names, &[name.as_str()]].concat();
        let key = names.join(".");
        let line = text
            .written_line(&[&["sweep", "values"], &names[..]].concat())
            .unwrap_or_else(|| sweep_line(text));
        match value {
            _ if key.split(['.', '[']).next() == Some("sweep") => faults.push((
                key,
                line,
                "a sweep cannot sweep its own keys: list every swept key in the one \
                 [sweep.values] (the points are their product)"
                    .into(),
            )),
            toml::Value::Array(list) if list.is_empty() => {
                faults.push((key, line, "is empty: list at least one value".into()))
            }
            toml::Value::Array(list) => match steps(&key) {
                Ok(_) => axes.push(Axis {
                    key,
                    values: list.clone(),
                    line,
                }),
                Err(message) => faults.push((key, line, message)),
            },
            toml::Value::Table(inner) => collect_axes(inner, &names, text, axes, faults),
            _ => faults.push((
                key,
                line,
                "expected a list of the values to sweep, such as [1e-4, 1e-3]".into(),
            )),
        }
    }
}

/// A point's folder name from its values, such as `learning_rate=0.001,conv_channels=8`:
/// each key without its section (`noise_cm_s.values` for `grid.noise_cm_s.values`; its
/// whole path when two keys would read the same), each value as written, a list joined
/// by '-', a table by its place in the list.
fn point_name(axes: &[Axis], picks: &[usize]) -> String {
    let short = |key: &str| {
        key.split_once('.')
            .map_or(key, |(_, rest)| rest)
            .to_string()
    };
    let parts: Vec<String> = axes
        .iter()
        .zip(picks)
        .map(|(axis, &pick)| {
            let ambiguous = axes
                .iter()
                .filter(|other| short(&other.key) == short(&axis.key))
                .count()
                > 1;
            let key = if ambiguous {
                axis.key.clone()
            } else {
                short(&axis.key)
            };
            // An index names a folder as a step: `models[0].terms` → `models.0.terms`.
            let key = key.replace('[', ".").replace(']', "");
            let scalar = |value: &toml::Value| match value {
                toml::Value::String(s) => Some(s.clone()),
                toml::Value::Integer(_) | toml::Value::Float(_) | toml::Value::Boolean(_) => {
                    Some(value.to_string())
                }
                _ => None,
            };
            let value = &axis.values[pick];
            let text = match value {
                toml::Value::Array(items) => items
                    .iter()
                    .map(scalar)
                    .collect::<Option<Vec<_>>>()
                    .map(|items| items.join("-")),
                other => scalar(other),
            }
            .unwrap_or_else(|| format!("v{}", pick + 1));
            let text: String = text
                .chars()
                .map(|c| {
                    if c.is_ascii_alphanumeric() || "-_.".contains(c) {
                        c
                    } else {
                        '_'
                    }
                })
                .collect();
            format!("{key}={text}")
        })
        .collect();
    parts.join(",")
}

#[cfg(test)]
mod tests {
    use crate::spec::fixture::quick_plus;
    use crate::spec::{load, load_experiment};
    use std::path::Path;

    fn line_containing(path: &Path, needle: &str) -> usize {
        let text = std::fs::read_to_string(path).unwrap();
        text.lines().position(|l| l.contains(needle)).unwrap() + 1
    }

    #[test]
    fn an_indexed_key_names_its_points_with_the_index_as_a_step() {
        let axes = [super::Axis {
            key: "calibration.models[0].terms".into(),
            values: vec![toml::Value::Array(vec![
                "lever_arm".into(),
                "time_offset".into(),
            ])],
            line: 1,
        }];
        assert_eq!(
            super::point_name(&axes, &[0]),
            "models.0.terms=lever_arm-time_offset"
        );
    }

    #[test]
    fn sweep_points_are_the_product_in_order_and_named_by_their_values() {
        let (_dir, path) = quick_plus(
            "[sweep.values]\n\"training.learning_rate\" = [1e-4, 1e-3]\nmodel.conv_channels = [8, 16, 32]\n",
        );
        let experiment = load_experiment(&path, &[]).unwrap();
        assert_eq!(experiment.name, "quick");
        assert_eq!(
            experiment.swept,
            ["training.learning_rate", "model.conv_channels"]
        );
        let names: Vec<&str> = experiment
            .points
            .iter()
            .map(|p| p.spec.name.as_str())
            .collect();
        assert_eq!(
            names,
            [
                "quick/learning_rate=0.0001,conv_channels=8",
                "quick/learning_rate=0.0001,conv_channels=16",
                "quick/learning_rate=0.0001,conv_channels=32",
                "quick/learning_rate=0.001,conv_channels=8",
                "quick/learning_rate=0.001,conv_channels=16",
                "quick/learning_rate=0.001,conv_channels=32",
            ]
        );
        let point = &experiment.points[4];
        assert_eq!(point.spec.training.learning_rates, [1e-3; 5]);
        assert_eq!(point.spec.model.conv_channels, 16);
        assert_eq!(
            point.values,
            [toml::Value::Float(1e-3), toml::Value::Integer(16)]
        );
        // Everything not swept is the spec's own.
        assert_eq!(point.spec.calibration.monte_carlo_runs, 20);
        // `load` gives the first point.
        assert_eq!(load(&path, &[]).unwrap().name, names[0]);
    }

    #[test]
    fn a_sample_draws_distinct_grid_points_from_its_seed() {
        let values = "[sweep.values]\n\"model.conv_channels\" = [4, 8, 16]\n\"training.batch_size\" = [16, 32, 64]\n";
        let sampled = |sample: &str| {
            let (_dir, path) = quick_plus(&format!("[sweep]\n{sample}\n{values}"));
            load_experiment(&path, &[]).map(|e| {
                e.points
                    .iter()
                    .map(|p| (p.spec.model.conv_channels, p.spec.training.batch_size))
                    .collect::<Vec<_>>()
            })
        };
        let four = sampled("sample = 4").unwrap();
        assert_eq!(four.len(), 4);
        let mut sorted = four.clone();
        sorted.sort();
        sorted.dedup();
        assert_eq!(sorted, four, "distinct and in grid order");
        assert_eq!(four, sampled("sample = 4").unwrap());
        assert_eq!(
            four,
            sampled("sample = 4\nsample_seed = 7").unwrap(),
            "the spec's seed is 7"
        );
        let others: Vec<_> = (0..8)
            .map(|seed| sampled(&format!("sample = 4\nsample_seed = {seed}")).unwrap())
            .collect();
        assert!(
            others.iter().any(|o| *o != four),
            "the seed changes the sample"
        );
        assert_eq!(sampled("sample = 9").unwrap().len(), 9);
        let error = sampled("sample = 10").unwrap_err().to_string();
        assert!(
            error.ends_with("sweep.sample: 10 points: choose between 1 and the grid's 9"),
            "{error}"
        );
    }

    /// A bad value of a sweep given with `--set` is placed on that `--set`, where it
    /// once pointed at the file's first line.
    #[test]
    fn a_bad_value_of_a_sweep_set_on_the_command_line_is_placed_there() {
        let (_dir, path) = quick_plus("");
        let set = r#"sweep.values={"model.dropout"=[0.1, 2.0]}"#.to_string();
        let error = load_experiment(&path, std::slice::from_ref(&set))
            .unwrap_err()
            .to_string();
        assert!(
            error.starts_with(&format!(
                "--set {set} (sweep point dropout=2.0): model.dropout:"
            )),
            "{error}"
        );
    }

    /// A sweep that sweeps its own keys was refused once per point as "unknown field
    /// `sweep`": it is refused once, on its `--set` or line, saying why.
    #[test]
    fn a_sweep_inside_a_sweep_is_refused_once_where_it_was_written() {
        let (_dir, path) = quick_plus("");
        let set = r#"sweep.values={"sweep.values" = [1, 2]}"#.to_string();
        let error = load_experiment(&path, std::slice::from_ref(&set))
            .unwrap_err()
            .to_string();
        assert_eq!(
            error,
            format!(
                "--set {set}: sweep.values.sweep.values: a sweep cannot sweep its own keys: \
                 list every swept key in the one [sweep.values] (the points are their product)"
            )
        );
        let (_dir, path) = quick_plus("[sweep.values]\n\"sweep.sample\" = [1, 2]\n");
        let line = line_containing(&path, "\"sweep.sample\" = [1, 2]");
        let error = load_experiment(&path, &[]).unwrap_err().to_string();
        assert!(
            error.starts_with(&format!(
                "{}:{line}: sweep.values.sweep.sample: a sweep cannot sweep its own keys",
                path.display()
            )),
            "{error}"
        );
    }

    #[test]
    fn bad_sweep_values_are_placed_on_their_line() {
        let (_dir, path) = quick_plus("[sweep.values]\n\"model.dropout\" = [0.1, 2.0]\n");
        let line = line_containing(&path, "\"model.dropout\" = [0.1, 2.0]");
        let error = load_experiment(&path, &[]).unwrap_err().to_string();
        let expected = format!(
            "{}:{line} (sweep point dropout=2.0): model.dropout:",
            path.display()
        );
        assert!(error.starts_with(&expected), "{error}");
        assert_eq!(error.lines().count(), 1, "{error}");

        let (_dir, path) = quick_plus("[sweep.values]\nmodel.channels = [8]\n");
        let line = line_containing(&path, "model.channels = [8]");
        let error = load_experiment(&path, &[]).unwrap_err().to_string();
        assert!(
            error.starts_with(&format!(
                "{}:{line} (sweep point channels=8): model.channels: unknown field",
                path.display()
            )),
            "{error}"
        );

        let (_dir, path) = quick_plus("[sweep.values]\n\"model.dropout\" = 0.1\n");
        let line = line_containing(&path, "\"model.dropout\" = 0.1");
        let error = load_experiment(&path, &[]).unwrap_err().to_string();
        assert_eq!(
            error,
            format!(
                "{}:{line}: sweep.values.model.dropout: expected a list of the values to sweep, such as [1e-4, 1e-3]",
                path.display()
            )
        );

        let (_dir, path) = quick_plus("[sweep]\nsamples = 3\n");
        let error = load_experiment(&path, &[]).unwrap_err().to_string();
        assert!(error.contains("sweep.samples: unknown field"), "{error}");
    }
}
