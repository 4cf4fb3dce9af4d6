//! End-to-end runs of experiments on tiny scenes (`experiment::plan::quad_scenes`) and built-in
//! ones: what a run writes (runs.csv, histograms.csv, verify.csv, plots, tables, figures, meta.json,
//! summary.md), its values against hand-worked counts, and what it refuses.
use std::cell::Cell;
use std::collections::{BTreeMap, HashMap};
use std::fs;

use std::path::{Path, PathBuf};

use raylab::accel::embree::{EMBREE4_BUILT, EMBREE4_HINT};
use raylab::error::{Error, Result};
use raylab::experiment::plan::quad_scenes::load_quads;
use raylab::experiment::plan::table_spec::RowsSpec;
use raylab::experiment::record::files::*;
use raylab::experiment::record::{check_row, histogram_row, run_row, selection};
use raylab::experiment::results::summary::Summary;
use raylab::experiment::{run, Chatter, Experiment, Plan, RunOverrides, SceneLoader, SceneSpec};
use raylab::scene::library::load_scene;
use raylab::scene::Scene;
use raylab::tracers::registry::TINYBVH_BUILT;

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("raylab-run-{name}-{}", std::process::id()));
    let _ = fs::remove_dir_all(&dir);
    dir
}

const TEXT: &str = "name = \"t\"\nscenes = [\"lit\", \"dark\", \"moving\"]\n\
    tracers = [\"reference\", { name = \"reference\", params = { leaf_size = 1 } }]\n\
    rays = [\"primary\", \"shadow\", \"diffuse\"]\nresolution = { width = 32, height = 32 }\n\
    frames = 3\nthreads = [1, 2]\nwarmup = 0\nrepeats = 2\n";

fn experiment(output: &Path) -> Experiment {
    let mut exp = Experiment::parse(Path::new("t.toml"), TEXT).unwrap();
    exp.output = output.to_path_buf();
    exp
}

/// Parses the experiment `text`, runs it into `out` with scenes from `load`, and returns the
/// run's directory.
fn run_text(text: &str, out: &Path, load: SceneLoader) -> PathBuf {
    let mut exp = Experiment::parse(Path::new("t.toml"), text).unwrap();
    exp.output = out.to_path_buf();
    run(&exp, text, &RunOverrides::default(), load).unwrap()
}

fn read_csv(path: &Path) -> (Vec<String>, Vec<HashMap<String, String>>) {
    let mut reader = csv::Reader::from_path(path).unwrap();
    let header: Vec<String> = reader.headers().unwrap().iter().map(String::from).collect();
    let rows = reader
        .records()
        .map(|r| {
            header
                .iter()
                .cloned()
                .zip(r.unwrap().iter().map(String::from))
                .collect()
        })
        .collect();
    (header, rows)
}

/// The unit quad seen from z = 4 with a 30° field of view at 32×32: pixel centres at
/// (2x − 31)/32 · tan 15° · distance hit when that is below 1. At distance 4 (frame 0, and
/// every frame of the static scenes) x = 1..=30: 900 hits; the moving quad is at distance 5
/// then 6: x = 4..=27 (576 hits), x = 6..=25 (400 hits).
fn expected_primary_hits(scene: &str, frame: usize) -> usize {
    match (scene, frame) {
        ("moving", 1) => 576,
        ("moving", 2) => 400,
        _ => 900,
    }
}

#[test]
fn soft_shadows_are_one_ray_per_light_sample() {
    let out = scratch("soft");
    let text = "name = \"t\"\nscenes = [\"soft\", \"lit\"]\ntracers = [\"reference\"]\n\
        rays = [\"primary\", \"soft_shadow\"]\nsoft_shadow = { samples = 4 }\n\
        resolution = { width = 32, height = 32 }\nwarmup = 0\nrepeats = 1\n";
    let dir = run_text(text, &out, &load_quads);
    let (_, runs) = read_csv(&dir.join(RUNS_CSV));
    // The point-lit scene has no soft shadows; the quad-lit one has 4 unblocked rays per
    // primary hit, all in front of the quad.
    let soft: Vec<_> = runs
        .iter()
        .filter(|r| r["ray_kind"] == "soft_shadow")
        .collect();
    assert_eq!(soft.len(), 1, "{runs:?}");
    let r = soft[0];
    assert_eq!(r["scene"], "soft");
    let hits = expected_primary_hits("soft", 0);
    assert_eq!(
        (r["rays"].as_str(), r["hits"].as_str()),
        (&*(4 * hits).to_string(), "0")
    );
    assert_eq!(r["counted_rays"], r["rays"]);
    assert_eq!(r["bounce_depth"], "1");
    // The sampled check covers the query: 4 blocks of 256 points (1024 rays at 4 samples)
    // reach all 900 points, every sample ray agreeing with Embree.
    let (_, checks) = read_csv(&dir.join(VERIFY_CSV));
    let soft: Vec<_> = checks
        .iter()
        .filter(|c| c["ray_kind"] == "soft_shadow")
        .collect();
    assert_eq!(soft.len(), 1, "{checks:?}");
    assert_eq!(
        (
            soft[0]["checked_rays"].as_str(),
            soft[0]["unexplained"].as_str()
        ),
        (&*(4 * hits).to_string(), "0")
    );
}

