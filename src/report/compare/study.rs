//! `dcnet-exp compare A B` of two installation studies. In: two results folders of an
//! installation study, each holding `heldout.parquet` and its siblings (read back by
//! `results::study::read_study`) and the `spec.toml` it ran. Out: one Markdown
//! text: both folders named, the spec keys that differ, each method's mean held-out
//! RMSE per calibration window in A and B with each one's 95 % interval and B − A,
//! marked ⚠ where the two intervals do not overlap, and for each installation model
//! the mean of each term over the calibration trajectories that see it, A and B side
//! by side in the term's table unit.

use super::CompareError;
use super::markdown::{new_table, spec_section};
use super::pairs::pair;
use crate::installation::study::rows::{StudyResults, SummaryRow, TermRow};
use crate::report::kit::numbers::three_digits;
use crate::report::kit::readable::readable_term;
use crate::results::read::ReadError;
use crate::results::study::read_study;
use std::fmt::Write;
use std::path::{Path, PathBuf};

/// Marks a difference whose two 95 % intervals do not overlap.
const FLAG: &str = "⚠";

/// One installation study read back: its folder, tables and resolved spec.
#[derive(Debug, Clone)]
pub struct StoredStudy {
    pub folder: PathBuf,
    pub study: StudyResults,
    pub spec: toml::Table,
}

/// Reads the installation study in `folder`: its tables and its `spec.toml`.
pub fn read(folder: &Path) -> Result<StoredStudy, CompareError> {
    let study = read_study(folder)?;
    let path = folder.join(crate::results::SPEC);
    let text = std::fs::read_to_string(&path).map_err(|source| {
        CompareError::Read(ReadError::Io {
            path: path.clone(),
            source,
        })
    })?;
    let spec = text
        .parse::<toml::Table>()
        .map_err(|source| CompareError::SpecToml {
            path: path.clone(),
            source: Box::new(source),
        })?;
    Ok(StoredStudy {
        folder: folder.to_path_buf(),
        study,
        spec,
    })
}

/// The comparison of study `a` with study `b` as Markdown.
pub fn render(a: &StoredStudy, b: &StoredStudy) -> String {
    let mut out = String::new();
    let _ = writeln!(out, "# Comparison of two installation studies\n");
    let _ = writeln!(out, "- A: `{}`", a.folder.display());
    let _ = writeln!(out, "- B: `{}`\n", b.folder.display());
    spec_section(&a.spec, &b.spec, &mut out);
    let (marked, both) = heldout_section(&a.study.summary, &b.study.summary, &mut out);
    terms_section(&a.study.terms, &b.study.terms, &mut out);
    let _ = writeln!(
        out,
        "{marked} of {both} method and window pairs differ with 95 % intervals that do not overlap"
    );
    out
}

/// A mean ± its 95 % half-width, or "—" for a side that lacks the row.
fn mean_text(row: Option<&SummaryRow>) -> String {
    row.map_or("—".into(), |r| {
        format!("{:.2} ± {:.2}", r.mean_cm_s, r.ci95_cm_s)
    })
}

/// Whether the 95 % intervals of `a` and `b` do not overlap.
fn apart(a: &SummaryRow, b: &SummaryRow) -> bool {
    (b.mean_cm_s - a.mean_cm_s).abs() > a.ci95_cm_s + b.ci95_cm_s
}

/// The held-out table; returns how many pairs it marked, and how many it has on both
/// sides.
fn heldout_section(a: &[SummaryRow], b: &[SummaryRow], out: &mut String) -> (usize, usize) {
    let _ = writeln!(out, "## Held-out RMSE\n");
    let mut table = new_table(&["method", "window s", "A cm/s", "B cm/s", "B − A cm/s", ""]);
    let (mut marked, mut both) = (0, 0);
    for (row_a, row_b) in pair(a, b, |r| (r.method.clone(), r.window_s.to_bits())) {
        let any = row_a.or(row_b).expect("a pair has a side");
        let (difference, flag) = match (row_a, row_b) {
            (Some(ra), Some(rb)) => {
                both += 1;
                let flag = apart(ra, rb);
                marked += usize::from(flag);
                (
                    format!("{:+.2}", rb.mean_cm_s - ra.mean_cm_s),
                    if flag { FLAG } else { "" },
                )
            }
            _ => ("—".to_string(), ""),
        };
        table.add_row(vec![
            any.method.clone(),
            any.window_s.to_string(),
            mean_text(row_a),
            mean_text(row_b),
            difference,
            flag.to_string(),
        ]);
    }
    let _ = writeln!(
        out,
        "Mean held-out RMSE over calibration trajectories ± the half-width of its 95 % interval; {FLAG} where the two intervals do not overlap:\n\n{table}\n"
    );
    (marked, both)
}

