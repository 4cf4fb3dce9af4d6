//! The experiment file's parsing: defaults, grids, limits, and the errors naming file and line.

use std::collections::BTreeSet;

use super::*;
use crate::accel::embree::EMBREE4_BUILT;
use crate::render::assembly::Assembly;
use crate::render::distribution::Integrator;
use crate::render::whitted::WhittedSettings;
use crate::scene::scene_file::Preset;

fn parse(text: &str) -> Result<Experiment> {
    Experiment::parse(Path::new("exp.toml"), text)
}

const BASE: &str = "name = \"t\"\nscenes = [\"room\"]\nrays = [\"primary\"]\nresolution = { width = 8, height = 4 }\n";

#[test]
fn parameter_grids_are_bounded() {
    // Three lists of 39 values asked for 59,319 instances, checked pairwise for repeats:
    // a minute of parsing for 600 bytes.
    let values = (1..40)
        .map(|i| i.to_string())
        .collect::<Vec<_>>()
        .join(", ");
    let text = format!(
        "{BASE}tracers = [{{ name = \"reference\", params = {{ leaf_size = [{values}], \
         max_depth = [{values}], bins = [{values}] }} }}]\n"
    );
    let err = parse(&text).unwrap_err();
    assert_eq!(err.exit_code(), 2);
    assert!(err.to_string().starts_with("exp.toml:5:"), "{err}");
    assert!(
        err.to_string().contains("more than 1000 combinations"),
        "{err}"
    );
    let renders = "[[render]]\nrenderer = \"whitted\"\nmax_reflection_depth = [1, 2, 3, 4, 5, 6, 7, 8, 9, 10, \
                   11]\nmax_depth = [1, 2, 3, 4, 5, 6, 7, 8, 9, 10]\nmax_refraction_depth = [1, 2, 3, 4, 5, 6, \
                   7, 8, 9, 10]\n";
    let err = parse(&format!("{BASE}tracers = [\"reference\"]\n{renders}")).unwrap_err();
    assert!(
        err.to_string().contains("more than 1000 combinations"),
        "{err}"
    );
}

#[test]
fn embree_best_sweeps_every_entry_point_context_and_quality() {
    let exp = parse(&format!(
        "{BASE}tracers = [\"reference\", \"embree-best\"]\n"
    ))
    .unwrap();
    let embree: Vec<String> = exp.instances[1..].iter().map(|i| i.to_string()).collect();
    // Embree 3's 5 entry points and Embree 4's 4 (when built) × 2 contexts × 2 qualities,
    // keys sorted, values as listed.
    let entry_points = if EMBREE4_BUILT { 9 } else { 5 };
    assert_eq!(embree.len(), entry_points * 4);
    assert_eq!(embree[0], "embree3-1[context=coherent;quality=medium]");
    assert_eq!(
        embree[19],
        "embree3-stream[context=incoherent;quality=high]"
    );
    if EMBREE4_BUILT {
        assert_eq!(embree[20], "embree4-1[context=coherent;quality=medium]");
        assert_eq!(embree[35], "embree4-16[context=incoherent;quality=high]");
    }
    let names: BTreeSet<&str> = exp.instances[1..].iter().map(|i| i.info.name).collect();
    assert_eq!(names.len(), entry_points);
    // Its own params replace an axis: per-frame rebuilds sweep low and refit.
    let exp = parse(&format!(
        "{BASE}tracers = [{{ name = \"embree-best\", params = {{ quality = [\"low\", \"refit\"], context = [\"auto\"] }} }}]\n"
    ))
    .unwrap();
    assert_eq!(exp.instances.len(), entry_points * 2);
    assert!(exp
        .instances
        .iter()
        .all(|i| i.params.0["context"] == "auto"));
    // A sweep entry also listed on its own is a duplicate instance.
    let twice = parse(&format!(
        "{BASE}tracers = [\"embree-best\", {{ name = \"embree16\", params = {{ context = [\"coherent\"], quality = [\"high\"] }} }}]\n"
    ));
    assert!(twice.unwrap_err().to_string().contains("listed twice"));
}

