//! The sample arithmetic of a spec. In: seconds, a sample rate, a trajectory's length,
//! a window and a stride, all in samples. Out: a whole number of samples, and the start
//! samples (or the count) of the windows cut from a trajectory, as the dataset and the
//! calibration cut them.

/// `seconds × rate` as a whole number of samples, if it is one.
pub fn seconds_to_samples(seconds: f64, rate_hz: f64) -> Option<usize> {
    let samples = seconds * rate_hz;
    let rounded = samples.round();
    (samples.is_finite() && rounded >= 0.0 && (samples - rounded).abs() < 1e-6)
        .then_some(rounded as usize)
}

/// Start samples of the windows of a trajectory of `len` samples: every `stride`
/// samples, as long as a whole window fits.
pub fn window_starts(len: usize, window: usize, stride: usize) -> impl Iterator<Item = usize> {
    (0..)
        .map(move |i| i * stride)
        .take_while(move |start| start + window <= len)
}

/// How many windows [`window_starts`] gives, counted without walking them.
pub fn window_count(len: usize, window: usize, stride: usize) -> usize {
    match len.checked_sub(window) {
        Some(room) if stride > 0 => room / stride + 1,
        _ => 0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn windows_are_counted_as_they_are_cut() {
        for (len, window, stride) in [
            (0, 10, 9),
            (9, 10, 9),
            (10, 10, 9),
            (165, 10, 9),
            (1000, 7, 3),
        ] {
            let cut = window_starts(len, window, stride).count();
            assert_eq!(
                window_count(len, window, stride),
                cut,
                "{len} {window} {stride}"
            );
        }
        assert_eq!(window_count(usize::MAX, 10, 1), usize::MAX - 9);
    }
}
