//! The installation study's window figure: each method's mean held-out RMSE against the
//! calibration window, its 95 % interval over calibration trajectories as bars, one
//! line per method and no calibration as a dashed reference. The paper's methods keep
//! the look they have in a run's figures (least squares dashed in its error model's
//! colour); each installation model has a colour of its own, its joint fit dashed and its
//! Kalman filter dotted in it. Beside it, with `[calibration.dive]`, the figure of the
//! held-out RMSE against the seconds that find each trajectory's clock again. In: a [`StudyResults`]'s summary.
//! Out: the figure, or why there is none (fewer than two windows).

use crate::installation::learned::spec::LEARNED_LABEL;
use crate::installation::study::method::{Clock, Method};
use crate::installation::study::rows::{NO_CALIBRATION, StudyResults, SummaryRow};
use crate::report::kit::plots::canvas::{Drawn, Outcome, draw_svg};
use crate::report::kit::plots::draw::*;
use crate::report::kit::plots::scale::Scale;
use crate::vocab::{ErrorModel, EstimatorKind};
use plotters::prelude::*;

/// The colours of the installation models, in the order the study lists them.
const INSTALLATION_COLORS: [RGBColor; 5] = [
    RGBColor(0, 128, 128),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
];

/// How a method of the study is drawn: its look and its marker (none for the
/// reference). `installation` counts the installation models listed before it;
/// `filtered`, for a Kalman filter, is the index among them of the model it filters.
pub fn method_look(
    method: &str,
    installation: usize,
    filtered: Option<usize>,
) -> (Look, Option<Marker>) {
    let paper = |estimator: EstimatorKind, rest: &str| {
        rest.trim()
            .parse::<ErrorModel>()
            .ok()
            .map(|model| series_look(estimator, Some(model)))
    };
    let look = |color, stroke| Look {
        label: method.to_string(),
        color,
        stroke,
    };
    if method == NO_CALIBRATION {
        return (look(BLACK, Stroke::Dashed), None);
    }
    if method == EstimatorKind::Baseline.label() {
        return (look(BLACK, Stroke::Solid), Some(Marker::Square));
    }
    if let Some(rest) = method.strip_prefix(EstimatorKind::LeastSquares.label())
        && let Some(found) = paper(EstimatorKind::LeastSquares, rest)
    {
        return (look(found.color, found.stroke), Some(Marker::Cross));
    }
    if let Some(rest) = method.strip_prefix(EstimatorKind::Dcnet.label())
        && let Some(found) = paper(EstimatorKind::Dcnet, rest)
    {
        return (look(found.color, found.stroke), Some(Marker::Circle));
    }
    if method.starts_with("installation") {
        let color = INSTALLATION_COLORS[installation % INSTALLATION_COLORS.len()];
        let parsed = Method::parse(method);
        return match parsed.is_joint() && !parsed.is_refound() {
            // A joint fit in its model's colour, dashed.
            true => (look(color, Stroke::Dashed), Some(Marker::Ring)),
            false => (look(color, Stroke::Solid), Some(Marker::Diamond)),
        };
    }
    if let Some(index) = filtered {
        // A Kalman filter in its installation model's colour, dotted.
        let color = INSTALLATION_COLORS[index % INSTALLATION_COLORS.len()];
        return (look(color, Stroke::Dotted), Some(Marker::Dot));
    }
    if let Some(rest) = method.strip_prefix(LEARNED_LABEL) {
        // Every replicate of a source in its colour (maroon, goldenrod: none of the paper
        // DCNets'); the vehicle's dashed.
        return if rest.starts_with("simulation") {
            (look(RGBColor(128, 0, 0), Stroke::Solid), Some(Marker::Ring))
        } else {
            (
                look(RGBColor(218, 165, 32), Stroke::Dashed),
                Some(Marker::Ring),
            )
        };
    }
    (look(GREY, Stroke::Solid), Some(Marker::Dot))
}