#[test]
fn embree_4_tracers_are_refused_or_skipped_when_not_built() {
    let named = parse(&format!(
        "{BASE}tracers = [\"reference\", \"embree4-16\"]\n"
    ));
    let optional = parse(&format!(
        "{BASE}tracers = [\"reference\", {{ name = \"embree4-16\", if_built = true }}]\n"
    ))
    .unwrap();
    if EMBREE4_BUILT {
        assert_eq!(named.unwrap().instances[1].info.name, "embree4-16");
        assert_eq!(optional.instances[1].info.name, "embree4-16");
    } else {
        let err = named.unwrap_err();
        assert!(
            matches!(err, Error::Usage(_) | Error::Input { .. }),
            "{err}"
        );
        assert!(err.to_string().contains("Embree 4 was not built"), "{err}");
        assert_eq!(optional.instances.len(), 1);
    }
    // `if_built` never hides a misspelt name.
    let misspelt = parse(&format!(
        "{BASE}tracers = [{{ name = \"embree5-16\", if_built = true }}]\n"
    ));
    assert!(misspelt.unwrap_err().to_string().contains("unknown tracer"));
}

#[test]
fn grid_expands_to_every_combination() {
    // reference reads the BVH's leaf_size, max_depth and bins. Its own table gives leaf_size
    // (2 values) and max_depth (1); the shared grid gives bins (2) and a leaf_size that the
    // own table overrides: 2 × 1 × 2 = 4 instances, then the bare entry takes the shared
    // leaf_size (3) × bins (2) = 6 more.
    let text = format!(
        "{BASE}tracers = [{{ name = \"reference\", params = {{ leaf_size = [1, 2], max_depth = 20 }} }}, \
         {{ name = \"reference\" }}]\nparams = {{ bins = [8, 16], leaf_size = [4, 6, 8] }}\n"
    );
    let exp = parse(&text).unwrap();
    let labels: Vec<String> = exp.instances.iter().map(|i| i.to_string()).collect();
    assert_eq!(
        labels,
        [
            "reference[bins=8;leaf_size=1;max_depth=20]",
            "reference[bins=8;leaf_size=2;max_depth=20]",
            "reference[bins=16;leaf_size=1;max_depth=20]",
            "reference[bins=16;leaf_size=2;max_depth=20]",
            "reference[bins=8;leaf_size=4]",
            "reference[bins=8;leaf_size=6]",
            "reference[bins=8;leaf_size=8]",
            "reference[bins=16;leaf_size=4]",
            "reference[bins=16;leaf_size=6]",
            "reference[bins=16;leaf_size=8]",
        ]
    );
    // Instances differing only in tracer-side parameters would share the structure; these
    // all differ in BVH parameters.
    assert_eq!(exp.instances[0].structure().params, exp.instances[0].params);
}

#[test]
fn thread_counts_twice_or_absurd_are_refused_at_their_line() {
    for (threads, message) in [
        ("[1, 1]", "exp.toml:6: thread count 1 is listed twice"),
        ("[2, 1, 2]", "exp.toml:6: thread count 2 is listed twice"),
        ("[100000]", "exp.toml:6: 100000 threads are more than 1024"),
        (
            "[0]",
            "exp.toml:6: threads must be a non-empty list of counts ≥ 1",
        ),
    ] {
        let text = format!("{BASE}tracers = [\"reference\"]\nthreads = {threads}\n");
        let err = parse(&text).unwrap_err();
        assert_eq!(err.exit_code(), 2);
        assert_eq!(err.to_string(), message);
    }
    assert_eq!(check_threads(&[1, 2, MAX_THREADS]), Ok(()));
}

