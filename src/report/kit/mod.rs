//! The rendering kit every content of the report uses, and which imports none of them.
//! In: the numbers, terms and tables a content room picks from its results, and the
//! figures it draws. Out: text set as Markdown or LaTeX, and figure files.
//!
//! - [`numbers`]: how a number is written (three significant digits, the decimals of a
//!   standard deviation);
//! - [`readable`]: error terms in the units people read;
//! - [`table`]: the one model of a report's tables (cells, tables, sections);
//! - [`markdown`] and [`latex`]: any such table or section set as Markdown and as
//!   LaTeX, and the file names and signs of `report.md` and `report.tex`;
//! - [`plots`]: the drawing kit of every figure (canvas, axes, looks, legends, term
//!   panels) and the figure files written as PNG and SVG.

pub mod numbers;
pub mod readable;
pub mod table;
pub mod markdown;
pub mod latex;
pub mod plots;
