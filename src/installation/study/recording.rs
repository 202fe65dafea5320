//! The recordings of a study: each stretch of paired data (a DVL beside its reference)
//! under its name, with the reference put in the body frame once, and the samples of
//! its first seconds, from which a method calibrates and a dive re-finds its clock. In:
//! a name and a [`PairedRecording`]. Out: a [`Recording`].

use crate::Vec3;
use crate::data::paired::{PairedRecording, sample_interval};
use crate::installation::frames::Reference;
use std::ops::Range;

/// One recording with its reference in the body frame.
pub struct Recording {
    pub name: String,
    pub recording: PairedRecording,
    pub reference: Reference,
}

impl Recording {
    pub fn new(name: String, recording: PairedRecording) -> Self {
        let reference = Reference::new(&recording);
        Recording {
            name,
            recording,
            reference,
        }
    }

    /// The samples of the first `window_s` seconds (all of them when the recording is
    /// shorter), and the seconds they span.
    pub fn first_seconds(&self, window_s: f64) -> (Range<usize>, f64) {
        let time = &self.recording.time_s;
        let start = time[0];
        let end = time.partition_point(|&t| t - start < window_s);
        let span = time[end - 1] - start + sample_interval(time);
        (0..end, span.min(window_s))
    }

    /// The DVL on the samples `range` and the reference's body velocity on their time
    /// stamps, where it is recorded.
    pub fn reference_on_stamps(&self, range: Range<usize>) -> (Vec<Vec3>, Vec<Vec3>) {
        let recording = &self.recording;
        range
            .filter_map(|i| {
                let at = self.reference.at(recording.time_s[i])?;
                Some((recording.dvl_m_s[i], at.velocity_body_m_s))
            })
            .unzip()
    }
}
