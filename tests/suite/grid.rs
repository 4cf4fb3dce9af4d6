//! `grid-dda` against Embree (robust mode) through `raylab verify`'s comparison: primary, shadow
//! and diffuse rays on built-in scenes — static (room, balls), animated mid-motion (marbles, frame 1
//! of 3) — and the real bunny, with zero unexplained disagreements and p99 distance error ≤ 1e-4.

use raylab::scene::library::load_scene;
use raylab::tracers::Params;
use raylab::verify::{format_table, verify_frame, Tolerance};

fn verify(name: &str, size: Option<u32>, frame: usize, frames: usize) {
    let scene = load_scene(name, size).unwrap();
    let frame = scene.frame(frame, frames);
    let tol = Tolerance::default();
    let reports = verify_frame(&scene, &frame, "grid-dda", &Params::new(), 256, 256, 1).unwrap();
    println!(
        "grid-dda on {name} ({} triangles):\n{}",
        frame.mesh.len(),
        format_table(&reports, &tol)
    );
    assert!(reports.len() >= 2, "{name}: primary and diffuse at least");
    for r in &reports {
        assert!(r.rays > 0);
        assert!(
            r.passes(&tol),
            "{name}/{}: {} unexplained, p99 error {:e}",
            r.kind.name(),
            r.unexplained,
            r.distance_error[2]
        );
    }
}

#[test]
fn grid_dda_verifies_on_room() {
    verify("room", None, 0, 1);
}

#[test]
fn grid_dda_verifies_on_balls() {
    verify("balls", Some(2), 0, 1);
}

#[test]
fn grid_dda_verifies_on_animated_marbles() {
    verify("marbles", None, 1, 3);
}

#[test]
fn grid_dda_verifies_on_bunny() {
    if let Err(e) = load_scene("bunny", None) {
        eprintln!("NOTE: skipping bunny, real scenes not found ({e}); set RAYLAB_SCENES");
        return;
    }
    verify("bunny", None, 0, 1);
}