#[test]
fn end_to_end_on_hand_made_scenes() {
    let out = scratch("e2e");
    let exp = experiment(&out);
    let dir = run(&exp, TEXT, &RunOverrides::default(), &load_quads).unwrap();
    assert_eq!(dir.parent().unwrap(), out.join("t"));

    let (header, runs) = read_csv(&dir.join(RUNS_CSV));
    assert_eq!(header, run_row::runs_columns());
    // frames 3 × instances 2 × threads 2 × kinds (lit 3 + dark 2 + moving 3).
    assert_eq!(runs.len(), 3 * 2 * 2 * (3 + 2 + 3));
    assert!(runs
        .iter()
        .all(|r| r.len() == run_row::runs_columns().len()));
    // The counting pass runs once, on the widest pool: its cost is beside the 2-thread rows.
    for r in &runs {
        let overhead = r["counting_overhead"].parse::<f64>();
        assert_eq!(overhead.is_ok(), r["threads"] == "2", "row {r:?}");
        assert!(overhead.map_or(true, |o| o > 0.0));
    }
    for r in &runs {
        let (scene, frame, kind) = (
            r["scene"].as_str(),
            r["frame"].parse::<usize>().unwrap(),
            r["ray_kind"].as_str(),
        );
        let hits = expected_primary_hits(scene, frame);
        // Shadow and diffuse rays leave every primary hit (the light is in front of the quad);
        // nothing blocks the light and a bounce off a lone plane hits nothing.
        let (rays, hit) = match kind {
            "primary" => (1024, hits),
            "shadow" | "diffuse" => (hits, 0),
            other => panic!("{other}"),
        };
        assert_eq!(
            (
                r["rays"].parse::<usize>().unwrap(),
                r["hits"].parse::<usize>().unwrap()
            ),
            (rays, hit),
            "{r:?}"
        );
        // The reference tracer counts every ray it is given, once.
        assert_eq!(r["counted_rays"], r["rays"]);
        assert!(
            r["seconds_min"].parse::<f64>().unwrap() <= r["seconds_median"].parse::<f64>().unwrap()
        );
        let static_scene = scene != "moving";
        let reused = static_scene && frame > 0;
        assert_eq!(r["build"], if reused { "reused" } else { "built" });
        assert_eq!(r["build_seconds"] == "0", reused, "{r:?}");
        assert_eq!(
            r["structure"],
            if r["parameters"].is_empty() {
                "bvh"
            } else {
                "bvh[leaf_size=1]"
            }
        );
    }
    assert!(runs
        .iter()
        .all(|r| r["scene"] != "dark" || r["ray_kind"] != "shadow"));

    // Per-depth counts add up to the totals of the same case.
    let (header, histograms) = read_csv(&dir.join(HISTOGRAMS_CSV));
    assert_eq!(header, histogram_row::HISTOGRAM_COLUMNS);
    let mut sums: HashMap<(String, String, String, String), (u64, u64)> = HashMap::new();
    for h in &histograms {
        let key = (
            h["scene"].clone(),
            h["frame"].clone(),
            h["parameters"].clone(),
            h["ray_kind"].clone(),
        );
        let sum = sums.entry(key).or_default();
        sum.0 += h["aabb_tests"].parse::<u64>().unwrap();
        sum.1 += h["triangle_tests"].parse::<u64>().unwrap();
    }
    // One histogram per (scene, frame, instance, kind): 3 × 2 × 8.
    assert_eq!(sums.len(), 48);
    for r in runs.iter().filter(|r| r["threads"] == "1") {
        let key = (
            r["scene"].clone(),
            r["frame"].clone(),
            r["parameters"].clone(),
            r["ray_kind"].clone(),
        );
        let totals = (
            r["aabb_tests"].parse().unwrap(),
            r["triangle_tests"].parse().unwrap(),
        );
        assert_eq!(sums[&key], totals, "{key:?}");
    }
    // The quad's two triangles both span its whole box. Default parameters: the root is one
    // leaf; all 1024 rays test its box, the 900 that hit it visit it and test both triangles.
    let counts = |parameters: &str| {
        let r = runs
            .iter()
            .find(|r| {
                r["scene"] == "lit" && r["parameters"] == parameters && r["ray_kind"] == "primary"
            })
            .unwrap();
        [
            r["aabb_tests"].clone(),
            r["nodes_visited"].clone(),
            r["triangle_tests"].clone(),
        ]
    };
    assert_eq!(counts(""), ["1024", "900", "1800"]);
    // leaf_size = 1: a root over two leaves. The 124 rays that miss test the root box only;
    // the 900 that hit test it and both children.
    assert_eq!(counts("leaf_size=1")[0], (900 * 3 + 124).to_string());

    let meta: serde_json::Value =
        serde_json::from_str(&fs::read_to_string(dir.join(META_JSON)).unwrap()).unwrap();
    assert_eq!(meta["experiment_file"]["contents"], TEXT);
    assert_eq!(
        meta["plan"]["scenes"][1]["ray_kinds"],
        serde_json::json!(["primary", "diffuse"])
    );
    assert_eq!(meta["threads"], serde_json::json!([1, 2]));
    assert_eq!(meta["run_id"], dir.file_name().unwrap().to_str().unwrap());
    assert!(
        meta["versions"]["embree"]
            .as_str()
            .unwrap()
            .starts_with("3."),
        "{}",
        meta["versions"]
    );

    let mut pngs: Vec<String> = fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .filter(|n| n.ends_with(".png"))
        .collect();
    pngs.sort();
    assert_eq!(pngs.len(), 3 * 3, "{pngs:?}");

    // Every ray batch was checked whole (≤ 4096 rays) against Embree: no disagreement on a
    // quad seen head-on but for ties on its diagonal.
    let (header, checks) = read_csv(&dir.join(VERIFY_CSV));
    assert_eq!(header, check_row::VERIFY_COLUMNS);
    assert_eq!(checks.len(), 3 * 2 * (3 + 2 + 3));
    for c in &checks {
        let rays = runs
            .iter()
            .find(|r| {
                ["scene", "frame", "parameters", "ray_kind"]
                    .iter()
                    .all(|k| r[*k] == c[*k])
            })
            .unwrap()["rays"]
            .clone();
        assert_eq!(c["checked_rays"], rays, "{c:?}");
        assert_eq!(c["unexplained"], "0", "{c:?}");
    }
    // The saved summary is the one recomputed from the files.
    let saved = fs::read_to_string(dir.join(SUMMARY_MD)).unwrap();
    assert_eq!(saved, Summary::read(&dir).unwrap().markdown());
    assert!(saved.contains("| lit (2 tris) | primary | — |"), "{saved}");
    fs::remove_dir_all(&out).unwrap();
}