#[test]
fn defaults_and_explicit_fields() {
    let exp = parse(&format!("{BASE}tracers = [\"reference\"]\n")).unwrap();
    assert_eq!(
        (
            exp.width,
            exp.height,
            exp.frames,
            exp.warmup,
            exp.repeats,
            exp.seed
        ),
        (8, 4, 1, 1, 3, 0)
    );
    assert_eq!(exp.threads, vec![1]);
    assert_eq!(exp.output, PathBuf::from("results"));
    assert_eq!(
        exp.scenes,
        vec![SceneSpec {
            name: "room".into(),
            size: None
        }]
    );

    let text = "name = \"t\"\ntracers = [\"reference\"]\nrays = [\"shadow\", \"primary\", \"shadow\"]\n\
                scenes = [\"room\", { name = \"balls\", size = 3 }]\nresolution = { width = 2, height = 2 }\n\
                frames = 5\nthreads = [1, 2, 4]\nwarmup = 0\nrepeats = 7\nseed = 42\noutput = \"out\"\n";
    let exp = parse(text).unwrap();
    assert_eq!(exp.ray_kinds, vec![RayKind::Shadow, RayKind::Primary]);
    assert_eq!(
        exp.scenes[1],
        SceneSpec {
            name: "balls".into(),
            size: Some(3)
        }
    );
    assert_eq!(
        (exp.frames, exp.warmup, exp.repeats, exp.seed),
        (5, 0, 7, 42)
    );
    assert_eq!(exp.threads, vec![1, 2, 4]);
    assert_eq!(exp.output, PathBuf::from("out"));
}

fn line_of_error(e: Error) -> (Option<usize>, String) {
    match e {
        Error::Input { line, message, .. } => (line, message),
        other => panic!("expected an input error, got {other:?}"),
    }
}

#[test]
fn invalid_toml_names_the_line() {
    let (line, _) = line_of_error(
        parse(&format!(
            "{BASE}tracers = [\"reference\" \"obvhs\"]\nframes = 2\n"
        ))
        .unwrap_err(),
    );
    assert_eq!(line, Some(5));
    // A wrong type on line 6.
    let (line, msg) = line_of_error(
        parse(&format!(
            "{BASE}tracers = [\"reference\"]\nframes = \"two\"\n"
        ))
        .unwrap_err(),
    );
    assert_eq!(line, Some(6), "{msg}");
    // An unknown key inside a scene table, line 1.
    let (line, msg) = line_of_error(
        parse("scenes = [{ name = \"room\", sise = 2 }]\nname = \"t\"\ntracers = [\"reference\"]\nrays = [\"primary\"]\nresolution = { width = 8, height = 4 }\n")
            .unwrap_err(),
    );
    assert_eq!(line, Some(1));
    assert!(msg.contains("sise"), "{msg}");
    // A semantic error with its line: zero repeats on line 6.
    let (line, _) = line_of_error(
        parse(&format!("{BASE}tracers = [\"reference\"]\nrepeats = 0\n")).unwrap_err(),
    );
    assert_eq!(line, Some(6));
}

fn usage_message(e: Error) -> String {
    match e {
        Error::Usage(m) => m,
        other => panic!("expected a usage error, got {other:?}"),
    }
}

#[test]
fn unknown_names_are_usage_errors_naming_file_and_line() {
    let msg =
        usage_message(parse(&format!("{BASE}tracers = [\"reference\", \"nope\"]\n")).unwrap_err());
    assert!(
        msg.starts_with("exp.toml:5: unknown tracer \"nope\""),
        "{msg}"
    );

    let msg = usage_message(
        parse("name = \"t\"\nscenes = [\"room\"]\nrays = [\"primary\",\n \"glossy\"]\nresolution = { width = 8, height = 4 }\ntracers = [\"reference\"]\n")
            .unwrap_err(),
    );
    assert!(
        msg.starts_with("exp.toml:4: unknown ray kind \"glossy\""),
        "{msg}"
    );

    let msg = usage_message(
        parse(&format!(
            "{BASE}tracers = [{{ name = \"reference\", params = {{ leafsize = 2 }} }}]\n"
        ))
        .unwrap_err(),
    );
    assert!(
        msg.starts_with("exp.toml:5: unknown parameter \"leafsize\" for tracer reference"),
        "{msg}"
    );

    let msg = usage_message(
        parse(&format!(
            "{BASE}tracers = [\"reference\"]\nparams = {{ width = [1] }}\n"
        ))
        .unwrap_err(),
    );
    assert!(
        msg.starts_with("exp.toml:6: shared parameter \"width\" is read by none"),
        "{msg}"
    );

    let msg = usage_message(
        parse(&format!("{BASE}tracers = [\"reference\", \"reference\"]\n")).unwrap_err(),
    );
    assert!(msg.contains("listed twice"), "{msg}");
}

