//! Per-pixel cost maps (issue 33) add up: on a real scene, for every tracer family that counts
//! its tests, the box tests, triangle tests and node visits of a map sum exactly to the counters
//! of the same counting pass — primary rays, shadow rays, diffuse bounces and (multi-frusta's
//! native answer and everyone's shadow rays) a soft-shadow query — and the counters themselves
//! equal those of an ordinary counting pass, so attributing costs changes no count. The lanes
//! maps sum to the pass's SIMD lane totals, which equal the counts each family already keeps.

use raylab::experiment::Experiment;
use raylab::geometry::RayBatch;
use raylab::render::area_light::{soft_shadow_points, LightSampleSets};
use raylab::render::assembly::BatchKind;
use raylab::render::cost_map::{count_per_pixel, wavefront, Cost, CostMap, Wavefront};
use raylab::render::distribution::{DrtSettings, Integrator};
use raylab::render::path::path_bounce_rays;
use raylab::render::wavefront::{answer, Answers, Tracing, Work};
use raylab::scene::library::load_scene;
use raylab::scene::Scene;
use raylab::stats::{Counters, Event};
use raylab::tracers::chunked::{query_rays, trace_hits};
use raylab::tracers::visibility::QuadLight;
use raylab::tracers::{tracer_for_frame, Params, Tracer, VisibilityQuery};

const SIZE: (u32, u32) = (64, 48);

/// Every from-scratch family, with the variants whose attribution differs (packet lanes and
/// frusta, wide trees, stream hand-off to single rays, primary frusta).
fn tracers() -> Vec<(&'static str, Params)> {
    vec![
        ("reference", Params::new()),
        ("wide-single", Params::new()),
        ("obvhs", Params::new()),
        ("grid-dda", Params::new()),
        ("packet", Params::new()),
        ("packet", Params::new().with("traversal", "masked")),
        ("packet", Params::new().with("width", 4)),
        ("cgt", Params::new()),
        ("stream", Params::new()),
        ("stream", Params::new().with("single", 8)),
        ("mft", Params::new()),
        ("mft", Params::new().with("primary", "frusta")),
        ("mft", Params::new().with("width", 4)),
    ]
}

/// An ordinary counting pass of `work`.
fn plain_counters(tracer: &dyn Tracer, work: Work<'_>) -> Counters {
    let mut counters = Counters::default();
    answer(
        tracer,
        work,
        &mut Answers::blank(&work),
        Some(&mut counters),
    );
    counters
}

/// The tracers whose SIMD operations run over rays (they have lanes maps).
fn traces_lanes(name: &str) -> bool {
    matches!(name, "packet" | "stream" | "cgt" | "mft")
}

/// The lanes map of `name`'s pass sums to its lane totals, which equal what the family counts
/// anyway: every test of packet and mft is one SIMD lane (their tests are all lane tests), a
/// stream's lanes are its traversal and intersection lanes, cgt's are its cells' triangle tests
/// less its lone rays'.
fn lanes_match(what: &str, name: &str, counters: &Counters, maps: &[CostMap]) {
    let lanes = maps.iter().find(|m| m.cost == Cost::Lanes);
    let Some(lanes) = lanes.filter(|_| traces_lanes(name)) else {
        assert!(lanes.is_none(), "{what}: a single-ray tracer has no lanes");
        assert_eq!(counters.simd_lanes, 0, "{what}");
        return;
    };
    assert_eq!(lanes.total.iter().sum::<u64>(), counters.simd_lanes_active);
    assert_eq!(lanes.per.iter().sum::<u64>(), counters.simd_lanes, "{what}");
    let tests = counters.aabb_tests + counters.triangle_tests;
    match name {
        "packet" | "mft" => assert_eq!(counters.simd_lanes_active, tests, "{what}"),
        "stream" => {
            let both = |a: Event, b: Event| counters.get(a) + counters.get(b);
            assert_eq!(
                (counters.simd_lanes_active, counters.simd_lanes),
                (
                    both(Event::TraversalLanesActive, Event::IntersectionLanesActive),
                    both(Event::TraversalLanesIssued, Event::IntersectionLanesIssued)
                ),
                "{what}"
            );
        }
        _ => assert!(
            counters.simd_lanes_active <= counters.triangle_tests,
            "{what}"
        ),
    }
    let share = lanes.mean();
    assert!(share > 0.0 && share <= 1.0, "{what}: lane share {share}");
}

