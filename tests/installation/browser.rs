//! The operator's `report.html` opened in a real browser, headless Chromium (Debian's
//! `chromium`, which `.ci/run` installs): a screenshot is taken and is not blank; a
//! probe script added to a copy of the page counts, once it has loaded, its images,
//! those that did not load, and the resources it requested (the browser's own record
//! of every fetch a page makes; an image inlined as `data:` is none): every image
//! loaded and nothing was requested. A copy with one image broken, and one with an
//! image from an address, are caught by the same probe. Ignored where there is no
//! Chromium, as the recording tests are where there are no recordings.

use crate::common::{dcnet, stderr};
use std::path::{Path, PathBuf};
use std::process::Command;

/// Where Debian installs Chromium.
const CHROMIUM: &str = "/usr/bin/chromium";

/// Chromium headless on `page` with `extra` flags, its profile in `profile`; its
/// standard output. The flags keep it from calling home (updates, sync, its own
/// services), so that what the network log shows is the page's.
fn chromium(page: &Path, profile: &Path, extra: &[String]) -> String {
    let output = Command::new(CHROMIUM)
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--disable-quic",
            "--no-first-run",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
            "--virtual-time-budget=10000",
        ])
        .arg(format!("--user-data-dir={}", profile.display()))
        .args(extra)
        .arg(format!("file://{}", page.display()))
        .output()
        .expect("chromium runs");
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    String::from_utf8_lossy(&output.stdout).into_owned()
}

/// A copy of the page `html` with a probe that, once every image has loaded or failed,
/// titles the page with how many images there are, how many did not load, and how many
/// resources the page requested.
fn probed(html: &str) -> String {
    let probe = "<script>window.addEventListener('load', () => { const all = [...document.images]; const broken = all.filter(i => !(i.complete && i.naturalWidth > 0)).length; const fetched = performance.getEntriesByType('resource').filter(e => !e.name.startsWith('data:')).length; document.title = `images ${all.length} broken ${broken} fetched ${fetched}`; });</script>";
    html.replacen("</body>", &format!("{probe}</body>"), 1)
}

/// The page's title once loaded in Chromium, with its DOM dumped.
fn loaded_title(page: &Path, profile: &Path) -> String {
    let dom = chromium(page, profile, &["--dump-dom".to_string()]);
    let start = dom.find("<title>").expect("a title") + "<title>".len();
    let end = dom.find("</title>").expect("a title's end");
    dom[start..end].to_string()
}

#[test]
#[ignore = "needs Debian's chromium (apt-get install chromium), which .ci/run installs"]
fn a_report_opens_in_chromium_every_image_loaded_and_nothing_fetched() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (_, args) = crate::report::dive(d, 0.0);
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    let output = dcnet(d, &[&args[..], &["--out", "cal", "--report"]].concat());
    assert!(output.status.success(), "{}", stderr(&output));
    let page: PathBuf = d.join("cal/report.html");
    let html = std::fs::read_to_string(&page).unwrap();

    // The page itself: a screenshot.
    let shot = d.join("shot.png");
    chromium(
        &page,
        &d.join("profile-page"),
        &[
            format!("--screenshot={}", shot.display()),
            "--window-size=1280,3000".to_string(),
        ],
    );
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&shot).unwrap()));
    let mut reader = decoder.read_info().expect("a PNG screenshot");
    let mut pixels = vec![0; reader.output_buffer_size().unwrap()];
    let frame = reader.next_frame(&mut pixels).unwrap();
    assert_eq!((frame.width, frame.height), (1280, 3000));
    let distinct: std::collections::HashSet<&[u8]> = pixels[..frame.buffer_size()]
        .chunks(frame.color_type.samples())
        .collect();
    assert!(
        distinct.len() > 50,
        "a blank screenshot: {} colours",
        distinct.len()
    );

    // Every image loaded, nothing requested; one image broken, or fetched, is caught.
    let probe = d.join("cal/probed.html");
    let title = |html: &str, profile: &str| {
        std::fs::write(&probe, probed(html)).unwrap();
        loaded_title(&probe, &d.join(profile))
    };
    assert_eq!(title(&html, "probe"), "images 2 broken 0 fetched 0");
    let at = html.find("base64,").unwrap() + "base64,".len();
    let broken = format!("{}AAAA{}", &html[..at], &html[at + 40..]);
    assert_eq!(title(&broken, "broken"), "images 2 broken 1 fetched 0");
    let start = html.find("data:image/png").unwrap();
    let end = start + html[start..].find('"').unwrap();
    let fetched = format!(
        "{}http://127.0.0.1:9/figure.png{}",
        &html[..start],
        &html[end..]
    );
    assert_eq!(title(&fetched, "fetched"), "images 2 broken 1 fetched 1");
}
