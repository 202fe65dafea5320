//! paper.toml on the real Snapir recordings: the baseline column of the paper, the
//! floor, and the training set counts. Ignored unless asked for
//! (`cargo test --release -- --ignored`), since a fresh clone has no recordings.

use crate::common;
use common::*;

#[test]
#[ignore = "needs the Snapir recordings: dcnet-exp data fetch"]
fn paper_spec_reproduces_the_baseline_column_and_the_floor() {
    let project = project(true);
    // The model-based methods only: DCNet's 100 epochs on the full grid take hours.
    let output = dcnet(
        project.path(),
        &[
            "run",
            "experiments/paper.toml",
            "--set",
            r#"estimators.kinds=["baseline", "least_squares", "floor"]"#,
        ],
    );
    assert!(output.status.success(), "{}", stderr(&output));
    let results = project.path().join("results/paper");

    let calibration = calibration_rows(&results);
    for (dvl, published, tolerance) in [("DVL1", 5.94, 0.03), ("DVL2", 0.74, 0.01)] {
        let t_conv: Vec<&Row> = calibration
            .iter()
            .filter(|r| r.dvl == dvl && r.estimator == "baseline" && r.selected)
            .collect();
        assert_eq!(t_conv.len(), 1);
        assert_eq!(t_conv[0].at, "100", "{dvl} baseline T_conv");
        assert!(
            (t_conv[0].rmse_cm_s - published).abs() <= tolerance,
            "{dvl} baseline {} vs {published}",
            t_conv[0].rmse_cm_s
        );
    }

    let evaluation = evaluation_rows(&results);
    for trajectory in ["T6", "T7", "T8", "T9", "T10Test"] {
        let baseline = find_row(&evaluation, "DVL2", "baseline", None, Some(trajectory));
        assert!(
            (baseline.rmse_cm_s - 0.74).abs() <= 0.01,
            "{trajectory}: {}",
            baseline.rmse_cm_s
        );
        assert_eq!(baseline.improvement_pct, Some(0.0));
        let floor = find_row(&evaluation, "DVL2", "floor", None, Some(trajectory));
        // Beam noise 0.02 cm/s × 2.97 / 1.01: what is left after a perfect correction.
        assert!(
            (floor.rmse_cm_s - 0.0588).abs() < 0.002,
            "floor {trajectory}: {}",
            floor.rmse_cm_s
        );
    }
    let floor_dvl1 = find_row(&evaluation, "DVL1", "floor", None, Some("T6"));
    assert!(
        (floor_dvl1.rmse_cm_s - 5.88).abs() < 0.05,
        "DVL1 floor {}",
        floor_dvl1.rmse_cm_s
    );

    // Least squares with a scalar bias subtracts the z bias from x and y too:
    // sqrt(2)·0.745 cm/s of new error on top of the uncorrected scale.
    let em3 = calibration
        .iter()
        .find(|r| r.dvl == "DVL2" && r.error_model.as_deref() == Some("EM3") && r.selected)
        .unwrap();
    assert!(em3.rmse_cm_s > 1.5, "EM3 least squares {}", em3.rmse_cm_s);
}

#[test]
#[ignore = "needs the Snapir recordings: dcnet-exp data fetch"]
fn data_info_counts_the_paper_windows() {
    let project = project(true);
    let output = dcnet(project.path(), &["data", "info", "experiments/paper.toml"]);
    assert!(output.status.success(), "{}", stderr(&output));
    let text = stdout(&output);
    // T1-T5: 148 + 136 + 51 + 96 + 65 windows of 10 s every 9 s.
    assert!(
        text.contains(
            "windows: 496 per combination × 1134 = 562464 (450198 train, 112266 validation)"
        ),
        "{text}"
    );
    assert!(text.contains("published: 835758 windows"), "{text}");
    assert!(
        text.contains(&format!("dataset size: {} bytes", 562464 * 90 * 4 + 562464)),
        "{text}"
    );
    assert!(
        text.contains("| T10Cal     | calibration | V_test.npy [0, 200)"),
        "{text}"
    );
}
