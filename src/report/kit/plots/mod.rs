//! The drawing kit every figure is made with, whatever the room that draws it: each
//! figure is drawn as SVG with plotters on a [`canvas`] and gives back a
//! [`canvas::Outcome`] (the figure, or why it does not apply). Every numeric axis is
//! chosen by [`scale`] (linear or logarithmic, its ticks, far values cut), or by
//! [`broken_axis`] in crowded panels; the shared pieces (looks, legends, marks) come
//! from [`draw`], a grid of terms against time from [`term_panels`] and a recording's
//! residual before and after from [`residual`], a clock search from [`search`], a fit to
//! position fixes in plan view and its fixes' residual from [`fixes`], a joint
//! calibration's terms dive by dive from [`forest`]. [`render`]
//! writes each figure as PNG and as SVG with the text outlined, both from the embedded
//! font, and this module writes the files ([`write_figures`]). In: the figures a room
//! drew. Out: the figure files, and each figure's caption or why it is absent
//! ([`Written`]).

pub mod broken_axis;
pub mod canvas;
pub mod draw;
pub mod fixes;
pub mod forest;
pub mod render;
pub mod residual;
pub mod scale;
pub mod search;
pub mod term_panels;

use crate::files::write_atomic;
use canvas::Outcome;
use std::path::{Path, PathBuf};

/// Which files each figure is written as.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    Png,
    Svg,
    Both,
}

impl Format {
    pub const ALL: [Format; 3] = [Format::Png, Format::Svg, Format::Both];

    /// How the command line spells it.
    pub fn name(self) -> &'static str {
        match self {
            Format::Png => "png",
            Format::Svg => "svg",
            Format::Both => "both",
        }
    }

    fn extensions(self) -> &'static [&'static str] {
        match self {
            Format::Png => &["png"],
            Format::Svg => &["svg"],
            Format::Both => &["png", "svg"],
        }
    }
}

/// A figure as written, or why the run has none.
#[derive(Debug, Clone)]
pub struct Written {
    pub stem: String,
    pub caption: Caption,
    /// The files written: none for a figure that does not apply.
    pub files: Vec<PathBuf>,
}

/// What the report says of a figure.
#[derive(Debug, Clone, PartialEq)]
pub enum Caption {
    /// The figure was written; its caption.
    Drawn(String),
    /// The data hold nothing the figure shows; why, in words that follow "not drawn, ".
    NotApplicable(String),
}

#[derive(Debug, thiserror::Error)]
pub enum PlotError {
    #[error("drawing the {what} figures")]
    Draw {
        /// Whose figures: a run's or a sweep's.
        what: &'static str,
        source: draw::DrawError,
    },
    #[error(transparent)]
    Render(#[from] render::RenderError),
    #[error("writing {}", path.display())]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
}

/// Writes each drawn figure into `folder` as `format` says, atomically; a figure that
/// does not apply is written as why.
pub(crate) fn write_figures(
    drawn: Vec<(String, Outcome)>,
    folder: &Path,
    format: Format,
) -> Result<Vec<Written>, PlotError> {
    let io = |path: &Path| {
        let path = path.to_path_buf();
        move |source| PlotError::Io { path, source }
    };
    std::fs::create_dir_all(folder).map_err(io(folder))?;
    let mut written = Vec::new();
    for (stem, outcome) in drawn {
        let figure = match outcome {
            Outcome::Drawn(figure) => figure,
            Outcome::NotApplicable(why) => {
                written.push(Written {
                    stem,
                    caption: Caption::NotApplicable(why),
                    files: Vec::new(),
                });
                continue;
            }
        };
        let mut files = Vec::new();
        for extension in format.extensions() {
            let bytes = match *extension {
                "png" => render::png(&figure.svg)?,
                _ => render::svg_with_outlined_text(&figure.svg)?.into_bytes(),
            };
            let path = folder.join(format!("{stem}.{extension}"));
            write_atomic(&path, &bytes).map_err(io(&path))?;
            files.push(path);
        }
        written.push(Written {
            stem,
            caption: Caption::Drawn(figure.caption),
            files,
        });
    }
    Ok(written)
}

#[cfg(test)]
mod tests {
    use super::*;
    use plotters::drawing::DrawingAreaErrorKind;

    #[test]
    fn a_drawing_error_keeps_its_cause_and_prints_it_once() {
        let error = PlotError::Draw {
            what: "run's",
            source: DrawingAreaErrorKind::LayoutError,
        };
        assert!(std::error::Error::source(&error).is_some());
        let chain = format!("{:#}", anyhow::Error::new(error));
        assert_eq!(chain, "drawing the run's figures: Bad layout");
    }
}
