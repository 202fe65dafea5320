//! The installation study's matrix figures: for each method, the held-out RMSE of every
//! calibration trajectory (rows) on every scored trajectory (columns) at the largest
//! window, as a heatmap with the number in each cell. One colour scale serves every
//! method's figure, so that a cell reads the same in each; its bar is the legend. In: a
//! [`StudyResults`]'s held-out rows. Out: one figure per method, named by its slug
//! (`installation_matrix_least_squares_em1`), or why there is none.

use crate::installation::study::method::Method;
use crate::installation::study::rows::{StudyResults, TransferRow};
use crate::report::kit::numbers::three_digits;
use crate::report::kit::plots::canvas::{Drawn, Outcome, draw_svg};
use crate::report::kit::plots::draw::*;
use crate::report::kit::plots::scale::Scale;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, VPos};

/// The stem of every matrix figure, before the method's slug.
pub const STEM: &str = "installation_matrix";

/// Light for a small RMSE to dark red for a large one.
const RAMP: [RGBColor; 5] = [
    RGBColor(255, 255, 204),
    RGBColor(254, 217, 118),
    RGBColor(253, 141, 60),
    RGBColor(227, 26, 28),
    RGBColor(128, 0, 38),
];

/// The colour at `fraction` (0 to 1) of [`RAMP`].
pub fn ramp(fraction: f64) -> RGBColor {
    let position = fraction.clamp(0.0, 1.0) * (RAMP.len() - 1) as f64;
    let low = (position.floor() as usize).min(RAMP.len() - 2);
    let t = position - low as f64;
    let (a, b) = (RAMP[low], RAMP[low + 1]);
    let mix = |x: u8, y: u8| (f64::from(x) + t * (f64::from(y) - f64::from(x))).round() as u8;
    RGBColor(mix(a.0, b.0), mix(a.1, b.1), mix(a.2, b.2))
}

/// A method's label as a file name: `least squares EM1` → `least_squares_em1`.
pub fn slug(method: &str) -> String {
    let mut slug = String::new();
    for c in method.chars() {
        if c.is_ascii_alphanumeric() {
            slug.push(c.to_ascii_lowercase());
        } else if !slug.ends_with('_') {
            slug.push('_');
        }
    }
    slug.trim_matches('_').to_string()
}

/// One matrix figure per method at the largest window, all on one colour scale.
pub fn matrix(study: &StudyResults) -> PlotResult<Vec<(String, Outcome)>> {
    let Some(window_s) = study.heldout.iter().map(|r| r.window_s).reduce(f64::max) else {
        return Ok(vec![(
            STEM.to_string(),
            Outcome::NotApplicable("the study holds no held-out rows".into()),
        )]);
    };
    let rows: Vec<&TransferRow> = study
        .heldout
        .iter()
        // A joint fit scores only the trajectory it left out: no matrix.
        .filter(|r| r.window_s == window_s && !Method::parse(&r.method).is_joint())
        .collect();
    let trajectories: Vec<String> = crate::first_seen(
        rows.iter()
            .flat_map(|r| [r.calibration.clone(), r.scored.clone()]),
    );
    let values: Vec<f64> = rows.iter().map(|r| r.total_cm_s).collect();
    let (colours, clipped_at) = colour_scale(&values);
    let methods = crate::first_seen(rows.iter().map(|r| r.method.as_str()));
    let mut figures = Vec::new();
    for method in methods {
        let cells: Vec<&TransferRow> = rows
            .iter()
            .copied()
            .filter(|r| r.method == method)
            .collect();
        // The summary table's mean, the same cells: over calibration trajectories, of
        // each one's mean.
        let mean = study
            .summary
            .iter()
            .find(|r| r.method == method && r.window_s == window_s)
            .map_or(f64::NAN, |r| r.mean_cm_s);
        let lines = title_lines(method, window_s, mean);
        let caption = lines.join(", ");
        let n = trajectories.len();
        let side = 44 * n as u32 + 120;
        let svg = draw_svg((side + 170, side + 70), |root| {
            // Three lines: one is wider than the figure.
            let root = lines.iter().try_fold(root.clone(), |root, line| {
                root.titled(line, font(PANEL_TITLE_SIZE))
            })?;
            let (matrix, bar) = root.split_horizontally(side);
            matrix_panel(&matrix, &trajectories, &cells, &colours)?;
            colour_bar(&bar, &colours, clipped_at)
        })?;
        figures.push((
            format!("{STEM}_{}", slug(method)),
            Outcome::Drawn(Drawn { caption, svg }),
        ));
    }
    Ok(figures)
}