/// The looks of `methods`, in order: a model's joint fit and its Kalman filter in the
/// model's colour.
pub fn method_looks(methods: &[&str]) -> Vec<(Look, Option<Marker>)> {
    let models: Vec<String> =
        crate::first_seen(methods.iter().filter_map(|m| installation_model(m)));
    methods
        .iter()
        .map(|method| {
            let model = |rest: &str| models.iter().position(|m| m == rest);
            let filtered = method.strip_prefix("Kalman filter").and_then(model);
            let installation = installation_model(method)
                .and_then(|m| model(&m))
                .unwrap_or(0);
            method_look(method, installation, filtered)
        })
        .collect()
}

/// What follows "installation" in the label of an installation model's method, a joint
/// fit with its clock carried named by its model's: the key of the model's colour.
fn installation_model(method: &str) -> Option<String> {
    let parsed = Method::parse(method);
    let shown = match parsed.is_joint() && !parsed.is_refound() {
        true => parsed.model,
        false => method.to_string(),
    };
    shown.strip_prefix("installation").map(str::to_string)
}

/// Whether a summary row is one of the study's main methods, calibrated on one
/// trajectory with its clock: not a joint fit nor one with its clock re-found.
fn is_main(method: &str) -> bool {
    let method = Method::parse(method);
    !method.is_joint() && !method.is_refound()
}

/// Mean held-out RMSE ± its 95 % interval against the calibration window, every method
/// but `[learned]`'s (scored inside their folds only, see [`folds`]).
pub fn windows(study: &StudyResults) -> PlotResult<Outcome> {
    let windows = crate::first_seen(study.summary.iter().map(|r| r.window_s));
    if windows.len() < 2 {
        return Ok(Outcome::NotApplicable(format!(
            "the study has {} calibration window{}",
            windows.len(),
            if windows.len() == 1 { "" } else { "s" }
        )));
    }
    let rows: Vec<(f64, &SummaryRow)> = study
        .summary
        .iter()
        .filter(|r| !r.method.starts_with(LEARNED_LABEL) && is_main(&r.method))
        .map(|r| (r.window_s, r))
        .collect();
    rmse_figure(
        &rows,
        XAxis {
            label: "calibration window [s]",
            ticks: None,
            lines: true,
        },
        "Held-out RMSE against the calibration window: mean over calibration trajectories, bars its 95 % interval".into(),
    )
}

/// With `[calibration.dive]`: held-out RMSE against the dive's window w, the first w
/// seconds of each scored trajectory that found its clock again (scored after them),
/// calibrated on the longest window; no calibration, each installation model, its joint
/// fit over the other trajectories (dashed) and its Kalman filter (dotted).
pub fn dive(study: &StudyResults) -> PlotResult<Outcome> {
    let longest = study
        .summary
        .iter()
        .map(|r| r.window_s)
        .fold(f64::NAN, f64::max);
    let rows: Vec<(f64, SummaryRow)> = study
        .summary
        .iter()
        .filter(|r| r.window_s == longest)
        .filter_map(|r| {
            let parsed = Method::parse(&r.method);
            let Clock::Refound { dive_s } = parsed.variant.clock else {
                return None;
            };
            let method = parsed.with_clock(Clock::Carried).to_string();
            let shown = method == NO_CALIBRATION
                || method.starts_with("installation")
                || method.starts_with("Kalman filter");
            shown.then(|| {
                let row = SummaryRow {
                    method: method.clone(),
                    ..r.clone()
                };
                (dive_s, row)
            })
        })
        .collect();
    if crate::first_seen(rows.iter().map(|(x, _)| x.to_bits())).len() < 2 {
        return Ok(Outcome::NotApplicable(
            "the study has fewer than two [calibration.dive] windows".into(),
        ));
    }
    let rows: Vec<(f64, &SummaryRow)> = rows.iter().map(|(x, r)| (*x, r)).collect();
    rmse_figure(
        &rows,
        XAxis {
            label: "seconds of each scored trajectory that find its clock again, w [s]",
            ticks: None,
            lines: true,
        },
        format!(
            "Clock found again from each scored trajectory's first w s (calibrated on {longest} s): held-out RMSE, 95 % bars"
        ),
    )
}

