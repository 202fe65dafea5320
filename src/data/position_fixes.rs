//! Position fixes as every reader gives them (a fixes file, a bag's topic) and the
//! fit to fixes reads them: each fix's time, north and east, optionally its depth and
//! its own noise, and where it came from.
//! In: what a reader read. Out: [`Fixes`].

/// Position fixes, on the attitude's clock.
#[derive(Debug, Clone, PartialEq)]
pub struct Fixes {
    /// Each fix's line in its file (the header is line 1), or its place among fixes
    /// simulated.
    pub lines: Vec<u64>,
    /// Seconds, strictly increasing.
    pub time_s: Vec<f64>,
    /// North and east, metres (of the first fix, where the file gives latitude and
    /// longitude).
    pub north_east_m: Vec<[f64; 2]>,
    /// Depth, metres, positive down, where the file gives one.
    pub depth_m: Option<Vec<f64>>,
    /// Each fix's noise per horizontal axis, m, where every fix carries its own (a
    /// bag's fixes with their covariances).
    pub noise_m: Option<Vec<f64>>,
}

impl Fixes {
    pub fn len(&self) -> usize {
        self.time_s.len()
    }

    pub fn is_empty(&self) -> bool {
        self.time_s.is_empty()
    }

    /// The root mean square of the fixes' own noise per horizontal axis, m, where they
    /// carry it: the residual RMS white fixes of that noise leave per axis.
    pub fn rms_noise_m(&self) -> Option<f64> {
        let own = self.noise_m.as_ref().filter(|own| !own.is_empty())?;
        Some((own.iter().map(|n| n * n).sum::<f64>() / own.len() as f64).sqrt())
    }

    /// The fixes `keep` selects (in order), with the same file.
    pub fn select(&self, keep: impl Fn(usize) -> bool) -> Fixes {
        let chosen: Vec<usize> = (0..self.len()).filter(|&i| keep(i)).collect();
        Fixes {
            lines: chosen.iter().map(|&i| self.lines[i]).collect(),
            time_s: chosen.iter().map(|&i| self.time_s[i]).collect(),
            north_east_m: chosen.iter().map(|&i| self.north_east_m[i]).collect(),
            depth_m: (self.depth_m.as_ref()).map(|d| chosen.iter().map(|&i| d[i]).collect()),
            noise_m: (self.noise_m.as_ref()).map(|n| chosen.iter().map(|&i| n[i]).collect()),
        }
    }
}
