//! The figures of a dead reckoning against positions. The plan view ([`draw_plan`]):
//! east across, north up, one metre the same length on both; the fixes (those the fit
//! left out crossed, those a blackout withheld ringed) or the reference's positions (a
//! line), and each piece's dead reckoning placed on its first fixes or position, with
//! no terms (grey) and with them (in colour), and the blackout's own dead reckoning,
//! placed at its start, in red: a track that bends away from the fixes shows as such.
//! The fixes' residual against time ([`draw_fix_residual`]): north and east, before
//! and after, the outliers crossed, the blackout shaded. Every line is drawn at one
//! point in k where it holds more than [`MOST_POINTS`], its ends kept. In: a
//! [`PlanView`] or a [`FixResidualTrace`]. Out: the SVG.

use super::canvas::draw_svg;
use super::draw::*;
use super::scale::Scale;
use plotters::prelude::*;

/// The colour of the dead reckoning with the terms, and of the residual after them.
const AFTER: RGBColor = RGBColor(31, 119, 180);
/// The colour of the dead reckoning and the residual with no terms.
const BEFORE: RGBColor = RGBColor(170, 170, 170);
/// The colour of the fixes.
const FIX: RGBColor = RGBColor(60, 60, 60);
/// The colour of the blackout: its dead reckoning, its withheld fixes, its shade.
const BLACKOUT: RGBColor = RGBColor(214, 39, 40);

/// The colour of the blackout's shade.
const SHADE: RGBColor = RGBColor(249, 224, 224);
/// The colour of the fixes a blackout withheld, drawn under the lines.
const WITHHELD: RGBColor = RGBColor(245, 170, 170);

/// The most points a line or a set of marks is drawn with.
pub const MOST_POINTS: usize = 3000;

/// A dead reckoning in plan view, against fixes or the reference's positions:
/// positions north and east, m.
pub struct PlanView {
    /// The reference's positions along each piece (none against fixes).
    pub reference: Vec<Vec<[f64; 2]>>,
    /// The fixes fitted, those the fit left out as outliers, those withheld.
    pub fixes: Vec<[f64; 2]>,
    pub outliers: Vec<[f64; 2]>,
    pub withheld: Vec<[f64; 2]>,
    /// Each piece's dead reckoning with no terms and with them.
    pub before: Vec<Vec<[f64; 2]>>,
    pub after: Vec<Vec<[f64; 2]>>,
    /// The blackout's dead reckoning with the terms, placed at its start.
    pub blackout: Option<Vec<[f64; 2]>>,
}

/// East, north: the plotted point of a north-east position.
fn east_north(p: &[f64; 2]) -> (f64, f64) {
    (p[1], p[0])
}

/// The plan view `plan` under `title`.
pub fn draw_plan(title: &str, plan: &PlanView) -> PlotResult<String> {
    let everything = || {
        (plan.fixes.iter())
            .chain(plan.reference.iter().flatten())
            .chain(&plan.outliers)
            .chain(&plan.withheld)
            .chain(plan.before.iter().flatten())
            .chain(plan.after.iter().flatten())
            .chain(plan.blackout.iter().flatten())
    };
    let (mut low, mut high) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for p in everything() {
        for k in 0..2 {
            (low[k], high[k]) = (low[k].min(p[k]), high[k].max(p[k]));
        }
    }
    if !low[0].is_finite() {
        (low, high) = ([0.0; 2], [1.0; 2]);
    }
    // One metre the same length across and up: both axes span the wider extent.
    let half = 0.55 * (high[0] - low[0]).max(high[1] - low[1]).max(1.0);
    let centre = [0.5 * (low[0] + high[0]), 0.5 * (low[1] + high[1])];
    let side = 900;
    let width = side + LEGEND_WIDTH;
    draw_svg((width, side + 40), |root| {
        let (panels, legend_area) = panels_and_legend(root, title, width, 1)?;
        let mut chart = chart_on(&panels[0], "", 70).build_cartesian_2d(
            Scale::linear((centre[1] - half)..(centre[1] + half)),
            Scale::linear((centre[0] - half)..(centre[0] + half)),
        )?;
        mesh(&mut chart)
            .x_desc("east [m]")
            .y_desc("north [m]")
            .draw()?;
        let drawn = |points: &[[f64; 2]]| -> Vec<(f64, f64)> {
            strided(points, MOST_POINTS)
                .iter()
                .map(east_north)
                .collect()
        };
        // The withheld fixes under the lines, so that the tracks through them show.
        Marker::Ring.draw(&mut chart, &drawn(&plan.withheld), WITHHELD)?;
        Marker::Dot.draw(&mut chart, &drawn(&plan.fixes), FIX)?;
        for track in &plan.reference {
            line(&mut chart, drawn(track), BLACK, Stroke::Solid)?;
        }
        for track in &plan.before {
            line(&mut chart, drawn(track), BEFORE, Stroke::Solid)?;
        }
        for track in &plan.after {
            line(&mut chart, drawn(track), AFTER, Stroke::Solid)?;
        }
        if let Some(track) = &plan.blackout {
            line(&mut chart, drawn(track), BLACKOUT, Stroke::Solid)?;
        }
        Marker::Cross.draw(&mut chart, &drawn(&plan.outliers), BLACK)?;
        legend(&legend_area, "plan view", &plan_entries(plan))
    })
}