#[test]
fn ray_files_mix_with_kinds_relative_to_the_experiment() {
    let text = "name = \"t\"\nscenes = [\"room\"]\ntracers = [\"reference\"]\n\
                rays = [\"primary\", { file = \"sub/a.rays\" }, \"shadow\", { file = \"sub/a.rays\" }]\n\
                resolution = { width = 8, height = 4 }\n";
    let exp = Experiment::parse(Path::new("dir/exp.toml"), text).unwrap();
    assert_eq!(exp.ray_kinds, vec![RayKind::Primary, RayKind::Shadow]);
    assert_eq!(
        exp.ray_files,
        vec![RayFileSpec {
            name: "sub/a.rays".into(),
            path: PathBuf::from("dir/sub/a.rays"),
        }]
    );
    // Files alone are enough rays.
    let only = text
        .replace("\"primary\", ", "")
        .replace("\"shadow\", ", "");
    assert!(Experiment::parse(Path::new("exp.toml"), &only)
        .unwrap()
        .ray_kinds
        .is_empty());
    for (bad, needle) in [
        ("{ file = \"\" }", "empty path"),
        ("{ path = \"a.rays\" }", "unknown field"),
        ("\"a.rays\"", "unknown ray kind"),
    ] {
        let e = parse(&format!(
            "{}tracers = [\"reference\"]\n",
            BASE.replace("[\"primary\"]", &format!("[{bad}]"))
        ))
        .unwrap_err();
        assert_eq!(e.exit_code(), 2);
        assert!(e.to_string().contains(needle), "{bad}: {e}");
        assert!(e.to_string().contains("exp.toml:3"), "{bad}: {e}");
    }
}

#[test]
fn the_render_grid_expands_to_every_combination() {
    let text = "name = \"t\"\nscenes = [\"room\"]\nresolution = { width = 8, height = 4 }\n\
                tracers = [\"reference\"]\nrender = { renderer = \"whitted\", max_depth = [1, 2], \
                assembly = [\"runs\", \"blind\"], pruning = [false, 0.01], materials = \"glass\" }\n";
    let exp = parse(text).unwrap();
    assert!(exp.ray_kinds.is_empty());
    let labels: Vec<String> = exp.renders.iter().map(|r| r.to_string()).collect();
    // Keys vary slowest in name order: assembly, materials, max_depth, pruning.
    let label = |a: &str, d: u32, p: &str| {
        format!("renderer=whitted;assembly={a};materials=glass;max_depth={d};packet=8;pruning={p};shadows=true")
    };
    assert_eq!(
        labels,
        [
            label("runs", 1, "false"),
            label("runs", 1, "0.01"),
            label("runs", 2, "false"),
            label("runs", 2, "0.01"),
            label("blind", 1, "false"),
            label("blind", 1, "0.01"),
            label("blind", 2, "false"),
            label("blind", 2, "0.01"),
        ]
    );
    assert_eq!(whitted(&exp, 1).pruning, Some(0.01));
    assert_eq!(whitted(&exp, 4).assembly, Assembly::Blind);
    assert_eq!(whitted(&exp, 0).materials, Some(Preset::Glass));

    for (bad, word) in [
        ("render = { renderer = \"bidirectional\" }", "renderer"),
        (
            "render = { renderer = \"whitted\", assembly = \"octants\" }",
            "octants",
        ),
        ("render = { renderer = \"whitted\", depth = 2 }", "depth"),
        (
            "render = { renderer = \"whitted\", pruning = -1 }",
            "pruning",
        ),
    ] {
        let text = format!("{BASE}tracers = [\"reference\"]\n{bad}\n");
        let msg = usage_message(parse(&text).unwrap_err());
        assert!(
            msg.starts_with("exp.toml:6:") && msg.contains(word),
            "{msg}"
        );
    }
    // An array of tables: each its own grid, duplicates rejected.
    let text = format!(
        "{BASE}tracers = [\"reference\"]\n[[render]]\nrenderer = \"whitted\"\nmax_depth = 0\nshadows = false\n\
         [[render]]\nrenderer = \"whitted\"\nmax_depth = 2\nmaterials = [\"mirror\", \"glass\"]\n"
    );
    let exp = parse(&text).unwrap();
    let settings: Vec<(u32, bool, Option<Preset>)> = (0..exp.renders.len())
        .map(|r| {
            let s = whitted(&exp, r);
            (s.max_depth, s.shadows, s.materials)
        })
        .collect();
    assert_eq!(
        settings,
        [
            (0, false, None),
            (2, true, Some(Preset::Mirror)),
            (2, true, Some(Preset::Glass))
        ]
    );
    let twice = format!(
        "{BASE}tracers = [\"reference\"]\nrender = [{{ renderer = \"whitted\" }}, {{ renderer = \"whitted\", max_depth = 5 }}]\n"
    );
    let msg = usage_message(parse(&twice).unwrap_err());
    assert!(msg.contains("listed twice"), "{msg}");

    // Separate reflection / refraction limits (Overbeck 2008 §6's kitchen): parsed, and named
    // in the render column only when set.
    let split = format!(
        "{BASE}tracers = [\"reference\"]\nrender = {{ renderer = \"whitted\", max_depth = 4, \
         max_reflection_depth = 1 }}\n"
    );
    let exp = parse(&split).unwrap();
    let s = whitted(&exp, 0);
    assert_eq!((s.reflection_depth(), s.refraction_depth()), (1, 4));
    assert_eq!(
        exp.renders[0].to_string(),
        "renderer=whitted;assembly=ray_types;materials=scene;max_depth=4;max_reflection_depth=1;\
         packet=8;pruning=0.00390625;shadows=true"
    );

    let none = "name = \"t\"\nscenes = [\"room\"]\nresolution = { width = 8, height = 4 }\ntracers = [\"reference\"]\n";
    let (_, msg) = line_of_error(parse(none).unwrap_err());
    assert!(msg.contains("no ray kinds and no render workload"), "{msg}");
}