/// The share of every cell below which the colour scale ends where the highest cell
/// is more than twice that: the cells above it, a method far off, take the darkest
/// colour, so that the colours tell apart the
/// few cm/s that separate the methods that work.
const CLIP_QUANTILE: f64 = 0.9;

/// The colour scale of every method's matrix: from the smallest cell to the
/// [`CLIP_QUANTILE`] of all of them where the highest is more than twice that, else to
/// the highest (logarithmic where that spans a decade), and the value it is clipped
/// at, if it is.
fn colour_scale(values: &[f64]) -> (Scale, Option<f64>) {
    let mut sorted: Vec<f64> = values.iter().copied().filter(|v| v.is_finite()).collect();
    sorted.sort_by(f64::total_cmp);
    let Some((&low, &high)) = sorted.first().zip(sorted.last()) else {
        return (Scale::fit(f64::NAN, f64::NAN), None);
    };
    let at = ((sorted.len() - 1) as f64 * CLIP_QUANTILE).round() as usize;
    let top = sorted[at];
    let clipped = (high > 2.0 * top && top > low).then_some(top);
    (Scale::fit(low, clipped.unwrap_or(high)), clipped)
}

/// The title of one method's matrix, in three lines that each fit the figure: what
/// is shown, what the rows and columns are, and its mean (the summary table's: over
/// calibration trajectories, of each one's mean over the trajectories it is scored on).
fn title_lines(method: &str, window_s: f64, mean_cm_s: f64) -> [String; 3] {
    [
        format!("{method}: held-out RMSE [cm/s]"),
        format!("calibrated on the row's first {window_s} s, scored on the column"),
        format!(
            "mean over the rows of each row's mean: {} cm/s",
            three_digits(mean_cm_s)
        ),
    ]
}

/// The matrix of one method: calibration trajectories down, scored ones across, the
/// diagonal (a trajectory scored on itself) left grey.
fn matrix_panel(
    area: &Area,
    trajectories: &[String],
    cells: &[&TransferRow],
    colours: &Scale,
) -> PlotResult {
    let n = trajectories.len();
    let extent = -0.5..(n as f64 - 0.5);
    let mut chart = ChartBuilder::on(area)
        .margin(12)
        .x_label_area_size(50)
        .y_label_area_size(60)
        .build_cartesian_2d(extent.clone(), extent)?;
    // The first calibration trajectory on top.
    let row_names: Vec<String> = trajectories.iter().rev().cloned().collect();
    mesh(&mut chart)
        .disable_mesh()
        .x_labels(n + 1)
        .y_labels(n + 1)
        .x_label_formatter(&|x| category(trajectories, *x))
        .y_label_formatter(&|y| category(&row_names, *y))
        .x_desc("scored trajectory")
        .y_desc("calibration trajectory")
        .draw()?;
    let position = |name: &str| trajectories.iter().position(|t| t == name);
    for row in 0..n {
        let y = (n - 1 - row) as f64;
        chart.draw_series(std::iter::once(Rectangle::new(
            [(row as f64 - 0.5, y - 0.5), (row as f64 + 0.5, y + 0.5)],
            RGBColor(220, 220, 220).filled(),
        )))?;
    }
    for cell in cells {
        let (Some(column), Some(row)) = (position(&cell.scored), position(&cell.calibration))
        else {
            continue;
        };
        let (x, y) = (column as f64, (n - 1 - row) as f64);
        let fraction = colours.fraction(cell.total_cm_s);
        let fill = ramp(fraction);
        let ink = if fraction > 0.55 { WHITE } else { BLACK };
        chart.draw_series([
            Rectangle::new([(x - 0.5, y - 0.5), (x + 0.5, y + 0.5)], fill.filled()),
            Rectangle::new(
                [(x - 0.5, y - 0.5), (x + 0.5, y + 0.5)],
                WHITE.stroke_width(1),
            ),
        ])?;
        chart.draw_series(std::iter::once(Text::new(
            format!("{:.1}", cell.total_cm_s),
            (x, y),
            anchored(12, HPos::Center, VPos::Center).color(&ink),
        )))?;
    }
    Ok(())
}