/// With `[learned]`: every method on the pairs inside the folds only, mean held-out
/// RMSE ± its 95 % interval against the calibration window.
pub fn folds(study: &StudyResults) -> PlotResult<Outcome> {
    let rows: Vec<(f64, &SummaryRow)> = study
        .folds
        .iter()
        .filter(|r| r.fold == "all")
        .map(|r| (r.summary.window_s, &r.summary))
        .collect();
    if rows.is_empty() {
        return Ok(Outcome::NotApplicable("the study has no [learned]".into()));
    }
    rmse_figure(
        &rows,
        XAxis {
            label: "calibration window [s]",
            ticks: None,
            lines: true,
        },
        "Inside the folds, on pairs the learned models never saw: held-out RMSE, bars its 95 % interval".into(),
    )
}

/// The x axis of [`rmse_figure`]: its label, and the names of the things at 0, 1, 2, …
/// when it is a list of things rather than a quantity.
pub struct XAxis<'a> {
    pub label: &'a str,
    pub ticks: Option<&'a [String]>,
    /// Whether a method's points are joined by a line (not where neighbours on the axis
    /// are not neighbours in any sense, as the points of a sweep over two keys).
    pub lines: bool,
}

/// The width of one character of a tick label, in pixels, to tell whether names fit
/// side by side.
pub const TICK_CHAR_PX: usize = 9;

/// The width the figure's x axis gives its tick labels, in pixels.
pub const TICKS_WIDTH_PX: usize = 700;

/// The x axis from `first` to `last`: the ticks' names, or padded numbers.
fn x_scale(x_axis: &XAxis, first: f64, last: f64) -> Scale {
    match x_axis.ticks {
        Some(names) => Scale::named(names),
        None => {
            let pad = 0.05 * (last - first);
            Scale::linear((first - pad)..(last + pad))
        }
    }
}

/// The legend: a swatch per method, and the cut mark's where a mean is off the axis.
fn legend_entries(looks: &[(Look, Option<Marker>)], cut: bool) -> Vec<(Swatch, String)> {
    let mut entries: Vec<(Swatch, String)> = looks
        .iter()
        .map(|(look, marker)| {
            let swatch = match marker {
                Some(marker) => Swatch::Marked(look.color, look.stroke, *marker),
                None => Swatch::Line(look.color, look.stroke),
            };
            (swatch, look.label.clone())
        })
        .collect();
    if cut {
        entries.push((Swatch::Cut, "beyond the axis".into()));
    }
    entries
}