#[test]
fn embree_tracers_share_one_build_and_count_rays_only() {
    let out = scratch("embree");
    let text = "name = \"t\"\nscenes = [\"lit\"]\ntracers = [\"embree1\", \"embree16\"]\n\
                rays = [\"primary\", \"shadow\"]\nresolution = { width = 32, height = 32 }\nrepeats = 1\n";
    let dir = run_text(text, &out, &load_quads);
    let (_, runs) = read_csv(&dir.join(RUNS_CSV));
    assert_eq!(runs.len(), 2 * 2);
    for r in &runs {
        let expected = if r["ray_kind"] == "primary" {
            ("1024", "900")
        } else {
            ("900", "0")
        };
        assert_eq!((r["rays"].as_str(), r["hits"].as_str()), expected);
        assert_eq!(r["counted_rays"], r["rays"]);
        for column in [
            "nodes_visited",
            "aabb_tests",
            "triangle_tests",
            "aabb_tests_per_ray",
        ] {
            assert_eq!(r[column], "", "{column} of {}", r["tracer"]);
        }
        // One Embree scene, built once, its time reported for both tracers.
        assert_eq!(r["build_seconds"], runs[0]["build_seconds"]);
        assert_eq!(r["structure"], "embree");
    }
    let (_, histograms) = read_csv(&dir.join(HISTOGRAMS_CSV));
    assert!(histograms.is_empty());
    assert!(dir.join("throughput_lit.png").is_file());
    assert!(!dir.join("depths_lit_embree3-1.png").exists());
    fs::remove_dir_all(&out).unwrap();
}

/// A glass quad (diffuse 0.7 under a dielectric coat) lit from above, 32×32 pixels: 900 camera
/// rays hit it, and each hit spawns one shadow ray (towards the unblocked light), one
/// reflection and one refraction ray (both leave the scene): 900 each, none hitting.
#[test]
fn a_whitted_workload_gives_one_row_per_batch_and_depth_plus_the_frame() {
    let out = scratch("whitted");
    let text = "name = \"t\"\nscenes = [\"glass\"]\ntracers = [\"reference\"]\n\
                render = { renderer = \"whitted\", max_depth = [0, 1], assembly = [\"ray_types\", \"blind\"] }\n\
                resolution = { width = 32, height = 32 }\nthreads = [1, 2]\nwarmup = 0\nrepeats = 2\n";
    let dir = run_text(text, &out, &load_quads);
    let (_, runs) = read_csv(&dir.join(RUNS_CSV));
    let rows: Vec<(String, String, String, String, String, String)> = runs
        .iter()
        .filter(|r| r["threads"] == "2")
        .map(|r| {
            let render = &r["render"];
            let assembly = if render.contains("assembly=blind") {
                "blind"
            } else {
                "ray_types"
            };
            let depth = if render.contains("max_depth=0") {
                "0"
            } else {
                "1"
            };
            (
                format!("{assembly}/{depth}"),
                r["ray_kind"].clone(),
                r["bounce_depth"].clone(),
                r["rays"].clone(),
                r["hits"].clone(),
                r["counted_rays"].clone(),
            )
        })
        .collect();
    let row = |w: &str, kind: &str, depth: &str, rays: &str, hits: &str| {
        let s = String::from;
        (s(w), s(kind), s(depth), s(rays), s(hits), s(rays))
    };
    assert_eq!(
        rows,
        [
            row("ray_types/0", "primary", "0", "1024", "900"),
            row("ray_types/0", "shadow", "1", "900", "0"),
            row("ray_types/0", "frame", "", "1924", "900"),
            row("ray_types/1", "primary", "0", "1024", "900"),
            row("ray_types/1", "shadow", "1", "900", "0"),
            row("ray_types/1", "reflection", "1", "900", "0"),
            row("ray_types/1", "refraction", "1", "900", "0"),
            row("ray_types/1", "frame", "", "3724", "900"),
            row("blind/0", "primary", "0", "1024", "900"),
            row("blind/0", "blind", "1", "900", "0"),
            row("blind/0", "frame", "", "1924", "900"),
            row("blind/1", "primary", "0", "1024", "900"),
            row("blind/1", "blind", "1", "2700", "0"),
            row("blind/1", "frame", "", "3724", "900"),
        ]
    );
    // Workloads in file order (ray_types, then blind); the same rows at 1 thread.
    assert_eq!(runs.len(), 2 * rows.len());
    for r in &runs {
        assert!(r["seconds_min"].parse::<f64>().unwrap() > 0.0);
    }
    let (_, histograms) = read_csv(&dir.join(HISTOGRAMS_CSV));
    assert!(histograms.is_empty());
    fs::remove_dir_all(&out).unwrap();
}