/// The maps of `work` sum to its counters, which equal an ordinary pass's; returns the maps.
fn sums_match(
    what: &str,
    name: &str,
    tracer: &dyn Tracer,
    work: Work<'_>,
    pixel_of: &[u32],
) -> Vec<CostMap> {
    let (counters, maps) = count_per_pixel(tracer, work, pixel_of, SIZE).unwrap();
    let plain = plain_counters(tracer, work);
    assert_eq!(
        (
            counters.aabb_tests,
            counters.triangle_tests,
            counters.nodes_visited
        ),
        (plain.aabb_tests, plain.triangle_tests, plain.nodes_visited),
        "{what}: attributing changed the counts"
    );
    let sum = |cost: Cost| -> u64 {
        let map: &CostMap = maps.iter().find(|m| m.cost == cost).unwrap();
        map.total.iter().sum()
    };
    assert_eq!(sum(Cost::Box), counters.aabb_tests, "{what}: box tests");
    assert_eq!(
        sum(Cost::Triangle),
        counters.triangle_tests,
        "{what}: triangle tests"
    );
    assert_eq!(sum(Cost::Nodes), counters.nodes_visited, "{what}: nodes");
    lanes_match(what, name, &counters, &maps);
    assert!(
        counters.aabb_tests + counters.triangle_tests > 0,
        "{what}: nothing counted"
    );
    // Every ray is counted at its pixel: the map's rays are the wavefront's (a query's: the
    // sample rays in front of their points).
    let rays: u64 = maps[0].per.iter().sum();
    assert_eq!(rays, work.rays() as u64, "{what}: rays per pixel");
    maps
}

fn conference() -> Option<Scene> {
    match load_scene("conference", None) {
        Ok(scene) => Some(scene),
        Err(e) => {
            eprintln!("NOTE: conference not found ({e}); set RAYLAB_SCENES to ../shared/scenes");
            None
        }
    }
}

#[test]
fn maps_sum_to_the_counters_for_every_tracer_family() {
    let Some(scene) = conference() else { return };
    let frame = scene.frame(0, 1);
    let reference = tracer_for_frame("reference", &Params::new(), &frame).unwrap();
    let batches: Vec<(&str, RayBatch)> = ["primary", "shadow", "diffuse"]
        .map(|kind| {
            let wave = wavefront(&scene, &frame, reference.as_ref(), (kind, 16), SIZE).unwrap();
            let Wavefront::Rays(rays) = wave else {
                panic!("{kind}: a batch of rays")
            };
            assert!(!rays.is_empty(), "{kind} rays");
            (kind, rays)
        })
        .to_vec();
    // The soft-shadow query of the primary hits: each shading point from its hit's pixel.
    let primary = &batches[0].1;
    let hits = trace_hits(reference.as_ref(), primary);
    let (points, samples) = soft_shadow_points(
        &frame.mesh,
        primary,
        &hits,
        SIZE.0,
        16,
        LightSampleSets::parse("jittered").unwrap(),
        7,
    )
    .unwrap();
    let point_pixels: Vec<u32> = (0..primary.len())
        .filter(|&i| hits[i].is_hit())
        .map(|i| primary.pixel[i])
        .collect();
    let query = VisibilityQuery::new(&points, QuadLight::of(&scene.lights[0]), &samples).unwrap();
    let mut soft_rays = RayBatch::default();
    query_rays(query, &mut soft_rays);
    let soft_ray_pixels: Vec<u32> = soft_rays
        .pixel
        .iter()
        .map(|&p| point_pixels[p as usize])
        .collect();

    for (name, params) in tracers() {
        let tracer = tracer_for_frame(name, &params, &frame).unwrap();
        let label = format!("{name} {params:?}");
        for (kind, rays) in &batches {
            let what = format!("{label} on {kind} rays");
            let maps = sums_match(
                &what,
                name,
                tracer.as_ref(),
                Work::of_batch(rays),
                &rays.pixel,
            );
            // Each camera ray of a BVH tracer tests the root box at least: its own test, or its
            // lane's or stream slot's, lands on its own pixel (frusta spread theirs instead).
            let bvh_rays =
                !matches!(name, "cgt" | "grid-dda") && !format!("{params:?}").contains("frusta");
            if *kind == "primary" && bvh_rays {
                let boxes = &maps.iter().find(|m| m.cost == Cost::Box).unwrap().total;
                assert!(
                    boxes.iter().all(|&b| b >= 1),
                    "{what}: a pixel without its box test"
                );
            }
        }
        let what = format!("{label} on soft-shadow rays");
        sums_match(
            &what,
            name,
            tracer.as_ref(),
            Work::Occlusion(&soft_rays),
            &soft_ray_pixels,
        );
        let what = format!("{label} on the soft-shadow query");
        sums_match(
            &what,
            name,
            tracer.as_ref(),
            Work::LightVisibility(query),
            &point_pixels,
        );
    }
}

