//! DCNet as a calibration method: the calibration window is cut into consecutive
//! windows of the training length, the trained network estimates the terms of each in
//! one batch, and their mean is the estimate (docs/paper.md, "Evaluation protocol").

use super::Estimator;
use crate::Vec3;
use crate::dataset::INPUT_ROWS;
use crate::model::{Dcnet, Settings, Windows, correction};
use crate::vocab::{Correction, ErrorModel};
use burn::tensor::Device;

pub struct DcnetEstimator {
    pub model: Dcnet,
    pub error_model: ErrorModel,
    /// Samples per network window (the training window).
    pub window: usize,
    pub settings: Settings,
    pub device: Device,
}

impl Estimator for DcnetEstimator {
    fn estimate(&self, dvl: &[Vec3], gnss: &[Vec3]) -> Correction {
        let w = self.window;
        // The spec check keeps every calibration window at least one network window long.
        let count = dvl.len() / w;
        assert!(
            count > 0,
            "a calibration window of {} samples is shorter than DCNet's {w}",
            dvl.len()
        );
        // [count, 6, w]: DVL x, y, z then GNSS x, y, z over time.
        let mut input = vec![0f32; count * INPUT_ROWS * w];
        for window in 0..count {
            for time in 0..w {
                let sample = window * w + time;
                for axis in 0..3 {
                    input[(window * INPUT_ROWS + axis) * w + time] = dvl[sample][axis] as f32;
                    input[(window * INPUT_ROWS + 3 + axis) * w + time] = gnss[sample][axis] as f32;
                }
            }
        }
        let windows = Windows::new(&input, INPUT_ROWS, w, self.settings.kernel, &self.device);
        let terms: Vec<f32> = self
            .model
            .forward(&windows, &self.settings, None)
            .into_data()
            .try_to_vec()
            .expect("DCNet outputs f32");
        let n = self.error_model.term_count();
        let mean: Vec<f32> = (0..n)
            .map(|t| (0..count).map(|row| terms[row * n + t]).sum::<f32>() / count as f32)
            .collect();
        correction(&mean, self.error_model)
    }
}