/// The built-in room (point light, mirror floor) at 16×16 with a lens: every sample count
/// traces spp camera rays per pixel (all hit: the room is closed), a frame row with the RMSE
/// against the 1024-spp reference, which falls as spp grows; the packet tracer's image is the
/// reference tracer's (bit-exact hits), so its RMSE is the same.
#[test]
fn a_distribution_workload_gives_rows_per_batch_and_an_rmse_that_falls_with_spp() {
    let out = scratch("drt");
    let text = "name = \"t\"\nscenes = [\"room\"]\ntracers = [\"reference\", \"packet\"]\n\
                render = { renderer = \"distribution\", spp = [1, 4, 16], aperture = 0.2, focus = 3, max_depth = 1 }\n\
                resolution = { width = 16, height = 16 }\nthreads = [1]\nwarmup = 0\nrepeats = 1\n";
    let load = |spec: &SceneSpec| raylab::scene::library::load_scene(&spec.name, spec.size);
    let dir = run_text(text, &out, &load);
    let (_, runs) = read_csv(&dir.join(RUNS_CSV));
    let spp_of = |r: &HashMap<String, String>| -> u32 {
        r["render"].rsplit("spp=").next().unwrap().parse().unwrap()
    };
    let mut rmse = BTreeMap::new();
    for tracer in ["reference", "packet"] {
        for spp in [1u32, 4, 16] {
            let rows: Vec<_> = runs
                .iter()
                .filter(|r| r["tracer"] == tracer && spp_of(r) == spp)
                .collect();
            let kinds: Vec<(&str, &str)> = rows
                .iter()
                .map(|r| (r["ray_kind"].as_str(), r["bounce_depth"].as_str()))
                .collect();
            assert_eq!(
                kinds,
                [
                    ("primary", "0"),
                    ("shadow", "1"),
                    ("reflection", "1"),
                    ("shadow", "2"),
                    ("frame", "")
                ],
                "{tracer} {spp}"
            );
            let primary = rows[0];
            assert_eq!(primary["rays"], (256 * spp).to_string());
            assert_eq!(primary["hits"], primary["rays"]);
            let total: u64 = rows[..4]
                .iter()
                .map(|r| r["rays"].parse::<u64>().unwrap())
                .sum();
            assert_eq!(rows[4]["rays"], total.to_string());
            assert!(rows[..4].iter().all(|r| r["rmse"].is_empty()));
            rmse.insert((tracer, spp), rows[4]["rmse"].parse::<f64>().unwrap());
        }
    }
    let r = |t, s| rmse[&(t, s)];
    assert!(r("reference", 4) < r("reference", 1), "{rmse:?}");
    assert!(r("reference", 16) < r("reference", 4), "{rmse:?}");
    for spp in [1, 4, 16] {
        assert_eq!(r("reference", spp), r("packet", spp));
    }
    // One error-vs-time plot: a line per tracer, a point per spp.
    let (_, points) = read_csv(&dir.join("error_vs_time.csv"));
    assert_eq!(points.len(), 6);
    assert!(dir.join("error_vs_time.png").is_file());
    // The reference image was cached under the results root.
    assert!(out.join(raylab::render::convergence::CACHE_DIR).is_dir());
    fs::remove_dir_all(&out).unwrap();
}

/// A path workload (Gribble & Ramani 2008 §4) is measured like a distribution one: a row per
/// (bounce, kind) batch with its `bounce_depth`, a frame row with the RMSE against the cached
/// reference image, and the error-vs-time plot.
/// Interleaved soft shadows (Benthin & Wald 2009) with retrace: camera rays, the first
/// visibility query, the retrace query, and a frame row with the RMSE and the share of pixels
/// retraced — the same for every tracer (the same bits); a scene without a quad light is
/// refused before anything runs.
#[test]
fn interleaved_soft_shadows_give_a_retraced_share_and_need_a_quad_light() {
    let out = scratch("interleaved");
    let text = "name = \"t\"\nscenes = [\"room-area-light\"]\ntracers = [\"reference\", \"packet\"]\n\
                render = { renderer = \"distribution\", shadows = \"interleaved\", sets = \"lp\", spp = 16, retrace = 64 }\n\
                resolution = { width = 32, height = 32 }\nthreads = [1]\nwarmup = 0\nrepeats = 1\n";
    let load = |spec: &SceneSpec| raylab::scene::library::load_scene(&spec.name, spec.size);
    let dir = run_text(text, &out, &load);
    let (_, runs) = read_csv(&dir.join(RUNS_CSV));
    let mut shares = Vec::new();
    for tracer in ["reference", "packet"] {
        let rows: Vec<_> = runs.iter().filter(|r| r["tracer"] == tracer).collect();
        let kinds: Vec<(&str, &str)> = rows
            .iter()
            .map(|r| (r["ray_kind"].as_str(), r["bounce_depth"].as_str()))
            .collect();
        assert_eq!(
            kinds,
            [
                ("primary", "0"),
                ("soft_shadow", "1"),
                ("soft_shadow", "2"),
                ("frame", "")
            ]
        );
        assert_eq!(rows[0]["rays"], "1024");
        let share: f64 = rows[3]["retraced_share"].parse().unwrap();
        assert!(share > 0.0 && share < 0.5, "{share}");
        assert!(rows[3]["rmse"].parse::<f64>().unwrap() > 0.0);
        assert!(rows[..3].iter().all(|r| r["retraced_share"].is_empty()));
        shares.push((share, rows[3]["rmse"].clone()));
    }
    assert_eq!(shares[0], shares[1]);
    fs::remove_dir_all(&out).unwrap();

    let dark = text.replace("room-area-light", "room");
    let mut exp = Experiment::parse(Path::new("t.toml"), &dark).unwrap();
    exp.output = out.clone();
    let err = run(&exp, &dark, &RunOverrides::default(), &load).unwrap_err();
    assert!(err.to_string().contains("no quad light"), "{err}");
    let left = fs::read_dir(out.join("t")).is_ok_and(|mut d| d.next().is_some());
    assert!(!left, "no results for a refused experiment");
    let _ = fs::remove_dir_all(&out);
}

