//! The Fisher information of the selected terms on a calibration window, from the DVL
//! and reference noise: each term's standard deviation, their correlation matrix, and
//! the terms that window cannot show (a standard deviation beyond its tolerance, or a
//! pair correlated beyond 0.95).
//! In: a DVL record, its reference, the fitted [`Installation`]. Out: a [`TermBound`].