/// `render --heatmap … --heatmap-rays soft-shadow`'s wavefront: the query of the primary hits on
/// the scene's quad light, natively for mft, as its shadow rays for the others; its maps sum to
/// the pass's counters, and a tracer that answers with rays counts every sample ray in front of
/// its point once, at its point's pixel.
#[test]
fn soft_shadow_maps_sum_to_the_counters() {
    let scene = load_scene("conference-area-light", None).unwrap();
    let frame = scene.frame(0, 1);
    for name in ["reference", "packet", "stream", "mft"] {
        let tracer = tracer_for_frame(name, &Params::new(), &frame).unwrap();
        let wave = wavefront(&scene, &frame, tracer.as_ref(), ("soft-shadow", 4), SIZE).unwrap();
        let Wavefront::SoftShadow { work, rays } = &wave else {
            panic!("a soft-shadow query")
        };
        assert_eq!(work.samples.per_point(), 4);
        let (work_of_tracer, pixel_of) = wave.work_for(tracer.as_ref());
        let native = matches!(work_of_tracer, Work::LightVisibility(_));
        assert_eq!(native, name == "mft", "{name}: natively only mft");
        assert_eq!(work_of_tracer.rays(), rays.len(), "{name}: the same rays");
        let what = format!("{name} on soft-shadow rays");
        sums_match(&what, name, tracer.as_ref(), work_of_tracer, &pixel_of);
    }
    // Without a quad light there is no query.
    let room = load_scene("room", None).unwrap();
    let frame = room.frame(0, 1);
    let tracer = tracer_for_frame("reference", &Params::new(), &frame).unwrap();
    let err = wavefront(&room, &frame, tracer.as_ref(), ("soft-shadow", 4), SIZE)
        .err()
        .unwrap();
    assert_eq!(err.exit_code(), 2);
    assert!(err.to_string().contains("quad light"), "{err}");
}

/// `--heatmap-rays bounce-N`: the path tracer's N-th bounce, each ray at the pixel its path
/// started at. Single rays count the same whether traced wave by wave in the frame or as one
/// batch, so the map sums to the frame's own record of that bounce; every family's map sums to
/// its pass's counters.
#[test]
fn path_bounce_maps_sum_to_the_frames_counters() {
    let scene = load_scene("conference-area-light", None).unwrap();
    let frame = scene.frame(0, 1);
    let reference = tracer_for_frame("reference", &Params::new(), &frame).unwrap();
    let settings = DrtSettings {
        integrator: Integrator::Path,
        width: SIZE.0,
        height: SIZE.1,
        spp: 1,
        ..DrtSettings::default()
    };
    let (rays, traced) = path_bounce_rays(
        &scene,
        &frame,
        reference.as_ref(),
        &settings,
        2,
        Tracing::Counted,
    )
    .unwrap();
    let record = traced
        .batches
        .iter()
        .find(|b| b.depth == 2 && b.kind == BatchKind::Rays(rays.kind()))
        .unwrap();
    assert!(!rays.is_empty());
    assert_eq!(rays.len(), record.rays, "the frame's bounce-2 rays");
    let maps = sums_match(
        "reference on bounce 2",
        "reference",
        reference.as_ref(),
        Work::of_batch(&rays),
        &rays.pixel,
    );
    let total = |cost: Cost| -> u64 {
        let map = maps.iter().find(|m| m.cost == cost).unwrap();
        map.total.iter().sum()
    };
    let c = &record.counters;
    assert_eq!(
        (total(Cost::Box), total(Cost::Triangle), total(Cost::Nodes)),
        (c.aabb_tests, c.triangle_tests, c.nodes_visited)
    );
    // The heat map's wavefront is the same bounce (the frame does not depend on the tracer).
    for name in ["reference", "packet", "stream", "cgt"] {
        let tracer = tracer_for_frame(name, &Params::new(), &frame).unwrap();
        let wave = wavefront(&scene, &frame, tracer.as_ref(), ("bounce-2", 1), SIZE).unwrap();
        let Wavefront::Rays(bounce) = &wave else {
            panic!("a batch of rays")
        };
        assert_eq!(bounce.pixel, rays.pixel, "{name}: the same paths");
        let what = format!("{name} on bounce 2");
        sums_match(
            &what,
            name,
            tracer.as_ref(),
            Work::of_batch(bounce),
            &bounce.pixel,
        );
    }
    let err = wavefront(&scene, &frame, reference.as_ref(), ("bounce-0", 1), SIZE)
        .err()
        .unwrap();
    assert!(err.to_string().contains("N ≥ 1"), "{err}");
}