#[test]
fn a_path_workload_gives_rows_per_bounce_and_an_rmse_that_falls_with_spp() {
    let out = scratch("path");
    let text = "name = \"t\"\nscenes = [\"room-area-light\"]\ntracers = [\"reference\", \"stream\", \"embree3-1\", \"embree3-16\"]\n\
                render = { renderer = \"path\", spp = [1, 16], max_depth = 2 }\n\
                resolution = { width = 12, height = 12 }\nthreads = [1]\nwarmup = 0\nrepeats = 1\n";
    let load = |spec: &SceneSpec| raylab::scene::library::load_scene(&spec.name, spec.size);
    let dir = run_text(text, &out, &load);
    let (_, runs) = read_csv(&dir.join(RUNS_CSV));
    let mut rmse = BTreeMap::new();
    for tracer in ["reference", "stream"] {
        for spp in [1u32, 16] {
            let rows: Vec<_> = runs
                .iter()
                .filter(|r| r["tracer"] == tracer && r["render"].ends_with(&format!(";spp={spp}")))
                .collect();
            let kinds: Vec<(&str, &str)> = rows
                .iter()
                .map(|r| (r["ray_kind"].as_str(), r["bounce_depth"].as_str()))
                .collect();
            assert_eq!(
                kinds,
                [
                    ("primary", "0"),
                    ("shadow", "1"),
                    ("diffuse", "1"),
                    ("shadow", "2"),
                    ("diffuse", "2"),
                    ("shadow", "3"),
                    ("frame", "")
                ],
                "{tracer} {spp}"
            );
            assert_eq!(rows[0]["rays"], (144 * spp).to_string());
            assert!(rows[0]["render"].starts_with("renderer=path;"));
            rmse.insert((tracer, spp), rows[6]["rmse"].parse::<f64>().unwrap());
        }
    }
    assert!(
        rmse[&("reference", 16)] < rmse[&("reference", 1)],
        "{rmse:?}"
    );
    assert_eq!(rmse[&("reference", 16)], rmse[&("stream", 16)]);
    // A line per tracer of ours and one for Embree: at each spp its fastest configuration.
    let (_, points) = read_csv(&dir.join("error_vs_time.csv"));
    assert_eq!(points.len(), 6);
    let frame_seconds = |tracer: &str, spp: u32| {
        runs.iter()
            .filter(|r| r["tracer"] == tracer && r["ray_kind"] == "frame")
            .find(|r| r["render"].ends_with(&format!(";spp={spp}")))
            .map(|r| r["seconds_min"].parse::<f64>().unwrap())
            .unwrap()
    };
    for spp in [1u32, 16] {
        let embree: Vec<_> = points
            .iter()
            .filter(|p| p["tracer"] == "Embree best" && p["spp"] == spp.to_string())
            .collect();
        assert_eq!(embree.len(), 1, "{points:?}");
        let fastest = frame_seconds("embree3-1", spp).min(frame_seconds("embree3-16", spp));
        let plotted: f64 = embree[0]["seconds"].parse().unwrap();
        assert!((plotted - fastest).abs() < 2e-6, "{plotted} vs {fastest}");
    }
    assert!(dir.join("error_vs_time.png").is_file());
    fs::remove_dir_all(&out).unwrap();
}

#[test]
fn every_committed_experiment_parses() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("experiments");
    let mut parsed = 0;
    for entry in fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        if path.ends_with("embree4.toml") && !EMBREE4_BUILT {
            println!("SKIPPED {}: {EMBREE4_HINT}", path.display());
            continue;
        }
        let exp = Experiment::load(&path).unwrap_or_else(|e| panic!("{e}"));
        assert!(!exp.instances.is_empty(), "{}", path.display());
        parsed += 1;
    }
    assert!(parsed >= 18, "only {parsed} experiment files");
    // packet.toml compares with Embree at its best: every Embree configuration it sweeps.
    let packet = Experiment::load(&dir.join("packet.toml")).unwrap();
    let embree = packet.instances.iter().filter(|i| i.info.accel.is_embree());
    assert_eq!(embree.count(), EMBREE_BEST_CONFIGURATIONS);
}

/// `embree-best`'s sweep: entry points (Embree 3: 1/4/8/16/stream; Embree 4, when built:
/// 1/4/8/16) × 2 contexts × 2 build qualities.
const EMBREE_BEST_CONFIGURATIONS: usize = if EMBREE4_BUILT { 36 } else { 20 };

/// `baseline-best`'s baselines beside Embree's: obvhs, and tinybvh-8 when built.
const BASELINE_BEST_OTHERS: usize = 1 + TINYBVH_BUILT as usize;

