//! The velocity figure: the ground-truth velocity of a training and a test trajectory
//! over time, body frame, one panel each (the two named in `report.velocity_trajectories`,
//! or the first with each role). In: a [`StoredRun`]'s trajectories. Out: the figure,
//! or why the run has no such pair.

use crate::report::kit::plots::canvas::{Drawn, Outcome, draw_svg};
use crate::report::kit::plots::draw::*;
use crate::report::kit::plots::scale::Scale;
use crate::results::read::{StoredRun, StoredTrajectory};
use plotters::prelude::*;

/// Velocity of a training and a test trajectory over time, body frame.
pub fn velocity(run: &StoredRun) -> PlotResult<Outcome> {
    let chosen = &run.spec.report.velocity_trajectories;
    let find = |name: &str| run.trajectories.iter().find(|t| t.name == name);
    let with_role = |role: &str| {
        run.trajectories
            .iter()
            .find(|t| t.roles.iter().any(|r| r == role))
    };
    let pair: Option<[&StoredTrajectory; 2]> = match chosen.as_slice() {
        [a, b] => find(a).zip(find(b)).map(|(a, b)| [a, b]),
        _ => with_role("train")
            .zip(with_role("test"))
            .map(|(a, b)| [a, b]),
    };
    let Some(pair) = pair else {
        return Ok(Outcome::NotApplicable(
            "trajectories.parquet holds no training and test trajectory".into(),
        ));
    };
    let caption = format!(
        "GT velocity of {} and {} over time, body frame",
        pair[0].name, pair[1].name
    );
    let svg = draw_svg((1100, 760), |root| {
        let root = root.titled(&caption, font(TITLE_SIZE))?;
        let (panels, legend_area) = root.split_horizontally(1100 - LEGEND_WIDTH);
        let axes = [("vx", 0), ("vy", 1), ("vz", 2)];
        let colors = [
            RGBColor(31, 119, 180),
            RGBColor(255, 127, 14),
            RGBColor(44, 160, 44),
        ];
        for (area, trajectory) in panels.split_evenly((2, 1)).iter().zip(pair) {
            let end = trajectory.time_s.last().copied().unwrap_or(1.0).max(1.0);
            let (low, high) = trajectory
                .velocity_m_s
                .iter()
                .flatten()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
                    (lo.min(*v), hi.max(*v))
                });
            let pad = 0.05 * (high - low).max(0.1);
            let title = format!("{} ({})", trajectory.name, trajectory.roles.join(", "));
            let mut chart = chart_on(area, &title, 70).build_cartesian_2d(
                Scale::linear(0.0..end),
                Scale::linear((low - pad)..(high + pad)),
            )?;
            mesh(&mut chart)
                .x_desc("time [s]")
                .y_desc("velocity [m/s]")
                .draw()?;
            for ((_, axis), color) in axes.iter().zip(colors) {
                let points: Vec<(f64, f64)> = trajectory
                    .time_s
                    .iter()
                    .zip(&trajectory.velocity_m_s)
                    .map(|(t, v)| (*t, v[*axis]))
                    .collect();
                chart.draw_series(LineSeries::new(points, color.stroke_width(1)))?;
            }
        }
        let entries: Vec<(Swatch, String)> = axes
            .iter()
            .zip(colors)
            .map(|((name, _), color)| (Swatch::Line(color, Stroke::Solid), name.to_string()))
            .collect();
        legend(&legend_area, "GT velocity", &entries)
    })?;
    Ok(Outcome::Drawn(Drawn { caption, svg }))
}