/// The mean of `term`'s estimates by `method` at `window_s` over the calibration
/// trajectories that see it, in the term's table unit, and how many see it.
fn seen_mean(rows: &[TermRow], method: &str, window_s: f64, term: &str) -> Option<(f64, usize)> {
    let (_, _, factor) = readable_term(term);
    let values: Vec<f64> = rows
        .iter()
        .filter(|r| {
            r.method == method && r.window_s == window_s && r.term == term && r.unseen.is_empty()
        })
        .map(|r| factor * r.value)
        .collect();
    (!values.is_empty()).then(|| {
        (
            values.iter().sum::<f64>() / values.len() as f64,
            values.len(),
        )
    })
}

/// The largest window at which `method` has terms in `rows`.
fn largest_window(rows: &[TermRow], method: &str) -> Option<f64> {
    rows.iter()
        .filter(|r| r.method == method)
        .map(|r| r.window_s)
        .max_by(f64::total_cmp)
}

/// B − A of two sides' means, signed, three significant digits; `—` where a side has
/// none.
fn difference_text(mean_a: Option<(f64, usize)>, mean_b: Option<(f64, usize)>) -> String {
    match (mean_a, mean_b) {
        (Some((va, _)), Some((vb, _))) => {
            let d = vb - va;
            if d == 0.0 {
                "0".into()
            } else if d > 0.0 {
                format!("+{}", three_digits(d))
            } else {
                three_digits(d)
            }
        }
        _ => "—".into(),
    }
}