/// `baseline-best` is `embree-best` (the entry's params reach the Embree tracers) plus tinybvh-8
/// over its highest-quality build and obvhs, at those settings whatever the entry's and the
/// shared params say.
#[test]
fn baseline_best_adds_the_other_baselines_at_their_recommended_settings() {
    let text = r#"name = "b"
scenes = ["room"]
tracers = ["reference", { name = "baseline-best", params = { quality = ["high"] } }]
# Reference reads this `builder` (our builder); tinybvh-8 keeps its own.
params = { builder = ["raylab"] }
rays = ["primary"]
resolution = { width = 8, height = 8 }
"#;
    let exp = Experiment::parse(Path::new("t.toml"), text).unwrap();
    let labels: Vec<String> = exp.instances.iter().map(|i| i.to_string()).collect();
    let embree: Vec<&String> = labels.iter().filter(|l| l.starts_with("embree")).collect();
    assert_eq!(embree.len(), EMBREE_BEST_CONFIGURATIONS / 2, "{labels:?}");
    assert!(
        embree.iter().all(|l| l.contains("quality=high")),
        "{embree:?}"
    );
    let others: Vec<&str> = labels[1 + embree.len()..]
        .iter()
        .map(|l| l.as_str())
        .collect();
    let expected = match TINYBVH_BUILT {
        true => vec!["obvhs", "tinybvh-8[builder=sbvh;optimize=25]"],
        false => vec!["obvhs"],
    };
    assert_eq!(others, expected);
    assert_eq!(
        labels.len(),
        1 + EMBREE_BEST_CONFIGURATIONS / 2 + BASELINE_BEST_OTHERS
    );
}

#[test]
fn the_quick_experiment_plans_as_documented() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("experiments/quick.toml");
    let exp = Experiment::load(&path).unwrap();
    let plan = Plan::derive(&exp, &|s: &SceneSpec| load_scene(&s.name, s.size)).unwrap();
    let scenes: Vec<(&str, usize, bool)> = plan
        .scenes
        .iter()
        .map(|s| (s.name.as_str(), s.triangles, s.rebuild_per_frame))
        .collect();
    assert_eq!(
        scenes,
        [("room", 864), ("marbles", 8_810), ("room-area-light", 864)].map(|(name, triangles)| (
            name,
            triangles,
            name == "marbles"
        ))
    );
    let labels: Vec<&str> = plan.instances.iter().map(|i| i.label.as_str()).collect();
    let ours = [
        "packet[frustum=false;lanes=16;packet=8;traversal=ranged]",
        "cgt[packet=16]",
        "stream[stream=65536;width=16]",
        "mft",
        "obvhs",
    ];
    assert_eq!(labels[..ours.len()], ours);
    // Then Embree at its best: the whole sweep, every label an Embree configuration.
    assert_eq!(labels.len(), ours.len() + EMBREE_BEST_CONFIGURATIONS);
    assert!(labels[ours.len()..].iter().all(|l| l.starts_with("embree")));
    // Soft shadows only under the quad light: (3 + 3 + 4) kinds × 1 frame × every tracer ×
    // 1 thread count.
    assert_eq!(plan.measurements(), 10 * labels.len());
}

const TABLES_TEXT: &str = r#"name = "t"
scenes = ["lit", "moving"]
tracers = ["reference", { name = "embree16", params = { quality = ["low", "refit"] } }]
rays = ["primary"]
resolution = { width = 32, height = 32 }
frames = 3
warmup = 0
repeats = 1

[[tables]]
title = "Hits per frame"
caption = "Primary rays, 32×32."
row_header = "scene"
where = { ray_kind = "primary", threads = 1, tracer = "reference" }
metric = "hits"
decimals = 1
rows = "scene"
columns = [
  { label = "ours" },
  { label = "paper", paper = { lit = 900, moving = "n/a" } },
  { label = "best", frames = "max" },
  { label = "ours/best", ratio = ["ours", "best"], decimals = 3 },
  { label = "both", sum = ["ours", "best"], decimals = 0 },
  { label = "lesser", min = ["ours", "best"] },
  { label = "per 1000", inverse = "ours", scale = 1000, decimals = 3 },
]

[[tables]]
title = "Embree rebuilt or refitted"
where = { scene = "moving", tracer = "embree16" }
rows = [{ label = "low", where = { "param:quality" = "low" } }, { label = "refit", where = { "param:quality" = "refit" } }, { label = "high", where = { "param:quality" = "high" } }]
columns = [{ label = "hits", metric = "hits", decimals = 1 }, { label = "last frame", metric = "hits", frames = "max", where = { frame = 2 }, decimals = 0 }]

[[figures]]
file = "hits.png"
title = "hits per frame"
where = { tracer = "reference" }
x = "frame"
y = "hits"
series = "scene"
"#;