/// The plan view's legend: what it draws, and only that.
fn plan_entries(plan: &PlanView) -> Vec<(Swatch, String)> {
    let mut entries = Vec::new();
    if !plan.fixes.is_empty() {
        entries.push((Swatch::Mark(FIX, Marker::Dot), "fix fitted".to_string()));
    }
    if !plan.reference.is_empty() {
        entries.push((
            Swatch::Line(BLACK, Stroke::Solid),
            "reference's positions".to_string(),
        ));
    }
    entries.extend([
        (
            Swatch::Line(BEFORE, Stroke::Solid),
            "dead reckoning, no terms".to_string(),
        ),
        (
            Swatch::Line(AFTER, Stroke::Solid),
            "dead reckoning, terms".to_string(),
        ),
    ]);
    if !plan.withheld.is_empty() {
        entries.push((
            Swatch::Mark(WITHHELD, Marker::Ring),
            "fix withheld (blackout)".to_string(),
        ));
    }
    if plan.blackout.is_some() {
        entries.push((
            Swatch::Line(BLACKOUT, Stroke::Solid),
            "through the blackout".to_string(),
        ));
    }
    if !plan.outliers.is_empty() {
        entries.push((
            Swatch::Mark(BLACK, Marker::Cross),
            "outlier, left out".to_string(),
        ));
    }
    entries
}

/// A fix's residual as drawn: its time, s, north and east, m, and whether its fit kept it.
pub type ResidualPoint = (f64, [f64; 2], bool);

/// The fixes' residuals as drawn, each fit's own: with no terms and with them; the
/// blackout's window, s, where there was one.
pub struct FixResidualTrace {
    pub before: Vec<ResidualPoint>,
    pub after: Vec<ResidualPoint>,
    pub blackout_s: Option<(f64, f64)>,
}

/// The fixes' residual `trace` under `title`: a panel north, a panel east.
pub fn draw_fix_residual(title: &str, trace: &FixResidualTrace) -> PlotResult<String> {
    let times = || (trace.before.iter().chain(&trace.after)).map(|p| p.0);
    let start = times().fold(f64::INFINITY, f64::min);
    let end = times().fold(f64::NEG_INFINITY, f64::max);
    let (start, end) = match start.is_finite() {
        true => (start, end.max(start + 1.0)),
        false => (0.0, 1.0),
    };
    let (start, end) = match trace.blackout_s {
        Some((from, to)) => (start.min(from), end.max(to)),
        None => (start, end),
    };
    let width = 1400 + LEGEND_WIDTH;
    draw_svg((width, 700), |root| {
        let (panels, legend_area) = panels_and_legend(root, title, width, 1)?;
        let rows = panels[0].split_evenly((2, 1));
        for (axis, name) in ["north", "east"].iter().enumerate() {
            let values = (trace.before.iter().chain(&trace.after)).map(|p| p.1[axis].abs());
            let top = values.fold(0.0, f64::max).max(1e-3) * 1.05;
            let mut chart = chart_on(&rows[axis], "", 70)
                .build_cartesian_2d(Scale::linear(start..end), Scale::linear(-top..top))?;
            mesh(&mut chart)
                .x_desc("time [s]")
                .y_desc(format!("{name}, dead reckoning − fix [m]"))
                .draw()?;
            if let Some((from, to)) = trace.blackout_s {
                chart.draw_series(std::iter::once(Rectangle::new(
                    [(from, -top), (to, top)],
                    SHADE.filled(),
                )))?;
            }
            let series = |of: &[ResidualPoint], keep: bool| -> Vec<(f64, f64)> {
                let points: Vec<(f64, f64)> = (of.iter())
                    .filter(|p| p.2 == keep)
                    .map(|p| (p.0, p.1[axis]))
                    .collect();
                strided(&points, MOST_POINTS)
            };
            Marker::Dot.draw(&mut chart, &series(&trace.before, true), BEFORE)?;
            Marker::Dot.draw(&mut chart, &series(&trace.after, true), AFTER)?;
            Marker::Cross.draw(&mut chart, &series(&trace.after, false), BLACK)?;
        }
        legend(&legend_area, "fixes' residual", &residual_entries(trace))
    })
}

/// The residual figure's legend: what it draws, and only that.
fn residual_entries(trace: &FixResidualTrace) -> Vec<(Swatch, String)> {
    let mut entries = vec![
        (Swatch::Mark(BEFORE, Marker::Dot), "no terms".to_string()),
        (Swatch::Mark(AFTER, Marker::Dot), "terms".to_string()),
    ];
    if trace.after.iter().any(|p| !p.2) {
        entries.push((
            Swatch::Mark(BLACK, Marker::Cross),
            "outlier, left out".to_string(),
        ));
    }
    if trace.blackout_s.is_some() {
        entries.push((
            Swatch::Bar(BLACKOUT),
            "blackout, fixes withheld".to_string(),
        ));
    }
    entries
}
