//! A clock search as a curve: the RMS of the DVL against the carried installation's
//! prediction at each time offset tried, the search's edges dashed, its best marked ◆ and
//! the clock least squares found from there marked: a second minimum, or a best at an
//! edge, shows at a glance. In: a [`SearchCurve`]. Out: the SVG ([`draw_search`]).

use super::canvas::draw_svg;
use super::draw::*;
use super::scale::Scale;
use plotters::prelude::*;

/// The colour of the curve.
const CURVE: RGBColor = RGBColor(31, 119, 180);
/// The colour of the clock found.
const FOUND: RGBColor = RGBColor(214, 39, 40);

/// A search as drawn, in the units it is shown in: cm/s against s.
pub struct SearchCurve {
    /// (offset s, RMS cm/s) at each offset tried, sorted by offset.
    pub tried: Vec<(f64, f64)>,
    /// The search's edges, s.
    pub edges_s: (f64, f64),
    /// The search's best: its offset and RMS.
    pub best: (f64, f64),
    /// The clock least squares found, s.
    pub found_s: f64,
}

/// The search under `title`.
pub fn draw_search(title: &str, search: &SearchCurve) -> PlotResult<String> {
    let width = 900 + LEGEND_WIDTH;
    draw_svg((width, 460), |root| {
        let (panels, legend_area) = panels_and_legend(root, title, width, 1)?;
        let (low, high) = search.edges_s;
        let pad = 0.03 * (high - low).max(1e-3);
        let rms: Vec<f64> = search.tried.iter().map(|&(_, r)| r).collect();
        let top = rms.iter().copied().fold(0.0, f64::max).max(1e-3);
        let mut chart = chart_on(&panels[0], "", 60).build_cartesian_2d(
            Scale::linear((low - pad)..(high + pad)),
            Scale::linear(0.0..1.08 * top),
        )?;
        mesh(&mut chart)
            .x_desc("time offset tried [s]")
            .y_desc("RMS, DVL − carried prediction [cm/s]")
            .draw()?;
        for edge in [low, high] {
            line(
                &mut chart,
                vec![(edge, 0.0), (edge, 1.08 * top)],
                GREY,
                Stroke::Dashed,
            )?;
        }
        line(&mut chart, search.tried.clone(), CURVE, Stroke::Solid)?;
        Marker::Diamond.draw(&mut chart, &[search.best], BLACK)?;
        line(
            &mut chart,
            vec![(search.found_s, 0.0), (search.found_s, 1.08 * top)],
            FOUND,
            Stroke::Solid,
        )?;
        legend(
            &legend_area,
            "clock search",
            &[
                (
                    Swatch::Line(CURVE, Stroke::Solid),
                    "RMS at each offset tried".into(),
                ),
                (
                    Swatch::Mark(BLACK, Marker::Diamond),
                    "the search's best".into(),
                ),
                (Swatch::Line(FOUND, Stroke::Solid), "the clock found".into()),
                (
                    Swatch::Line(GREY, Stroke::Dashed),
                    "the search's edges".into(),
                ),
            ],
        )
    })
}