#[test]
fn tables_and_figures_come_from_runs_csv_and_refit_embree_per_frame() {
    let out = scratch("tables");
    let dir = run_text(TABLES_TEXT, &out, &load_quads);
    // The moving quad's primary hits per frame are 900, 576, 400 (see expected_primary_hits):
    // mean 625.3, best 900, ratio 0.695. Refitted and rebuilt Embree scenes hit the same.
    let tables = fs::read_to_string(dir.join(TABLES_MD)).unwrap();
    assert_eq!(
        tables,
        "# t: paper vs ours\n\n\
         ## Hits per frame\n\n\
         Primary rays, 32×32.\n\n\
         | scene | ours | paper | best | ours/best | both | lesser | per 1000 |\n\
         |---|---:|---:|---:|---:|---:|---:|---:|\n\
         | lit | 900.0 | 900 | 900.0 | 1.000 | 1800 | 900.0 | 1.111 |\n\
         | moving | 625.3 | n/a | 900.0 | 0.695 | 1525 | 625.3 | 1.599 |\n\n\
         ## Embree rebuilt or refitted\n\n\
         |  | hits | last frame |\n\
         |---|---:|---:|\n\
         | low | 625.3 | 400 |\n\
         | refit | 625.3 | 400 |\n\
         | high | – | – |\n\n"
    );
    let rows = selection::read_rows(&dir.join(RUNS_CSV)).unwrap();
    let exp = Experiment::parse(Path::new("t.toml"), TABLES_TEXT).unwrap();
    let lines = exp.figures[0].lines(&rows);
    assert_eq!(
        lines,
        [
            (
                "lit".to_string(),
                vec![(0.0, 900.0), (1.0, 900.0), (2.0, 900.0)]
            ),
            (
                "moving".to_string(),
                vec![(0.0, 900.0), (1.0, 576.0), (2.0, 400.0)]
            )
        ]
    );
    assert!(dir.join("hits.png").is_file());
    // Every frame of the moving quad builds (or refits) each structure and reports its
    // throughput; the static quad reuses frame 0's.
    for r in &rows {
        let reused = r["scene"] == "lit" && r["frame"] != "0";
        assert_eq!(r["build"], if reused { "reused" } else { "built" }, "{r:?}");
        let build: f64 = r["build_seconds"].parse().unwrap();
        let trace: f64 = r["seconds_min"].parse().unwrap();
        let total: f64 = r["build_plus_trace_seconds"].parse().unwrap();
        assert!((total - (build + trace)).abs() < 1e-12, "{r:?}");
        match reused {
            true => assert_eq!(r["build_mtris_per_s"], ""),
            false => {
                let rate: f64 = r["build_mtris_per_s"].parse().unwrap();
                assert!((rate - 2.0 / build / 1e6).abs() <= 1e-9 * rate, "{r:?}");
            }
        }
    }
    fs::remove_dir_all(&out).unwrap();
}

#[test]
fn bad_tables_and_figures_are_usage_errors_with_the_line() {
    let text = format!(
        "{}\n[[tables]]\ntitle = \"x\"\nrows = \"scnee\"\ncolumns = [{{ label = \"a\", metric = \"hits\" }}]\n",
        TEXT
    );
    let err = Experiment::parse(Path::new("t.toml"), &text).unwrap_err();
    assert!(
        matches!(&err, Error::Usage(m) if m.starts_with("t.toml:11: table \"x\" rows: unknown field \"scnee\"")),
        "{err}"
    );
    let text = format!(
        "{}\n[[figures]]\nfile = \"../x.png\"\ntitle = \"x\"\nx = \"frame\"\ny = \"hits\"\n",
        TEXT
    );
    let err = Experiment::parse(Path::new("t.toml"), &text).unwrap_err();
    assert!(
        err.to_string().contains("plain name ending in .png"),
        "{err}"
    );
}

#[test]
fn the_wald06_experiments_parse_with_their_tables_and_figures() {
    let load = |file: &str| {
        Experiment::load(
            &Path::new(env!("CARGO_MANIFEST_DIR"))
                .join("experiments")
                .join(file),
        )
        .unwrap()
    };
    let exp = load("wald06.toml");
    // 4 MB/FC combinations + 8 λ values + grid-dda + reference.
    assert_eq!(exp.instances.len(), 14);
    assert_eq!((exp.tables.len(), exp.figures.len()), (4, 1));
    let exp = load("wald06-packets.toml");
    assert_eq!(exp.instances.len(), 6);
    assert_eq!(exp.scenes.len(), 10);
    assert_eq!((exp.tables.len(), exp.figures.len()), (4, 3));
    let exp = load("wald06-animated.toml");
    let labels: Vec<String> = exp.instances.iter().map(|i| i.to_string()).collect();
    assert_eq!(
        labels,
        [
            "cgt[packet=4]",
            "cgt[packet=8]",
            "embree3-16[quality=low]",
            "embree3-16[quality=refit]",
            "obvhs",
            "reference"
        ]
    );
    assert_eq!(
        (exp.width, exp.height, exp.threads.as_slice()),
        (1024, 1024, &[1, 2][..])
    );
    assert_eq!(exp.tables.len(), 5);
    let bench = load("wald06-benchmark.toml");
    assert_eq!(exp.scenes, bench.scenes);
    // cgt 4×4, 8×8, 16×16; every Embree entry point and context at low and refit.
    assert_eq!(bench.instances.len(), 3 + EMBREE_BEST_CONFIGURATIONS);
    assert_eq!(
        (bench.width, bench.frames, bench.threads.as_slice()),
        (1024, 2, &[1, 2][..])
    );
    assert_eq!(bench.tables.len(), 4);
}

/// Both Boulos 2007 files parse, and every `render` a table or figure selects is one of the
/// file's workloads (a typo would silently give empty cells).
#[test]
fn the_boulos07_experiments_parse_and_select_their_own_workloads() {
    for (file, instances, renders, tables, figures) in [
        // Plus baseline-best's baselines (below).
        ("boulos07.toml", 5, 12, 8, 1),
        ("boulos07-drt.toml", 2, 8, 4, 1),
        ("boulos07-fig8.toml", 1, 2, 4, 2),
    ] {
        let exp = Experiment::load(
            &Path::new(env!("CARGO_MANIFEST_DIR"))
                .join("experiments")
                .join(file),
        )
        .unwrap();
        let embree = match file {
            "boulos07-fig8.toml" => 0,
            _ => EMBREE_BEST_CONFIGURATIONS + BASELINE_BEST_OTHERS,
        };
        assert_eq!(exp.instances.len(), instances + embree, "{file}");
        assert_eq!(exp.renders.len(), renders, "{file}");
        assert_eq!(
            (exp.tables.len(), exp.figures.len()),
            (tables, figures),
            "{file}"
        );
        let labels: Vec<String> = exp.renders.iter().map(|r| r.to_string()).collect();
        let filters = exp.tables.iter().flat_map(|t| {
            let rows = match &t.rows {
                RowsSpec::List(rows) => rows.iter().map(|r| &r.filter).collect(),
                RowsSpec::Field(_) => Vec::new(),
            };
            std::iter::once(&t.filter)
                .chain(rows)
                .chain(t.columns.iter().map(|c| &c.filter))
        });
        let mut selected = 0;
        for filter in filters.chain(exp.figures.iter().map(|f| &f.filter)) {
            for render in filter.0.get("render").into_iter().flatten() {
                assert!(labels.contains(render), "{file}: {render} is no workload");
                selected += 1;
            }
        }
        assert!(selected >= renders, "{file}: {selected} selections");
    }
}

