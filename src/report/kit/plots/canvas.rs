//! What every figure is drawn on and what it gives back. A figure function takes its
//! data (a stored run or sweep), draws on the white SVG canvas of [`draw_svg`], and
//! returns an [`Outcome`]: the [`Drawn`] figure, or why the data hold nothing it could
//! show. A failure while drawing is an `Err` of [`PlotResult`], never an outcome.
//! In: a figure's size and its drawing. Out: the SVG text.

use super::draw::{Area, PlotResult};
use plotters::prelude::*;

/// A figure: its caption and the SVG plotters drew.
pub struct Drawn {
    pub caption: String,
    pub svg: String,
}

/// What a figure function gives back when drawing did not fail.
pub enum Outcome {
    /// The figure.
    Drawn(Drawn),
    /// The data hold nothing the figure shows (no DCNet, no baseline, no EM5, …): why,
    /// in words that follow "not drawn, ".
    NotApplicable(String),
}

/// The SVG text of a white canvas of `size` on which `draw` drew.
pub fn draw_svg(size: (u32, u32), draw: impl FnOnce(&Area) -> PlotResult) -> PlotResult<String> {
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, size).into_drawing_area();
        root.fill(&WHITE)?;
        draw(&root)?;
        root.present()?;
    }
    Ok(svg)
}