/// Each method's mean held-out RMSE ± its 95 % interval at the x of each of its `rows`
/// (`(x, row)`), one line per method and no calibration as a dashed reference.
pub fn rmse_figure(
    rows: &[(f64, &SummaryRow)],
    x_axis: XAxis,
    caption: String,
) -> PlotResult<Outcome> {
    let xs: Vec<f64> = rows.iter().map(|(x, _)| *x).collect();
    let mut methods = crate::first_seen(rows.iter().map(|(_, r)| r.method.as_str()));
    methods.sort_by_key(|m| *m != NO_CALIBRATION);
    let looks = method_looks(&methods);
    let (first, last) = xs
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), x| {
            (lo.min(*x), hi.max(*x))
        });
    let x = x_scale(&x_axis, first, last);
    // The means decide the axis: logarithmic when they span a decade, as the blown-up
    // short windows of the paper's least squares make them, so that no calibration,
    // the paper's methods and the installation models each keep a height of their own.
    let means: Vec<f64> = rows.iter().map(|(_, r)| r.mean_cm_s).collect();
    let y = Scale::fit_values(
        &means,
        crate::first_seen(xs.iter().map(|x| x.to_bits())).len(),
    );
    let y_label = if y.is_log() {
        "held-out RMSE [cm/s], log scale"
    } else {
        "held-out RMSE [cm/s]"
    };
    let width = 760 + LEGEND_WIDTH + 60;
    let svg = draw_svg((width, 560), |root| {
        let (panels, legend_area) = panels_and_legend(root, &caption, width - 60, 1)?;
        let mut chart = chart_on(&panels[0], "", 60).build_cartesian_2d(x.clone(), y.clone())?;
        mesh(&mut chart)
            .x_desc(x_axis.label)
            .y_desc(y_label)
            .draw()?;
        for (method, (look, marker)) in methods.iter().zip(&looks) {
            let mut mine: Vec<(f64, &SummaryRow)> = rows
                .iter()
                .filter(|(_, r)| r.method == *method)
                .map(|(x, r)| (*x, *r))
                .collect();
            mine.sort_by(|a, b| a.0.total_cmp(&b.0));
            let points: Vec<(f64, f64)> = mine
                .iter()
                .map(|(x, r)| (*x, y.shown(r.mean_cm_s)))
                .collect();
            if x_axis.lines || marker.is_none() {
                line(&mut chart, points.clone(), look.color, look.stroke)?;
            }
            if let Some(marker) = marker {
                marker.draw(&mut chart, &points, look.color)?;
                chart.draw_series(mine.iter().map(|(x, r)| {
                    let ends = [r.mean_cm_s - r.ci95_cm_s, r.mean_cm_s + r.ci95_cm_s]
                        .map(|v| (*x, y.shown(v)));
                    PathElement::new(ends.to_vec(), look.color.stroke_width(2))
                }))?;
            }
            for (x, r) in mine.iter().filter(|(_, r)| y.is_cut(r.mean_cm_s)) {
                let edge = if y.is_below(r.mean_cm_s) {
                    Edge::Bottom
                } else {
                    Edge::Top
                };
                cut_mark(
                    &mut chart,
                    (*x, y.shown(r.mean_cm_s)),
                    r.mean_cm_s,
                    look.color,
                    edge,
                )?;
            }
        }
        let cut = means.iter().any(|mean| y.is_cut(*mean));
        legend(&legend_area, "method", &legend_entries(&looks, cut))
    })?;
    Ok(Outcome::Drawn(Drawn { caption, svg }))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_paper_methods_keep_their_looks_and_installation_models_and_their_filters_have_their_own()
    {
        let methods = [
            NO_CALIBRATION,
            "baseline",
            "least squares EM2",
            "installation lever+offset",
            "DCNet EM5",
            "installation lever+offset+bias",
            "Kalman filter lever+offset+bias",
            "Kalman filter lever+offset",
        ];
        let looks = method_looks(&methods);
        assert_eq!(looks[0].1, None);
        assert_eq!(looks[0].0.stroke, Stroke::Dashed);
        let em2 = series_look(EstimatorKind::LeastSquares, Some(ErrorModel::Em2));
        assert_eq!(
            (looks[2].0.color, looks[2].0.stroke, looks[2].1),
            (em2.color, Stroke::Dashed, Some(Marker::Cross))
        );
        assert_eq!(looks[3].0.color, INSTALLATION_COLORS[0]);
        assert_eq!(looks[5].0.color, INSTALLATION_COLORS[1]);
        let dcnet = series_look(EstimatorKind::Dcnet, Some(ErrorModel::Em5));
        assert_eq!(looks[4].0.color, dcnet.color);
        assert_eq!(looks[5].0.label, "installation lever+offset+bias");
        // Each filter in its model's colour, dotted: two filters tell apart.
        assert_eq!(
            (looks[6].0.color, looks[6].0.stroke),
            (INSTALLATION_COLORS[1], Stroke::Dotted)
        );
        assert_eq!(looks[7].0.color, INSTALLATION_COLORS[0]);
    }
}
