//! `calibrate --report`: the operator's report of one recording calibrated against a
//! velocity reference. Known answers on a synthetic dive with one lost ping and one
//! spike: the residual figure's caption gives the RMSE before and after of the samples
//! it draws, which are the printed ones; the filter's figure gives the printed settling
//! time; `report.html` stands alone (every figure inlined as a PNG that decodes, no
//! address outside the page, no script); `--report` takes a folder only as
//! `--report=DIR`. (Against fixes: `blackout`; several recordings: `operator`.)

use crate::bags::TERMS;
use crate::common::installed::{INSTALLED, write_installed};
use crate::common::{dcnet, stderr, stdout};
use base64::Engine;
use std::path::Path;

/// Writes the synthetic dive, its 101st ping lost (no velocity) and its 201st a spike
/// of 1 m/s forward, the DVL's stamps `shift_s` late; its DVL file, and the arguments
/// that calibrate it.
pub(crate) fn dive(d: &Path, shift_s: f64) -> (String, Vec<String>) {
    write_installed(d, 1, &[], INSTALLED, 11);
    let dvl = d.join("Trajectory1/DVL_trajectory1.csv");
    let text = std::fs::read_to_string(&dvl).unwrap();
    let rows: Vec<String> = (text.lines().enumerate())
        .map(|(k, line)| {
            let mut cells: Vec<String> = line.split(',').map(String::from).collect();
            if k > 0 {
                cells[0] = (cells[0].parse::<f64>().unwrap() + shift_s).to_string();
            }
            match k {
                101 => cells[1] = String::new(),
                201 => cells[1] = (cells[1].parse::<f64>().unwrap() + 1.0).to_string(),
                _ => {}
            }
            cells.join(",")
        })
        .collect();
    std::fs::write(&dvl, rows.join("\n") + "\n").unwrap();
    let reference = d.join("Trajectory1/GT_trajectory1.csv");
    let dvl = dvl.display().to_string();
    let args = [
        "calibrate",
        &dvl,
        "--reference",
        reference.to_str().unwrap(),
        TERMS,
    ];
    (dvl.clone(), args.map(String::from).to_vec())
}

/// The number after `label` in `text`, up to the next space.
fn after<'a>(text: &'a str, label: &str) -> &'a str {
    let start = text
        .find(label)
        .unwrap_or_else(|| panic!("{label} not in {text}"))
        + label.len();
    text[start..].split_whitespace().next().unwrap()
}

#[test]
fn a_calibrations_report_draws_the_printed_numbers_and_stands_alone() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (_, args) = dive(d, 0.0);
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    // `--report` takes its folder only as --report=DIR: before the DVL file, it leaves it
    // be.
    let first = [
        &["calibrate", "--report"][..],
        &args[1..],
        &["--out", "cal"],
    ]
    .concat();
    let output = dcnet(d, &first);
    assert!(output.status.success(), "{}", stderr(&output));
    let printed = stdout(&output);
    let markdown = std::fs::read_to_string(d.join("cal/report.md")).unwrap();
    caption_is_printed(&printed, &markdown);
    let marks = "samples scored, outliers aside; 1 outlier ×; 1 sample left out ▼";
    assert!(markdown.contains(marks), "{markdown}");
    assert!(printed.contains("1 with no velocity"), "{printed}");
    let settled = after(&printed, "\nafter ");
    assert!(
        markdown.contains(&format!("; settled after {settled} s")),
        "{markdown}"
    );
    // The printed terms table is the report's.
    assert!(markdown.contains("| lever arm x"), "{markdown}");
    for stem in ["residual", "filter_terms"] {
        for extension in ["png", "svg"] {
            assert!(
                d.join(format!("cal/{stem}.{extension}")).is_file(),
                "{stem}.{extension}"
            );
        }
    }
    let html = std::fs::read_to_string(d.join("cal/report.html")).unwrap();
    stands_alone(&html, 2);
    // --report DIR writes there.
    let output = dcnet(
        d,
        &[&args[..], &["--out", "again", "--report=elsewhere"]].concat(),
    );
    assert!(output.status.success(), "{}", stderr(&output));
    assert!(d.join("elsewhere/report.html").is_file());
}