#[test]
fn full_packets_keep_every_lane_busy() {
    let Some(scene) = conference() else { return };
    let frame = scene.frame(0, 1);
    // 64×48 camera rays in 8×8 packets of 4-wide SIMD rays: every SIMD ray is full, and the
    // packet tests all its lanes at every node and triangle it visits.
    let packet = tracer_for_frame("packet", &Params::new().with("width", 4), &frame).unwrap();
    let rays = raylab::render::rays::primary_rays(&frame.camera, SIZE.0, SIZE.1);
    let (counters, maps) =
        count_per_pixel(packet.as_ref(), Work::of_batch(&rays), &rays.pixel, SIZE).unwrap();
    let lanes = maps.iter().find(|m| m.cost == Cost::Lanes).unwrap();
    assert_eq!(counters.simd_lanes_active, counters.simd_lanes);
    assert!((0..lanes.total.len()).all(|i| lanes.value(i) == 1.0));
    // A stream's filters narrow as rays leave: its lanes are busy less than all the time.
    let stream = tracer_for_frame("stream", &Params::new(), &frame).unwrap();
    let (counters, _) =
        count_per_pixel(stream.as_ref(), Work::of_batch(&rays), &rays.pixel, SIZE).unwrap();
    assert!(counters.simd_lanes_active < counters.simd_lanes);
}

#[test]
fn baselines_without_counts_give_no_map() {
    let Some(scene) = conference() else { return };
    let frame = scene.frame(0, 1);
    let embree = tracer_for_frame("embree3-4", &Params::new(), &frame).unwrap();
    let rays = raylab::render::rays::primary_rays(&frame.camera, SIZE.0, SIZE.1);
    let err =
        count_per_pixel(embree.as_ref(), Work::of_batch(&rays), &rays.pixel, SIZE).unwrap_err();
    assert!(err.to_string().contains("does not report"), "{err}");
}

#[test]
fn the_readme_picture_is_made_by_a_committed_command() {
    let readme = std::fs::read_to_string("README.md").unwrap();
    let picture = "docs/heatmaps/heatmap-conference-area-light-soft_shadow-box.png";
    assert!(
        readme.contains(&format!("]({picture})")),
        "the README shows the picture"
    );
    // The command that makes it is in the reference, where the README points.
    assert!(readme.contains("experiments/heatmaps.toml"));
    let reference = std::fs::read_to_string("docs/REFERENCE.md").unwrap();
    assert!(reference.contains("raylab run experiments/heatmaps.toml --out /tmp/heatmaps"));
    assert!(reference.contains(&format!("cp /tmp/heatmaps/heatmaps/*/{}", &picture[14..])));
    let exp = Experiment::load(std::path::Path::new("experiments/heatmaps.toml")).unwrap();
    assert_eq!(exp.name, "heatmaps");
    assert_eq!(exp.heatmaps, vec![Cost::Box]);
    assert_eq!(exp.scenes[0].name, "conference-area-light");
    let image = image::open(picture).unwrap();
    // The shaded frame and three tracers' 256² panels side by side, plus the colour bar.
    assert!(image.width() > 4 * 256 && image.height() >= 256);
}

#[test]
fn an_unknown_heat_map_names_the_file_and_line() {
    let text =
        "name = \"x\"\nscenes = [\"room\"]\ntracers = [\"reference\"]\nrays = [\"primary\"]\n\
                heatmaps = [\"box\", \"lane\"]\nresolution = { width = 8, height = 8 }\n\
                frames = 1\nthreads = [1]\nwarmup = 0\nrepeats = 1\n";
    let err = Experiment::parse(std::path::Path::new("x.toml"), text).unwrap_err();
    assert_eq!(err.exit_code(), 2);
    let message = err.to_string();
    assert!(
        message.contains("x.toml:5:") && message.contains("\"lane\"") && message.contains("lanes"),
        "{message}"
    );
}
