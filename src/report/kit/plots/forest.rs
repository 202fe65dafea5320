//! A forest plot of a joint calibration: a panel per vehicle term, a row per dive with
//! its own estimate and 95 % interval, then the joint estimate's, then the vehicle's
//! interval between dives (diamonds), over the band a next dive's own fit should fall
//! in (shaded): a dive that disagrees with the others stands out of the band. In: the
//! [`ForestPanel`]s. Out: the SVG ([`draw_forest`]).

use super::canvas::draw_svg;
use super::draw::*;
use super::scale::Scale;
use plotters::prelude::*;

/// The colour of a dive's own estimate.
const DIVE: RGBColor = RGBColor(31, 119, 180);
/// The colour of the joint estimate and the vehicle's interval.
const VEHICLE: RGBColor = RGBColor(214, 39, 40);
/// The colour of the next dive's band.
const BAND: RGBColor = RGBColor(232, 232, 232);

/// The panels side by side in a row, at most.
const COLUMNS: usize = 3;

/// A row of a panel: its label, the estimate and its 95 % interval (in the panel's
/// unit), and whether it is the vehicle's (joint or between dives) rather than a dive's.
#[derive(Debug, Clone, PartialEq)]
pub struct ForestRow {
    pub label: String,
    pub value: f64,
    pub interval: (f64, f64),
    pub vehicle: bool,
}

/// One term: its title and unit, its rows top to bottom, and the next dive's 95 % band
/// where there is one.
#[derive(Debug, Clone, PartialEq)]
pub struct ForestPanel {
    pub title: String,
    pub unit: &'static str,
    pub rows: Vec<ForestRow>,
    pub band: Option<(f64, f64)>,
}

/// The forest plot of `panels` under `title`.
pub fn draw_forest(title: &str, panels: &[ForestPanel]) -> PlotResult<String> {
    let columns = panels.len().clamp(1, COLUMNS);
    let grid_rows = panels.len().div_ceil(COLUMNS).max(1);
    let rows_per_panel = panels.iter().map(|p| p.rows.len()).max().unwrap_or(1);
    let panel_height = (60 + 32 * rows_per_panel as u32).max(240);
    let width = 520 * columns as u32 + LEGEND_WIDTH;
    let height = 60 + panel_height * grid_rows as u32;
    draw_svg((width, height), |root| {
        let root = root.titled(title, font(TITLE_SIZE))?;
        let (grid, legend_area) = root.split_horizontally(width - LEGEND_WIDTH);
        let cells = grid.split_evenly((grid_rows, columns));
        for (panel, area) in panels.iter().zip(&cells) {
            draw_panel(area, panel)?;
        }
        legend(&legend_area, "forest plot", &entries(panels))
    })
}

/// One term's panel: the band, then each row's interval and estimate.
fn draw_panel(area: &Area, panel: &ForestPanel) -> PlotResult {
    // Top to bottom as given: the first row at the top.
    let names: Vec<String> = panel.rows.iter().rev().map(|r| r.label.clone()).collect();
    let ends = (panel.rows.iter())
        .flat_map(|r| [r.interval.0, r.interval.1, r.value])
        .chain(panel.band.into_iter().flat_map(|(low, high)| [low, high]))
        .filter(|v| v.is_finite());
    let (low, high) = ends.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
        (lo.min(v), hi.max(v))
    });
    let x = Scale::fit(low, high);
    let place = |k: usize| (panel.rows.len() - 1 - k) as f64;
    let mut chart = chart_on(area, &format!("{} [{}]", panel.title, panel.unit), 150)
        .build_cartesian_2d(x, Scale::named(&names))?;
    mesh(&mut chart).draw()?;
    if let Some((low, high)) = panel.band {
        let top = names.len() as f64 - 0.5;
        chart.draw_series(std::iter::once(Rectangle::new(
            [(low, -0.5), (high, top)],
            BAND.filled(),
        )))?;
    }
    for (k, row) in panel.rows.iter().enumerate() {
        let color = if row.vehicle { VEHICLE } else { DIVE };
        let y = place(k);
        line(
            &mut chart,
            vec![(row.interval.0, y), (row.interval.1, y)],
            color,
            Stroke::Solid,
        )?;
        let marker = if row.vehicle {
            Marker::Diamond
        } else {
            Marker::Square
        };
        marker.draw(&mut chart, &[(row.value, y)], color)?;
    }
    Ok(())
}

/// The legend: what the panels draw, and only that.
fn entries(panels: &[ForestPanel]) -> Vec<(Swatch, String)> {
    let mut entries = vec![(
        Swatch::Marked(DIVE, Stroke::Solid, Marker::Square),
        "a dive's own fit, 95 %".to_string(),
    )];
    if panels.iter().any(|p| p.rows.iter().any(|r| r.vehicle)) {
        entries.push((
            Swatch::Marked(VEHICLE, Stroke::Solid, Marker::Diamond),
            "the vehicle's, 95 %".to_string(),
        ));
    }
    if panels.iter().any(|p| p.band.is_some()) {
        entries.push((Swatch::Bar(BAND), "next dive's own fit, 95 %".to_string()));
    }
    entries
}