/// The colour scale's bar, its ticks those of `colours`, saying whether it is
/// logarithmic and where it is clipped.
fn colour_bar(area: &Area, colours: &Scale, clipped_at: Option<f64>) -> PlotResult {
    let range = colours.range();
    let kind = if colours.is_log() { ", log" } else { "" };
    let (bar, note) = area.split_vertically(area.dim_in_pixel().1 as i32 - 60);
    if let Some(top) = clipped_at {
        note.draw(&Text::new(
            format!("darkest: ≥ {}", three_digits(top)),
            (0, 10),
            font(LABEL_SIZE),
        ))?;
    }
    let area = &bar;
    let mut chart = ChartBuilder::on(area)
        .margin_top(40)
        .margin_bottom(20)
        .margin_right(40)
        .y_label_area_size(60)
        .caption(format!("RMSE [cm/s]{kind}"), font(LABEL_SIZE))
        .build_cartesian_2d(0.0..1.0, colours.clone())?;
    mesh(&mut chart)
        .disable_x_mesh()
        .disable_y_mesh()
        .x_labels(0)
        .draw()?;
    let steps = 120;
    let at = |k: usize| {
        let t = k as f64 / steps as f64;
        if colours.is_log() {
            range.start * (range.end / range.start).powf(t)
        } else {
            range.start + t * (range.end - range.start)
        }
    };
    chart.draw_series((0..steps).map(|k| {
        let (from, to) = (at(k), at(k + 1));
        Rectangle::new(
            [(0.0, from), (1.0, to)],
            ramp(colours.fraction(0.5 * (from + to))).filled(),
        )
    }))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slugs_and_the_colour_ramp() {
        assert_eq!(slug("least squares EM1"), "least_squares_em1");
        assert_eq!(
            slug("installation lever+offset+bias"),
            "installation_lever_offset_bias"
        );
        assert_eq!(slug("no calibration"), "no_calibration");
        assert_eq!(ramp(0.0), RAMP[0]);
        assert_eq!(ramp(1.0), RAMP[4]);
        assert_eq!(ramp(0.125), RGBColor(255, 236, 161));
        assert_eq!(ramp(7.0), RAMP[4]);
    }

    /// A method far off (one cell of 300 cm/s among 1–20) does not wash out the rest:
    /// the scale ends at the cells' 90 % quantile, logarithmic over its decade, and the
    /// far cell takes the darkest colour.
    #[test]
    fn the_colour_scale_is_clipped_where_a_few_cells_are_far_above_the_rest() {
        let mut values: Vec<f64> = (1..=20).map(f64::from).collect();
        values.push(300.0);
        let (scale, clipped_at) = colour_scale(&values);
        assert_eq!(clipped_at, Some(19.0));
        assert!(scale.is_log());
        assert!(scale.range().end < 25.0, "{:?}", scale.range());
        assert_eq!(ramp(scale.fraction(300.0)), RAMP[4]);
        assert!(scale.fraction(10.0) > 0.6 && scale.fraction(10.0) < 0.9);
        // Nothing far above: no clipping.
        let (_, none) = colour_scale(&values[..20]);
        assert_eq!(none, None);
    }

    #[test]
    fn the_title_keeps_what_it_says_in_three_lines_that_fit() {
        let lines = title_lines("installation lever+offset+bias+scale", 400.0, 6.123);
        assert_eq!(
            lines,
            [
                "installation lever+offset+bias+scale: held-out RMSE [cm/s]",
                "calibrated on the row's first 400 s, scored on the column",
                "mean over the rows of each row's mean: 6.12 cm/s",
            ]
        );
        // A 13-trajectory matrix is 862 pixels wide, some 85 characters of the title font.
        assert!(lines.iter().all(|line| line.chars().count() <= 75));
    }
}