fn terms_section(a: &[TermRow], b: &[TermRow], out: &mut String) {
    let methods = crate::first_seen(a.iter().chain(b).map(|r| r.method.as_str()));
    if methods.is_empty() {
        return;
    }
    let _ = writeln!(out, "## Estimated terms\n");
    for method in methods {
        // The largest window both sides have, or else each side's largest.
        let windows = |rows: &[TermRow]| {
            crate::first_seen(
                rows.iter()
                    .filter(|r| r.method == method)
                    .map(|r| r.window_s),
            )
        };
        let (in_a, in_b) = (windows(a), windows(b));
        let common = in_a
            .iter()
            .copied()
            .filter(|w| in_b.contains(w))
            .max_by(f64::total_cmp);
        let (window_a, window_b) = match common {
            Some(w) => (Some(w), Some(w)),
            None => (largest_window(a, method), largest_window(b, method)),
        };
        let terms = crate::first_seen(
            a.iter()
                .chain(b)
                .filter(|r| r.method == method)
                .map(|r| r.term.as_str()),
        );
        let mut table = new_table(&["term", "A", "seen on", "B", "seen on", "B − A"]);
        for term in terms {
            let (name, unit, _) = readable_term(term);
            let side = |rows: &[TermRow], window: Option<f64>| {
                window.and_then(|w| seen_mean(rows, method, w, term))
            };
            let (mean_a, mean_b) = (side(a, window_a), side(b, window_b));
            let value = |mean: Option<(f64, usize)>| {
                mean.map_or(("—".into(), "0".into()), |(v, n)| {
                    (three_digits(v), n.to_string())
                })
            };
            let ((value_a, seen_a), (value_b, seen_b)) = (value(mean_a), value(mean_b));
            let difference = difference_text(mean_a, mean_b);
            table.add_row(vec![
                format!("{name} ({unit})"),
                value_a,
                seen_a,
                value_b,
                seen_b,
                difference,
            ]);
        }
        let window = |w: Option<f64>| w.map_or("—".into(), |w| format!("{w} s"));
        let windows_text = if window_a == window_b {
            format!("window {}", window(window_a))
        } else {
            format!(
                "window {} in A, {} in B",
                window(window_a),
                window(window_b)
            )
        };
        let _ = writeln!(
            out,
            "### {method}, {windows_text}\n\nThe mean of each term over the calibration trajectories that see it, and on how many:\n\n{table}\n"
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn summary(method: &str, window_s: f64, mean_cm_s: f64, ci95_cm_s: f64) -> SummaryRow {
        SummaryRow {
            method: method.into(),
            window_s,
            mean_cm_s,
            ci95_cm_s,
            ratio: 1.0,
            calibrations: 2,
        }
    }

    fn term(calibration: &str, term: &str, value: f64, unseen: &str) -> TermRow {
        TermRow {
            method: "installation lever".into(),
            calibration: calibration.into(),
            window_s: 400.0,
            term: term.into(),
            value,
            std: 0.01,
            bound_std: 0.01,
            unseen: unseen.into(),
            asked: String::new(),
            between_dives_std: f64::NAN,
            next_dive_low: f64::NAN,
            next_dive_high: f64::NAN,
        }
    }

    fn stored(
        folder: &str,
        spec: &str,
        summary: Vec<SummaryRow>,
        terms: Vec<TermRow>,
    ) -> StoredStudy {
        StoredStudy {
            folder: folder.into(),
            study: StudyResults {
                heldout: Vec::new(),
                terms,
                summary,
                trace: Vec::new(),
                failures: Vec::new(),
                folds: Vec::new(),
                filtered: Vec::new(),
                calibration_time: Vec::new(),
                recordings: Vec::new(),
            },
            spec: spec.parse().unwrap(),
        }
    }

    #[test]
    fn means_their_intervals_and_the_terms_side_by_side() {
        let a = stored(
            "results/a",
            "name = \"a\"\n[noise]\ndvl_cm_s = 2.0\n",
            vec![
                summary("no calibration", 400.0, 15.07, 0.37),
                summary("installation lever", 400.0, 12.48, 1.53),
                summary("least squares EM5", 50.0, 209.38, 315.79),
            ],
            vec![
                term("T1", "lever_arm_x_m", -1.5, ""),
                term("T2", "lever_arm_x_m", -1.7, ""),
                term(
                    "T12",
                    "lever_arm_x_m",
                    -4.0,
                    "standard deviation 3.2e-1 above its tolerance 1e-1",
                ),
                term("T1", "bias_x_m_s", 0.004, ""),
            ],
        );
        let b = stored(
            "results/b",
            "name = \"a\"\n[noise]\ndvl_cm_s = 3.0\n",
            vec![
                summary("no calibration", 400.0, 15.07, 0.37),
                summary("installation lever", 400.0, 6.03, 0.92),
                summary("installation all", 400.0, 6.13, 1.06),
            ],
            vec![
                term("T1", "lever_arm_x_m", -1.9, ""),
                term("T1", "bias_x_m_s", 0.006, ""),
            ],
        );
        let text = render(&a, &b);
        let lines: Vec<&str> = text.lines().collect();
        let has = |line: &str| assert!(lines.contains(&line), "missing {line:?} in\n{text}");
        has("- A: `results/a`");
        has("| `noise.dvl_cm_s` | 2.0 | 3.0 |");
        has("| method             | window s | A cm/s          | B cm/s       | B − A cm/s |   |");
        has("| no calibration     | 400      | 15.07 ± 0.37    | 15.07 ± 0.37 | +0.00      |   |");
        has("| installation lever | 400      | 12.48 ± 1.53    | 6.03 ± 0.92  | -6.45      | ⚠ |");
        has("| least squares EM5  | 50       | 209.38 ± 315.79 | —            | —          |   |");
        has("| installation all   | 400      | —               | 6.13 ± 1.06  | —          |   |");
        has("### installation lever, window 400 s");
        has("| term            | A     | seen on | B     | seen on | B − A  |");
        has("| lever arm x (m) | -1.60 | 2       | -1.90 | 1       | -0.300 |");
        has("| bias x (cm/s)   | 0.400 | 1       | 0.600 | 1       | +0.200 |");
        has("1 of 2 method and window pairs differ with 95 % intervals that do not overlap");
    }

    #[test]
    fn identical_specs_say_so() {
        let a = stored("a", "name = \"a\"\n", Vec::new(), Vec::new());
        let text = render(&a, &a.clone());
        assert!(text.contains("The resolved specs are the same."), "{text}");
        assert!(!text.contains("## Estimated terms"), "{text}");
    }
}
