//! The HTML report as a browser shows it: a real run of a tiny experiment, its report opened by
//! headless Chromium from a file:// URL with the network off. A copy of the page with a short
//! inline script reports, in the dumped DOM, how many tables and cells exist, how many images
//! decoded with a non-zero natural size, and where the first table and image are drawn; a
//! screenshot then must show ink (pixel variance) in those two places.
//!
//! A second test runs the Benthin benchmark (`experiments/benthin09-benchmark.toml`, as written
//! but at 32² and one pass) and checks its report shows every heat map (issue 33), and that
//! `experiments/packet.toml` asks for the same maps.
//!
//! CI installs Chromium (`.ci/setup`); without it this test fails, unless `RAYLAB_NO_BROWSER` is set
//! (then it prints why it skipped).

use std::path::{Path, PathBuf};
use std::process::Command;

use raylab::experiment::results::report;
use raylab::experiment::{run_experiment, RunOverrides};

const EXPERIMENT: &str = "name = \"browser\"\nscenes = [{ name = \"room\", size = 1 }]\n\
    tracers = [\"reference\", \"obvhs\"]\nrays = [\"primary\"]\nresolution = { width = 32, height = 32 }\n\
    frames = 1\nthreads = [1]\nwarmup = 0\nrepeats = 1\n\
    [[tables]]\ntitle = \"Table 1: rays\"\nrows = \"tracer\"\nmetric = \"rays\"\n\
    columns = [{ label = \"ours\" }, { label = \"paper\", paper = { reference = 1024 } }]\n";

/// Reports itself into the DOM once every image has loaded.
const PROBE: &str = "<script>window.addEventListener('load', () => {\
    const imgs = [...document.images];\
    const decoded = imgs.filter(i => i.complete && i.naturalWidth > 0 && i.naturalHeight > 0);\
    const box = e => { const r = e.getBoundingClientRect(); \
        return [r.left, r.top, r.width, r.height].map(Math.round).join(','); };\
    const p = document.createElement('pre'); p.id = 'probe';\
    p.textContent = `images=${imgs.length} decoded=${decoded.length} \
        tables=${document.querySelectorAll('table').length} cells=${document.querySelectorAll('td').length} \
        table=${box(document.querySelector('table'))} image=${box(imgs[0])} height=${document.body.scrollHeight}`;\
    document.body.appendChild(p); });</script>";

fn chromium() -> Option<PathBuf> {
    let path = std::env::var_os("PATH")?;
    ["chromium", "chromium-browser", "google-chrome"]
        .iter()
        .flat_map(|name| std::env::split_paths(&path).map(move |dir| dir.join(name)))
        .find(|p| p.is_file())
}

/// Runs headless Chromium on `page` with `args`, killed after two minutes (coreutils `timeout`) so a
/// stuck browser fails the test instead of hanging CI; returns its standard output.
fn browse(browser: &Path, profile: &Path, page: &Path, args: &[String]) -> String {
    let out = Command::new("timeout")
        .arg("120")
        .arg(browser)
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--disable-quic",
            "--no-first-run",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
            "--hide-scrollbars",
            "--force-device-scale-factor=1",
            "--virtual-time-budget=10000",
        ])
        .arg(format!("--user-data-dir={}", profile.display()))
        .args(args)
        .arg(format!("file://{}", page.display()))
        .output()
        .expect("chromium starts");
    assert!(
        out.status.success(),
        "chromium failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// The probe's `key=value` fields.
fn field<'a>(probe: &'a str, key: &str) -> &'a str {
    probe
        .split_whitespace()
        .find_map(|f| f.strip_prefix(key).and_then(|v| v.strip_prefix('=')))
        .unwrap_or_else(|| panic!("no {key} in {probe}"))
}

fn rect(text: &str) -> [u32; 4] {
    let v: Vec<u32> = text.split(',').map(|n| n.parse().unwrap()).collect();
    [v[0], v[1], v[2], v[3]]
}

/// Variance of luminance over a rectangle of the screenshot.
fn variance(shot: &image::RgbImage, [x, y, w, h]: [u32; 4]) -> f64 {
    let mut values = Vec::new();
    for py in y..(y + h).min(shot.height()) {
        for px in x..(x + w).min(shot.width()) {
            let [r, g, b] = shot.get_pixel(px, py).0;
            values.push(0.299 * r as f64 + 0.587 * g as f64 + 0.114 * b as f64);
        }
    }
    assert!(
        !values.is_empty(),
        "rectangle {x},{y},{w},{h} is off the screenshot"
    );
    let mean = values.iter().sum::<f64>() / values.len() as f64;
    values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / values.len() as f64
}

/// Chromium, or `None` when `RAYLAB_NO_BROWSER` says to skip.
fn browser_or_skip() -> Option<PathBuf> {
    if let Some(why) = std::env::var_os("RAYLAB_NO_BROWSER") {
        println!("skipped: RAYLAB_NO_BROWSER={}", why.to_string_lossy());
        return None;
    }
    Some(chromium().expect(
        "the HTML report test needs Chromium (`apt-get install chromium`, as .ci/setup does); \
         set RAYLAB_NO_BROWSER=1 to skip it",
    ))
}