fn whitted(exp: &Experiment, r: usize) -> WhittedSettings {
    match exp.renders[r] {
        RenderWorkload::Whitted(s) => s,
        RenderWorkload::Distribution(_) => panic!("render {r} is not Whitted"),
    }
}

#[test]
fn a_distribution_grid_expands_like_whitted_and_checks_its_settings() {
    let text = format!(
        "{BASE}tracers = [\"reference\"]\nrender = {{ renderer = \"distribution\", spp = [1, 4], aperture = [0, 0.05], max_depth = 1 }}\n"
    );
    let exp = parse(&text).unwrap();
    let labels: Vec<String> = exp.renders.iter().map(|r| r.to_string()).collect();
    let label = |a: &str, spp: u32| {
        format!(
            "renderer=distribution;aperture={a};focus=camera;max_depth=1;shutter=none;spp={spp}"
        )
    };
    assert_eq!(
        labels,
        [
            label("0", 1),
            label("0", 4),
            label("0.05", 1),
            label("0.05", 4)
        ]
    );
    let RenderWorkload::Distribution(w) = exp.renders[3] else {
        panic!("a distribution workload")
    };
    assert_eq!((w.settings.spp, w.settings.aperture), (4, Some(0.05)));
    let RenderWorkload::Distribution(v) = exp.renders[2] else {
        panic!("a distribution workload")
    };
    assert!(w.same_but_spp(&v));
    for (bad, word) in [
        ("spp = 3", "spp"),
        ("aperture = -1", "aperture"),
        ("shutter = 0", "shutter"),
        ("max_depth = 99", "max_depth"),
        ("assembly = \"runs\"", "assembly"),
    ] {
        let text = format!(
            "{BASE}tracers = [\"reference\"]\nrender = {{ renderer = \"distribution\", {bad} }}\n"
        );
        let msg = usage_message(parse(&text).unwrap_err());
        assert!(
            msg.starts_with("exp.toml:6:") && msg.contains(word),
            "{msg}"
        );
    }
}

