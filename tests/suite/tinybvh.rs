//! The tinybvh baseline beyond agreement with Embree (tests/suite/embree_agreement.rs): its packet tracer
//! really gets the camera rays' 16×16 blocks (not single rays behind its name), and every case of
//! the stability suite is answered without a crash, a hang or an ill-formed ray hit — tinybvh
//! exits the process on a NaN ray, and raylab must never hand it one. Whether tinybvh is
//! watertight is printed (it is not: Möller–Trumbore), not asserted.

#![cfg(tinybvh)]

use std::process::Command;
use std::time::Duration;

use raylab::render::rays::primary_rays;
use raylab::scene::library::load_scene;
use raylab::tracers::chunked::trace_hits;
use raylab::tracers::tinybvh::tile::{block_slots, mirrored, PACKET};
use raylab::tracers::{tracer_for_frame, Params, TracerInfo};
use raylab::verify::stability::cases::Case;
use raylab::verify::stability::{generate, run, CaseKind, Contender, Status};

use crate::common;
use common::smaller_sweep;

/// A camera batch of full 32×32 tiles: every aligned run of 256 rays is a 16×16 block, in the
/// slots Intersect256Rays expects; raylab's cameras are the handedness it must mirror. At an edge
/// of partial tiles some runs are not blocks (they go by single rays) and the hits are the same.
#[test]
fn camera_batches_come_in_blocks_the_packet_kernel_takes() {
    let scene = load_scene("room", None).unwrap();
    let frame = scene.frame(0, 1);
    let batch = primary_rays(&frame.camera, 64, 64);
    let rays = batch.view();
    let camera = rays
        .camera
        .expect("a pinhole camera's batch carries its grid");
    assert!(mirrored(camera));
    for start in (0..rays.len()).step_by(PACKET) {
        let slots = block_slots(camera, &rays.pixel[start..start + PACKET]);
        assert!(slots.is_some(), "rays {start}..: not a 16×16 block");
    }
    let ragged = primary_rays(&frame.camera, 40, 24);
    let view = ragged.view();
    let blocks = (0..view.len() / PACKET)
        .filter(|b| block_slots(camera_of(&view), &view.pixel[b * PACKET..][..PACKET]).is_some())
        .count();
    assert!(
        blocks < view.len() / PACKET,
        "some runs straddle partial tiles"
    );
    let single = tracer_for_frame("tinybvh-2", &Params::new(), &frame).unwrap();
    let packets = tracer_for_frame("tinybvh-256", &Params::new(), &frame).unwrap();
    for batch in [&batch, &ragged] {
        let (a, b) = (trace_hits(&*single, batch), trace_hits(&*packets, batch));
        // The two kernels share the tree and the triangle test's formula, not its threshold: a
        // ray through a shared edge may name either triangle.
        let differ = a.iter().zip(&b).filter(|(a, b)| a.prim != b.prim).count();
        assert!(
            differ * 1000 <= a.len(),
            "{differ} of {} rays differ",
            a.len()
        );
        assert!(a.iter().filter(|h| h.is_hit()).count() * 2 > a.len());
    }
}

fn camera_of<'a>(rays: &raylab::geometry::Rays<'a>) -> &'a raylab::geometry::CameraGrid {
    rays.camera.expect("a pinhole camera's batch")
}

#[test]
fn tinybvh_answers_every_stiff_case_without_a_crash() {
    let sweep = smaller_sweep();
    let contenders: Vec<Contender> = ["tinybvh-2", "tinybvh-4", "tinybvh-8", "tinybvh-256"]
        .into_iter()
        .map(|name| {
            let info = TracerInfo::find(name).unwrap();
            Contender::new(name.to_string(), info, Params::new()).unwrap()
        })
        .collect();
    // Each case is named before it runs: a crash (tinybvh's cannot be caught) shows which.
    let progress = |case: &Case, c: &Contender| {
        eprintln!(
            "{} {:?} {} ({} triangles)",
            c.label,
            case.kind,
            case.variant,
            case.mesh.len()
        )
    };
    let outcomes = run(
        generate(&sweep),
        &contenders,
        Duration::from_secs(120),
        &progress,
    )
    .unwrap();
    assert!(!outcomes.is_empty());
    for o in &outcomes {
        assert_eq!(o.status, Status::Answered, "{o:?}");
        if o.kind == CaseKind::IllFormed {
            assert_eq!(o.false_hits, 0, "an ill-formed ray hit: {o:?}");
        }
        if o.leaks + o.missed + o.false_hits > 0 {
            println!(
                "{} {:?} {} (magnitude {:e}): {} leaks, {} missed, {} false hits of {} rays",
                o.tracer, o.kind, o.variant, o.magnitude, o.leaks, o.missed, o.false_hits, o.rays
            );
        }
    }
}

