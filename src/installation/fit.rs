//! Nonlinear least squares of the selected terms (Levenberg–Marquardt), τ included:
//! the terms that make the model's prediction from the reference closest to the DVL
//! over a calibration window.
//! In: a DVL record, its reference, a [`TermSet`]. Out: an [`Installation`].