#[test]
fn a_path_grid_is_a_sampled_workload_with_its_own_limits() {
    let text = format!(
        "{BASE}tracers = [\"reference\"]\nrender = {{ renderer = \"path\", spp = [1, 3], aperture = 0.1 }}\n"
    );
    let exp = parse(&text).unwrap();
    let labels: Vec<String> = exp.renders.iter().map(|r| r.to_string()).collect();
    assert_eq!(
        labels,
        [
            "renderer=path;aperture=0.1;focus=camera;max_depth=5;shutter=none;spp=1",
            "renderer=path;aperture=0.1;focus=camera;max_depth=5;shutter=none;spp=3"
        ]
    );
    let RenderWorkload::Distribution(w) = exp.renders[1] else {
        panic!("a sampled workload")
    };
    assert_eq!((w.settings.integrator, w.rmse), (Integrator::Path, true));
    let text = format!(
        "{BASE}tracers = [\"reference\"]\nrender = {{ renderer = \"path\", rmse = false }}\n"
    );
    let exp = parse(&text).unwrap();
    assert_eq!(
        exp.renders[0].to_string(),
        "renderer=path;aperture=camera;focus=camera;max_depth=5;rmse=false;shutter=none;spp=16"
    );
    for (bad, word) in [
        ("spp = 0", "spp"),
        ("max_depth = 65", "max_depth"),
        ("rmse = 1", "rmse"),
        ("packet = 4", "packet"),
    ] {
        let text =
            format!("{BASE}tracers = [\"reference\"]\nrender = {{ renderer = \"path\", {bad} }}\n");
        let msg = usage_message(parse(&text).unwrap_err());
        assert!(
            msg.starts_with("exp.toml:6:") && msg.contains(word),
            "{msg}"
        );
    }
}

#[test]
fn interleaved_soft_shadows_are_a_distribution_mode_with_checked_keys() {
    let text = format!(
        "{BASE}tracers = [\"reference\"]\nrender = {{ renderer = \"distribution\", shadows = \"interleaved\", \
         sets = \"lp\", filter = [true, false], retrace = 64, spp = 16 }}\nsoft_shadow = {{ samples = 4, sets = \"hammersley\" }}\n"
    );
    let exp = parse(&text).unwrap();
    assert_eq!(exp.soft_shadow_sets, LightSampleSets::Hammersley);
    let labels: Vec<String> = exp.renders.iter().map(|r| r.to_string()).collect();
    let label = |filter| {
        format!("renderer=distribution;aperture=camera;focus=camera;max_depth=0;shutter=none;spp=16;shadows=interleaved;sets=lp;filter={filter};retrace=64")
    };
    assert_eq!(labels, [label(true), label(false)]);
    let (RenderWorkload::Distribution(a), RenderWorkload::Distribution(b)) =
        (&exp.renders[0], &exp.renders[1])
    else {
        panic!("distribution workloads")
    };
    // Filtered and unfiltered are one error-vs-time plot.
    assert!(a.same_but_spp(b));
    assert_eq!(
        a.settings.soft_shadows.unwrap().refinement(),
        " filtered retrace 64"
    );
    assert_eq!(b.settings.soft_shadows.unwrap().refinement(), " retrace 64");
    for (bad, word) in [
        ("sets = \"lp\"", "needs shadows = \"interleaved\""),
        ("shadows = \"soft\"", "sampled or interleaved"),
        ("shadows = \"interleaved\", sets = \"sobol\"", "sobol"),
        (
            "shadows = \"interleaved\", sets = \"lp\", spp = 9",
            "powers of 4",
        ),
        (
            "shadows = \"interleaved\", retrace = 8, sets = \"lp\"",
            "powers of 4",
        ),
        ("shadows = \"interleaved\", filter = 1", "filter"),
        ("shadows = \"interleaved\", max_depth = 1", "max_depth = 0"),
        ("shadows = \"interleaved\", aperture = 2", "aperture 0"),
    ] {
        let text = format!(
            "{BASE}tracers = [\"reference\"]\nrender = {{ renderer = \"distribution\", {bad} }}\n"
        );
        let msg = usage_message(parse(&text).unwrap_err());
        assert!(
            msg.starts_with("exp.toml:6:") && msg.contains(word),
            "{bad}: {msg}"
        );
    }
    let text = format!(
        "{BASE}tracers = [\"reference\"]\nsoft_shadow = {{ samples = 16, sets = \"halton\" }}\n"
    );
    let msg = usage_message(parse(&text).unwrap_err());
    assert!(
        msg.contains("soft_shadow") && msg.contains("halton"),
        "{msg}"
    );
}
