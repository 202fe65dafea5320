//! The physical and practical ranges of a spec's values, each with the reason a value
//! beyond it makes no sense: an AUV's speeds and missions, a DVL's error terms, and
//! counts past which a run is no longer an experiment but a mistake (a grid of 10⁸
//! combinations, 10⁹ Monte Carlo runs). The checks in `spec/check/` take their upper
//! ends from here (a fault at a key whose value is beyond its limit); the lower ends
//! (positive, at least 1) are theirs. Memory is estimated later, from the sizes these
//! ranges let through, by the footprint module.

/// The largest value a key may take, and why.
#[derive(Debug, Clone, Copy)]
pub struct Limit {
    pub max: f64,
    pub unit: &'static str,
    pub why: &'static str,
}

pub const SAMPLE_RATE_HZ: Limit = Limit {
    max: 1000.0,
    unit: "Hz",
    why: "faster than any DVL pings",
};
pub const GROUND_TRUTH_WINDOW_S: Limit = Limit {
    max: 60.0,
    unit: "s",
    why: "a moving average that long smooths away the manoeuvres the DVL measures",
};
pub const TRAJECTORY_S: Limit = Limit {
    max: 30.0 * 86_400.0,
    unit: "s",
    why: "longer than a 30-day AUV mission",
};
pub const SPEED_M_S: Limit = Limit {
    max: 10.0,
    unit: "m/s",
    why: "faster than an AUV travels",
};
pub const TURN_RATE_DEG_S: Limit = Limit {
    max: 180.0,
    unit: "deg/s",
    why: "faster than an AUV turns",
};
pub const VELOCITY_ERROR_CM_S: Limit = Limit {
    max: 100.0,
    unit: "cm/s",
    why: "a velocity error of more than 1 m/s is no DVL or GNSS-RTK worth calibrating",
};
pub const SCALE_PCT: Limit = Limit {
    max: 100.0,
    unit: "%",
    why: "a scale factor error above 100 % is no DVL worth calibrating",
};
pub const DCNET_WINDOW_S: Limit = Limit {
    max: 600.0,
    unit: "s",
    why: "DCNet's windows are seconds long; its first layer grows with the window",
};
pub const GRID_AXIS_VALUES: Limit = Limit {
    max: 10_000.0,
    unit: "values",
    why: "an axis that fine is no longer a grid of error terms",
};
pub const GRID_COMBINATIONS: Limit = Limit {
    max: 100_000.0,
    unit: "combinations",
    why: "the paper's grid has 1134; each combination is a copy of the training trajectories",
};
pub const MONTE_CARLO_RUNS: Limit = Limit {
    max: 100_000.0,
    unit: "runs",
    why: "the paper runs 200; at 100 000 the standard error of a mean RMSE is a 300th of its spread",
};
pub const CONV_CHANNELS: Limit = Limit {
    max: 4096.0,
    unit: "channels",
    why: "the paper's convolutions have 16",
};
pub const FC_WIDTH: Limit = Limit {
    max: 65_536.0,
    unit: "units",
    why: "the paper's widest layer has 128",
};
pub const EPOCHS: Limit = Limit {
    max: 100_000.0,
    unit: "epochs",
    why: "the paper trains for 100",
};
pub const BATCH_SIZE: Limit = Limit {
    max: 1_000_000.0,
    unit: "windows",
    why: "the paper's batches hold 256",
};
pub const REPLICATES: Limit = Limit {
    max: 100.0,
    unit: "replicates",
    why: "at 100 the confidence interval's t factor is 1.98, near its limit 1.96: more replicates only train more models",
};
pub const SWEEP_POINTS: Limit = Limit {
    max: 10_000.0,
    unit: "points",
    why: "each point is a run of its own; draw some with sample = N",
};

impl Limit {
    /// Why `value` is too large, when it is; a value that is not finite is left to the
    /// checks that ask for a number.
    pub fn exceeded(&self, value: f64) -> Option<String> {
        (value.is_finite() && value > self.max).then(|| {
            let unit = if self.unit.is_empty() {
                String::new()
            } else {
                format!(" {}", self.unit)
            };
            format!("{value}{unit} is above {}{unit}: {}", self.max, self.why)
        })
    }
}

#[cfg(test)]
mod tests {
    use crate::spec::fixture::quick_faults;

    #[test]
    fn values_beyond_their_physical_range_are_refused_at_their_key() {
        for (set, key, why) in [
            (
                "data.sample_rate_hz=5000",
                "data.sample_rate_hz",
                "faster than any DVL",
            ),
            (
                "data.ground_truth_window_samples=100000",
                "data.ground_truth_window_samples",
                "100000 samples at 1 Hz",
            ),
            (
                "data.trajectories[0].synthetic_duration_s=1e12",
                "data.trajectories[0].synthetic_duration_s",
                "30-day AUV mission",
            ),
            (
                "data.synthetic.speed_m_s=[1, 100]",
                "data.synthetic.speed_m_s[1]",
                "faster than an AUV travels",
            ),
            (
                "data.synthetic.turn_rate_deg_s=1000",
                "data.synthetic.turn_rate_deg_s",
                "faster than an AUV turns",
            ),
            (
                "sensors.gnss_noise_cm_s=500",
                "sensors.gnss_noise_cm_s",
                "more than 1 m/s",
            ),
            (
                "grid.bias_cm_s={values = [0.3, -150]}",
                "grid.bias_cm_s[1]",
                "more than 1 m/s",
            ),
            (
                "grid.scale_pct={values = [0.5, 250]}",
                "grid.scale_pct[1]",
                "above 100 %",
            ),
            (
                "grid.noise_cm_s={start = 0.0, stop = 100.0, step = 0.001}",
                "grid.noise_cm_s",
                "100001 values",
            ),
            (
                "grid.noise_cm_s={start = 0.0, stop = 1e308, step = 1e-308}",
                "grid.noise_cm_s",
                "values is above 10000",
            ),
            (
                "dvl[1].noise_cm_s=101",
                "dvl[1].noise_cm_s",
                "more than 1 m/s",
            ),
            (
                "dataset.window_s=1000",
                "dataset.window_s",
                "DCNet's windows",
            ),
            (
                "calibration.monte_carlo_runs=1000000000",
                "calibration.monte_carlo_runs",
                "the paper runs 200",
            ),
            (
                "model.conv_channels=1000000",
                "model.conv_channels",
                "the paper's convolutions",
            ),
            (
                "model.fc_widths=[100000000, 64, 32]",
                "model.fc_widths[0]",
                "the paper's widest layer",
            ),
            (
                "training.epochs=10000000",
                "training.epochs",
                "the paper trains for 100",
            ),
            (
                "training.batch_size=100000000",
                "training.batch_size",
                "hold 256",
            ),
        ] {
            let error = quick_faults(&[set]);
            assert!(
                error.contains(&format!("--set {set}: {key}: ")),
                "{set}: {error}"
            );
            assert!(error.contains(why), "{set}: {error}");
            assert_eq!(
                error.lines().count(),
                1,
                "{set}: one fault, no echoes: {error}"
            );
        }
        let combinations = quick_faults(&[
            "grid.scale_pct={start = 0.1, stop = 100.0, step = 0.1}",
            "grid.bias_cm_s={start = 0.1, stop = 10.0, step = 0.1}",
        ]);
        assert!(
            combinations.contains(": grid: 200000 combinations is above 100000"),
            "{combinations}"
        );
    }
}