/// The residual figure's caption in `markdown` gives the RMSE before and after, and the
/// count of samples, that `printed` gives.
fn caption_is_printed(printed: &str, markdown: &str) {
    // "… outliers aside: 19.73 cm/s (x …) before, 2.81 cm/s (x …) after"
    let line = (printed.lines())
        .find(|l| l.starts_with("RMSE against the reference"))
        .unwrap();
    let before = after(line, "outliers aside: ");
    let after_cm_s = (line.rsplit(") before, ").next().unwrap().split(' ').next()).unwrap();
    // The count printed is the samples the RMSE after is of: the caption's.
    let count = after(line, "body frame, on the ");
    let caption = format!("RMSE {before} → {after_cm_s} cm/s, total over the {count} samples");
    assert!(markdown.contains(&caption), "{caption}\nnot in\n{markdown}");
}

/// The DVL's clock 20 s late, found by a search: samples at the ends are scored before
/// or after only (the reference covers t or t + τ), and the caption still gives the
/// printed RMSE, each of its own samples.
#[test]
fn a_searched_clocks_report_gives_the_printed_numbers() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (_, args) = dive(d, 20.0);
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    let more = ["--search-s", "30", "--out", "late", "--report"];
    let output = dcnet(d, &[&args[..], &more].concat());
    assert!(output.status.success(), "{}", stderr(&output));
    let markdown = std::fs::read_to_string(d.join("late/report.md")).unwrap();
    caption_is_printed(&stdout(&output), &markdown);
}

/// `html` needs nothing beyond itself: `figures` images, each a PNG inlined that
/// decodes, no other source or link to an address, no script.
fn stands_alone(html: &str, figures: usize) {
    let sources: Vec<&str> = html
        .split("src=\"")
        .skip(1)
        .map(|s| s.split('"').next().unwrap())
        .collect();
    assert_eq!(sources.len(), figures, "{sources:?}");
    for source in sources {
        let encoded = source
            .strip_prefix("data:image/png;base64,")
            .expect("a PNG inlined");
        let bytes = base64::engine::general_purpose::STANDARD
            .decode(encoded)
            .unwrap();
        let decoder = png::Decoder::new(std::io::Cursor::new(bytes));
        let info = decoder
            .read_info()
            .expect("a PNG that decodes")
            .info()
            .clone();
        assert!(info.width > 500 && info.height > 500, "{info:?}");
    }
    for outside in ["http:", "https:", "<script", "<link", "href=\""] {
        assert!(!html.contains(outside), "{outside} in the page");
    }
}

/// `correct --report`: the installation of the dive with a lost ping and a spike,
/// carried to another dive whose clock is 7.3 s late, found again by its search; the
/// report's clock-search figure gives the printed search's best and the clock found,
/// its residual figure the printed residual after the first seconds (its total and its
/// count of samples), and the page stands alone. Against fixes, refused by the
/// flag.
#[test]
fn a_corrections_report_draws_the_printed_residual() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (_, args) = dive(&d.join("first"), 0.0);
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    let save = ["--save", "installation.toml", "--out", "cal"];
    let output = dcnet(d, &[&args[..], &save].concat());
    assert!(output.status.success(), "{}", stderr(&output));
    let (next, next_args) = dive(&d.join("next"), 7.3);
    let reference = next_args[3].as_str();
    let correct = [
        "correct",
        next.as_str(),
        "--reference",
        reference,
        "--installation",
        "installation.toml",
        "--out",
        "corrected",
        "--report",
    ];
    let output = dcnet(d, &correct);
    assert!(output.status.success(), "{}", stderr(&output));
    let printed = stdout(&output);
    assert!(printed.contains("clock found again"), "{printed}");
    // "residual after the first 60 s: 3.52 cm/s in total (… body axes, over 338 samples, …"
    let line = (printed.lines())
        .find(|l| l.starts_with("residual after the first"))
        .unwrap();
    let total = after(line, " s: ");
    let count = after(line, "body axes, over ");
    let markdown = std::fs::read_to_string(d.join("corrected/report.md")).unwrap();
    let caption = format!("→ {total} cm/s, total over the {count} samples scored");
    assert!(markdown.contains(&caption), "{caption}\nnot in\n{markdown}");
    assert!(markdown.contains("clock found again"), "{markdown}");
    // The clock search's caption gives the printed search's best and least squares' clock.
    let best = after(&printed, "put the time offset at ");
    let found = after(&printed, "least squares at ");
    let half_width = after(&printed, "(95 %: ± ");
    let search = format!("its best {best} s at ");
    let fitted = format!("least squares from there {found} s ± {half_width} s (95 %)");
    for expected in [search, fitted, "the clock search over ±30 s".to_string()] {
        assert!(
            markdown.contains(&expected),
            "{expected}\nnot in\n{markdown}"
        );
    }
    let html = std::fs::read_to_string(d.join("corrected/report.html")).unwrap();
    stands_alone(&html, 2);
}