/// The probe's line from the DOM Chromium dumps of `html` with the probe added.
fn probe_of(browser: &Path, work: &Path, html: &str) -> String {
    let probe_page = work.join("probe.html");
    std::fs::write(
        &probe_page,
        html.replace("</body>", &format!("{PROBE}</body>")),
    )
    .unwrap();
    let dom = browse(
        browser,
        &work.join("profile"),
        &probe_page,
        &["--dump-dom".into()],
    );
    let start = dom.find("<pre id=\"probe\">").expect("the probe ran") + 16;
    dom[start..start + dom[start..].find("</pre>").unwrap()].to_string()
}

#[test]
fn chromium_shows_the_benthin_benchmarks_heat_maps() {
    let Some(browser) = browser_or_skip() else {
        return;
    };
    if raylab::scene::library::load_scene("conference-area-light", None).is_err() {
        println!("skipped: real scenes not found; set RAYLAB_SCENES to ../shared/scenes");
        return;
    }
    let packet = std::fs::read_to_string("experiments/packet.toml").unwrap();
    assert!(packet.contains("\nheatmaps = [\"box\", \"triangle\"]\n"));
    let work = std::env::temp_dir().join(format!("raylab-heatmaps-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&work);
    std::fs::create_dir_all(&work).unwrap();
    let overrides = RunOverrides {
        output: Some(work.join("results")),
        resolution: Some((32, 32)),
        threads: Some(vec![1]),
        warmup: Some(0),
        repeats: Some(1),
        ..RunOverrides::default()
    };
    let experiment = Path::new("experiments/benthin09-benchmark.toml");
    let dir = run_experiment(experiment, &overrides).unwrap();
    // Two scenes × (primary, soft shadows) × (box, triangle).
    let mut maps: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|name| name.starts_with("heatmap-"))
        .collect();
    maps.sort();
    assert_eq!(maps.len(), 8, "{maps:?}");
    assert!(maps.contains(&"heatmap-sibenik-area-light-soft_shadow-box.png".to_string()));
    let page = report::write(std::slice::from_ref(&dir), false, None).unwrap();
    let html = std::fs::read_to_string(&page).unwrap();
    for name in &maps {
        assert!(
            html.contains(&format!("<img alt=\"{name}\"")),
            "{name} not in the page"
        );
    }
    let probe = probe_of(&browser, &work, &html);
    // Every image decoded with a size: the maps among them.
    let images: usize = field(&probe, "images").parse().unwrap();
    assert!(images >= maps.len(), "{probe}");
    assert_eq!(field(&probe, "decoded"), images.to_string(), "{probe}");
    let _ = std::fs::remove_dir_all(&work);
}

#[test]
fn chromium_renders_the_reports_tables_and_images() {
    let Some(browser) = browser_or_skip() else {
        return;
    };
    let work = std::env::temp_dir().join(format!("raylab-browser-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&work);
    std::fs::create_dir_all(&work).unwrap();
    let experiment = work.join("browser.toml");
    std::fs::write(&experiment, EXPERIMENT).unwrap();
    let overrides = RunOverrides {
        output: Some(work.join("results")),
        ..RunOverrides::default()
    };
    let dir = run_experiment(&experiment, &overrides).unwrap();
    let pngs = std::fs::read_dir(&dir)
        .unwrap()
        .filter(|e| {
            e.as_ref()
                .unwrap()
                .path()
                .extension()
                .is_some_and(|x| x == "png")
        })
        .count();
    assert!(pngs >= 2, "the run drew {pngs} plots");
    let page = report::write(std::slice::from_ref(&dir), false, None).unwrap();
    let html = std::fs::read_to_string(&page).unwrap();
    let probe = &probe_of(&browser, &work, &html);
    let profile = work.join("profile");
    assert_eq!(field(probe, "images"), pngs.to_string(), "{probe}");
    assert_eq!(field(probe, "decoded"), pngs.to_string(), "{probe}");
    // Machines, scenes, Table 1 and runs.csv at least.
    assert!(
        field(probe, "tables").parse::<usize>().unwrap() >= 4,
        "{probe}"
    );
    assert!(
        field(probe, "cells").parse::<usize>().unwrap() >= 20,
        "{probe}"
    );
    let (table, img) = (rect(field(probe, "table")), rect(field(probe, "image")));
    assert!(
        table[2] > 0 && table[3] > 0 && img[2] > 0 && img[3] > 0,
        "{probe}"
    );

    // Tall enough to hold the first image.
    let height = (img[1] + img[3] + 20).max(800);
    let shot = work.join("shot.png");
    browse(
        &browser,
        &profile,
        &page,
        &[
            format!("--screenshot={}", shot.display()),
            format!("--window-size=1200,{height}"),
        ],
    );
    let shot = image::open(&shot).unwrap().to_rgb8();
    assert_eq!(shot.width(), 1200);
    // Text and borders in the table, a plot in the image: not a flat colour.
    assert!(variance(&shot, table) > 100.0, "table region is blank");
    assert!(variance(&shot, img) > 100.0, "image region is blank");
    let _ = std::fs::remove_dir_all(&work);
}