/// `tools/tinybvh-direct.cpp`, the independent check of the tinybvh rows (docs/REFERENCE.md,
/// Kernel work), builds with the shim's flags against the same header and, on the scene and rays
/// `raylab run --dump-rays` wrote, hits the same triangles as raylab's `tinybvh-8` on those rays
/// (their count and the sum of their ids): the two call the same tinybvh on the same work, so a
/// tool that read the dump wrongly (a field out of place) would differ.
#[test]
fn the_direct_check_finds_the_hits_of_the_tinybvh_rows() {
    let dir = common::scratch_in("tinybvh", "direct");
    let cache = std::env::var_os("RAYLAB_TINYBVH_DIR")
        .map(std::path::PathBuf::from)
        .unwrap_or_else(|| {
            std::path::Path::new(&std::env::var_os("HOME").unwrap()).join(".cache/raylab/tinybvh")
        });
    let tool = dir.join("tinybvh-direct");
    let source = concat!(env!("CARGO_MANIFEST_DIR"), "/tools/tinybvh-direct.cpp");
    succeeded(
        Command::new(std::env::var("CXX").unwrap_or_else(|_| "c++".into()))
            .args(["-std=c++20", "-O2", "-march=native", "-I"])
            .arg(cache.join("include"))
            .arg("-o")
            .arg(&tool)
            .arg(source),
    );
    std::fs::write(
        dir.join("dump.toml"),
        "name = \"dump\"\nscenes = [\"room\"]\ntracers = [\"reference\"]\n\
         rays = [\"primary\", \"diffuse\"]\nresolution = { width = 48, height = 48 }\n\
         warmup = 0\nrepeats = 1\n",
    )
    .unwrap();
    succeeded(
        Command::new(env!("CARGO_BIN_EXE_raylab"))
            .args(["run", "dump.toml", "--dump-rays", "--quiet"])
            .current_dir(&dir)
            .env_remove("RAYLAB_SCENES"),
    );
    let dumped = common::only_run(&dir.join("results"), "dump").join("rays");
    let scene = load_scene("room", None).unwrap();
    let frame = scene.frame(0, 1);
    let raylab_tinybvh = tracer_for_frame("tinybvh-8", &Params::new(), &frame).unwrap();
    for kind in ["primary", "diffuse"] {
        let rays = dumped.join(format!("room-f0-{kind}.rays"));
        let batch = raylab::geometry::ray_file::read_rays(&rays).unwrap();
        let found = trace_hits(&*raylab_tinybvh, &batch);
        let met: Vec<u64> = found
            .iter()
            .filter(|h| h.is_hit())
            .map(|h| h.prim as u64)
            .collect();
        let expected = format!(
            "{} hit, triangle ids summing to {}",
            met.len(),
            met.iter().sum::<u64>()
        );
        let line = succeeded(
            Command::new(&tool)
                .arg(dumped.join("room-f0.tris"))
                .arg(&rays)
                .args(["--repeats", "1"]),
        );
        assert!(met.len() > batch.len() / 2, "{kind}: {expected}");
        assert!(
            line.trim_end().ends_with(&expected),
            "{kind}: {line} (raylab: {expected})"
        );
    }
}

/// `command`'s standard output, once it has run and exited with success (else its errors).
fn succeeded(command: &mut Command) -> String {
    let out = command.output().unwrap();
    assert!(
        out.status.success(),
        "{command:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}
