//! The terms against time, as a grid of panels: one panel per term of a Kalman filter,
//! its estimate after every sample with a ±σ band, the reference value (the true term
//! of a simulated DVL, or the trajectory's own batch fit of a real one) dashed, and
//! that value ± the bound's σ for a batch of the samples so far dotted: where the band
//! meets the dotted lines, the filter knows the term as well as the data allow. In:
//! rows of [`TermPanel`]s, each in the unit it is shown in. Out: the SVG
//! ([`draw_panels`]); the paper's and the study's figures pick the panels.

use super::canvas::draw_svg;
use super::draw::*;
use super::scale::Scale;
use plotters::prelude::*;

/// The colour of the estimate.
const ESTIMATE: RGBColor = RGBColor(31, 119, 180);
/// The colour of its ±σ band: the estimate's, a fifth of it over white.
const BAND: RGBColor = RGBColor(210, 228, 240);

/// One term's panel, in the unit it is shown in.
pub struct TermPanel {
    pub title: String,
    pub unit: &'static str,
    /// (time s, estimate, σ) after each sample.
    pub points: Vec<(f64, f64, f64)>,
    pub reference: Option<f64>,
    /// The bound's σ after each sample, as `points`.
    pub bound_std: Vec<f64>,
}

/// The y range that shows the panel once the first tenth of it has passed.
fn y_scale(panel: &TermPanel) -> Scale {
    let start = panel.points.len() / 10;
    let settled = panel.points.iter().zip(&panel.bound_std).skip(start);
    let mut values: Vec<f64> = Vec::new();
    for (&(_, estimate, std), &bound) in settled {
        values.extend([estimate - std, estimate + std]);
        if let Some(reference) = panel.reference {
            values.extend([reference - bound, reference + bound, reference]);
        }
    }
    let (low, high) = values
        .iter()
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| {
            (lo.min(v), hi.max(v))
        });
    if !(low.is_finite() && high.is_finite()) {
        return Scale::linear(-1.0..1.0);
    }
    let pad = if high > low { 0.08 * (high - low) } else { 1.0 };
    Scale::linear((low - pad)..(high + pad))
}

/// A grid of term panels, one row per entry of `rows` (its name, its panels: each
/// panel titled by both, or by its own where the row's name is empty), under `caption`;
/// `reference` names the dashed line in the legend.
pub fn draw_panels(
    caption: &str,
    rows: &[(String, Vec<TermPanel>)],
    reference: &str,
) -> PlotResult<String> {
    let columns = rows.iter().map(|(_, p)| p.len()).max().unwrap_or(1).max(1);
    let panel_width = if columns > 3 { 330 } else { 420 };
    let width = panel_width * columns as u32 + LEGEND_WIDTH;
    let height = 60 + 300 * rows.len() as u32;
    draw_svg((width, height), |root| {
        let (panels, legend_area) = panels_and_legend(root, caption, width, 1)?;
        let grid = panels[0].split_evenly((rows.len(), columns));
        for (r, (name, row)) in rows.iter().enumerate() {
            for (c, panel) in row.iter().enumerate() {
                let area = &grid[r * columns + c];
                let start = panel.points.first().map_or(0.0, |p| p.0);
                let end = panel.points.last().map_or(1.0, |p| p.0).max(start + 1.0);
                let title = match name.is_empty() {
                    true => panel.title.clone(),
                    false => format!("{name}: {}", panel.title),
                };
                let mut chart = chart_on(area, &title, 60)
                    .build_cartesian_2d(Scale::linear(0.0..end), y_scale(panel))?;
                mesh(&mut chart)
                    .x_desc("time [s]")
                    .y_desc(format!("[{}]", panel.unit))
                    .draw()?;
                let (y_low, y_high) = {
                    let range = chart.y_range();
                    (range.start, range.end)
                };
                let clip = |v: f64| v.clamp(y_low, y_high);
                let band: Vec<(f64, f64)> = panel
                    .points
                    .iter()
                    .map(|&(t, e, s)| (t, clip(e + s)))
                    .chain(panel.points.iter().rev().map(|&(t, e, s)| (t, clip(e - s))))
                    .collect();
                chart.draw_series(std::iter::once(Polygon::new(band, BAND.filled())))?;
                let estimate = panel.points.iter().map(|&(t, e, _)| (t, clip(e))).collect();
                line(&mut chart, estimate, ESTIMATE, Stroke::Solid)?;
                if let Some(reference) = panel.reference {
                    line(
                        &mut chart,
                        vec![(0.0, reference), (end, reference)],
                        BLACK,
                        Stroke::Dashed,
                    )?;
                    for sign in [-1.0, 1.0] {
                        let bound: Vec<(f64, f64)> = panel
                            .points
                            .iter()
                            .zip(&panel.bound_std)
                            .filter(|(_, b)| b.is_finite())
                            .map(|(&(t, _, _), &b)| (t, clip(reference + sign * b)))
                            .collect();
                        line(&mut chart, bound, GREY, Stroke::Dotted)?;
                    }
                }
            }
        }
        legend(
            &legend_area,
            "Kalman filter",
            &[
                (Swatch::Line(ESTIMATE, Stroke::Solid), "estimate".into()),
                (Swatch::Bar(BAND), "± σ".into()),
                (Swatch::Line(BLACK, Stroke::Dashed), reference.into()),
                (
                    Swatch::Line(GREY, Stroke::Dotted),
                    "± the bound's σ, batch".into(),
                ),
            ],
        )
    })
}