/// Nothing but the (empty) experiment directory may remain.
fn assert_no_results(out: &Path) {
    let left: Vec<_> = fs::read_dir(out.join("t"))
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert!(left.is_empty(), "left behind: {left:?}");
}

#[test]
fn a_scene_failing_mid_run_leaves_no_results() {
    let out = scratch("scene-fails");
    let exp = experiment(&out);
    // The plan loads each scene once; the run loads them again, and "moving" is gone by then.
    let loads = Cell::new(0);
    let load = |spec: &SceneSpec| -> Result<Scene> {
        loads.set(loads.get() + 1);
        if spec.name == "moving" && loads.get() > 3 {
            return Err(Error::usage("unknown scene \"moving\""));
        }
        load_quads(spec)
    };
    let err = run(&exp, TEXT, &RunOverrides::default(), &load).unwrap_err();
    assert_eq!(err.to_string(), "unknown scene \"moving\"");
    assert_eq!(loads.get(), 6);
    assert_no_results(&out);
    fs::remove_dir_all(&out).unwrap();
}

#[test]
fn a_write_error_leaves_no_results() {
    let out = scratch("write-fails");
    let exp = experiment(&out);
    // Once the run has started, a directory squats on runs.csv inside the partial results.
    let load = |spec: &SceneSpec| -> Result<Scene> {
        if let Ok(entries) = fs::read_dir(out.join("t")) {
            for partial in entries.map(|e| e.unwrap().path()) {
                let _ = fs::create_dir(partial.join(RUNS_CSV));
            }
        }
        load_quads(spec)
    };
    let err = run(&exp, TEXT, &RunOverrides::default(), &load).unwrap_err();
    assert!(err.to_string().contains(RUNS_CSV), "{err}");
    assert_no_results(&out);
    fs::remove_dir_all(&out).unwrap();
}

#[test]
fn overrides_replace_settings_and_reject_zeros() {
    let mut exp = experiment(Path::new("x"));
    let overrides = RunOverrides {
        output: Some("elsewhere".into()),
        threads: Some(vec![4]),
        resolution: Some((16, 8)),
        frames: Some(1),
        warmup: Some(2),
        repeats: Some(5),
        dump_rays: false,
        shard: None,
        chatter: Chatter::Quiet,
        scale: None,
    };
    overrides.apply(&mut exp).unwrap();
    assert_eq!(
        (
            exp.output.to_str().unwrap(),
            exp.threads.as_slice(),
            exp.width,
            exp.height,
            exp.frames,
            exp.warmup,
            exp.repeats
        ),
        ("elsewhere", &[4][..], 16, 8, 1, 2, 5)
    );
    let zero = RunOverrides {
        repeats: Some(0),
        ..RunOverrides::default()
    };
    assert!(matches!(zero.apply(&mut exp), Err(Error::Usage(_))));
}

/// runs.csv carries the SAH cost of our BVH, whichever builder made it (`builder = "embree"`:
/// Embree's rtcBuildBVH), equal to the tree's own `sah_cost`; Embree's own scenes have none.
#[test]
fn runs_carry_the_sah_cost_of_our_trees_from_either_builder() {
    use raylab::accel::AccelKind;
    use raylab::params::Params;
    let out = scratch("sah");
    let text = "name = \"t\"\nscenes = [\"room\"]\ntracers = [\"reference\", \
        { name = \"reference\", params = { builder = \"embree\" } }, \"embree1\"]\n\
        rays = [\"primary\"]\nresolution = { width = 16, height = 16 }\nwarmup = 0\nrepeats = 1\n";
    let load = |spec: &SceneSpec| load_scene(&spec.name, spec.size);
    let dir = run_text(text, &out, &load);
    let (_, runs) = read_csv(&dir.join(RUNS_CSV));
    let room = load_scene("room", None).unwrap();
    let mesh = room.frame(0, 1).mesh.into_owned();
    let sah = |params: Params| {
        AccelKind::Bvh
            .build(&mesh, &params)
            .unwrap()
            .sah_cost()
            .unwrap()
    };
    let (ours, embrees) = (
        sah(Params::new()),
        sah(Params::new().with("builder", "embree")),
    );
    assert!(ours > 1.0 && embrees > 1.0, "{ours}, {embrees}");
    assert_eq!(runs.len(), 3, "{runs:?}");
    for r in &runs {
        let expected = match (r["tracer"].as_str(), r["parameters"].as_str()) {
            ("reference", "") => ours.to_string(),
            ("reference", "builder=embree") => embrees.to_string(),
            _ => String::new(),
        };
        assert_eq!(r["sah_cost"], expected, "{r:?}");
    }
    fs::remove_dir_all(&out).unwrap();
}
