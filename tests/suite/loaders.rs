//! Every benchmark scene in the shared collection loads with the triangle counts its README and
//! SOURCE.md give, and the BART animations play. The collection is found through
//! `$RAYLAB_SCENES` (default `../shared/scenes` next to the crate); tests skip with a note when
//! it is absent. Each test loads its scene once.

use std::path::PathBuf;
use std::time::Instant;

use raylab::scene::loaders::{load, LoadOptions};
use raylab::scene::{Light, Scene};

fn scenes_dir() -> Option<PathBuf> {
    let dir = std::env::var_os("RAYLAB_SCENES")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared/scenes"));
    if dir.is_dir() {
        Some(dir)
    } else {
        println!(
            "note: scene collection {} not found; skipping",
            dir.display()
        );
        None
    }
}

fn load_scene(relative: &str) -> Option<Scene> {
    let path = scenes_dir()?.join(relative);
    let start = Instant::now();
    let scene = load(&path).unwrap_or_else(|e| panic!("{e}"));
    println!(
        "{relative}: {} triangles in {:.2?}",
        scene.triangle_count(),
        start.elapsed()
    );
    assert!(scene.mesh.triangles.iter().all(|t| t.is_finite()));
    assert_eq!(scene.mesh.material_ids.len(), scene.triangle_count());
    assert!(scene
        .mesh
        .material_ids
        .iter()
        .all(|&m| (m as usize) < scene.materials.len()));
    Some(scene)
}

/// Triangles of `n` default-tessellated spheres and cylinders.
fn sphere_triangles(n: usize) -> usize {
    let s = LoadOptions::default().sphere_segments as usize;
    n * 2 * s * (s / 2 - 1)
}

fn cylinder_triangles(n: usize) -> usize {
    n * 2 * LoadOptions::default().cone_segments as usize
}

#[test]
fn static_meshes_have_their_measured_triangle_counts() {
    let cases = [
        ("conference/conference.obj", 331_179),
        ("sibenik/sibenik.obj", 75_284),
        ("bunny/bunny.obj", 69_451),
        ("teapot/teapot.obj", 6_320),
        ("teapot/teapot_mcguire.obj", 15_704),
        ("toasters/Toasters004.obj", 11_141),
        ("stanford-dragon/dragon_vrip_res2.ply.gz", 202_520),
        ("stanford-dragon/dragon_vrip_res3.ply.gz", 47_794),
        ("stanford-dragon/dragon_vrip_res4.ply.gz", 11_102),
    ];
    for (file, triangles) in cases {
        let Some(scene) = load_scene(file) else {
            return;
        };
        assert_eq!(scene.triangle_count(), triangles, "{file}");
        assert!(scene.animation.is_none() && scene.camera_path.is_none());
        assert_eq!(scene.duration(), 0.0);
    }
}

#[test]
fn conference_keeps_its_degenerate_triangles_and_bounds() {
    let Some(scene) = load_scene("conference/conference.obj") else {
        return;
    };
    let degenerate = scene
        .mesh
        .triangles
        .iter()
        .filter(|t| t.v[0] == t.v[1] || t.v[1] == t.v[2] || t.v[0] == t.v[2])
        .count();
    assert_eq!(degenerate, 52_670);
    let b = scene.mesh.bounds();
    assert!((b.min.x - -1020.13).abs() < 0.01 && (b.max.x - 1685.81).abs() < 0.01);
    assert!((b.min.y - -2.7924).abs() < 1e-3 && (b.max.y - 650.293).abs() < 1e-3);
}

#[test]
fn spd_databases_load_with_their_counts() {
    let Some(balls) = load_scene("spd/balls.nff") else {
        return;
    };
    // One quad and 7,381 spheres.
    assert_eq!(balls.triangle_count(), 2 + sphere_triangles(7_381));
    assert_eq!(balls.lights.len(), 3);
    assert_eq!(balls.camera.fov_y_deg, 45.0);
    assert_eq!(balls.camera.position, glam::Vec3::new(2.1, 1.3, 1.7));
    for (file, triangles, lights) in [
        ("spd/gears.nff", 36_610, 5),
        ("spd/teapot.nff", 2_328, 2),
        ("spd/tetra.nff", 4_096, 1),
    ] {
        let scene = load_scene(file).unwrap();
        assert_eq!(scene.triangle_count(), triangles, "{file}");
        assert_eq!(scene.lights.len(), lights, "{file}");
    }
}

#[test]
fn gears_concave_faces_are_covered_exactly() {
    // The gear faces are concave polygons (SPD gears): ear clipping must cover each exactly,
    // so the total area of the triangles equals the sum of the polygons' (Newell) areas.
    let Some(dir) = scenes_dir() else {
        return;
    };
    let text = std::fs::read_to_string(dir.join("spd/gears.nff")).unwrap();
    let words: Vec<&str> = text.split_whitespace().collect();
    let mut polygon_area = 0.0f64;
    let mut i = 0;
    while i < words.len() {
        if words[i] == "p" {
            let n: usize = words[i + 1].parse().unwrap();
            let v: Vec<glam::DVec3> = (0..n)
                .map(|k| {
                    let w = &words[i + 2 + 3 * k..];
                    glam::DVec3::new(
                        w[0].parse().unwrap(),
                        w[1].parse().unwrap(),
                        w[2].parse().unwrap(),
                    )
                })
                .collect();
            let newell: glam::DVec3 = (0..n).map(|k| v[k].cross(v[(k + 1) % n])).sum();
            polygon_area += 0.5 * newell.length();
            i += 2 + 3 * n;
        } else {
            i += 1;
        }
    }
    let scene = load_scene("spd/gears.nff").unwrap();
    let area: f64 = scene.mesh.triangles.iter().map(|t| t.area() as f64).sum();
    assert!(
        (area - polygon_area).abs() < 1e-4 * polygon_area,
        "{area} vs {polygon_area}"
    );
}

/// The animated geometry at two times: same count and order, different vertices.
fn check_animation_moves(scene: &Scene, t0: f32, t1: f32) {
    let animation = scene.animation.as_ref().expect("animated");
    let (a, b) = (animation.mesh_at(t0), animation.mesh_at(t1));
    assert_eq!(a.len(), scene.triangle_count());
    assert_eq!(b.len(), scene.triangle_count());
    assert_eq!(a.material_ids, b.material_ids);
    assert_ne!(a.triangles, b.triangles);
    assert_eq!(animation.mesh_at(0.0), scene.mesh);
}

fn check_camera_path(scene: &Scene, frames: usize, duration: f32) {
    let path = scene.camera_path.as_ref().expect("camera path");
    assert_eq!(path.keys.len(), frames);
    assert!((path.duration() - duration).abs() < 1e-4);
    assert_eq!(path.keys[0].camera, scene.camera);
    assert_ne!(
        path.keys[0].camera.position,
        path.keys[frames / 2].camera.position
    );
    // Scene::frame over the file's frame count lands on the path's keys.
    for i in [0, 1, frames / 3, frames - 1] {
        let frame = scene.frame(i, frames);
        let key = path.keys[i].camera;
        assert!(
            (frame.camera.position - key.position).length() < 1e-3,
            "frame {i}"
        );
    }
}

#[test]
fn bart_kitchen_plays() {
    let Some(scene) = load_scene("bart-kitchen/kitchen.aff") else {
        return;
    };
    assert_eq!(scene.triangle_count(), 110_561);
    assert_eq!(scene.lights.len(), 6);
    assert!(
        matches!(scene.lights[0], Light::Point { intensity, .. } if intensity == glam::Vec3::splat(0.3))
    );
    assert_eq!(scene.camera.fov_y_deg, 40.0);
    assert_eq!(scene.duration(), 20.0);
    check_camera_path(&scene, 800, 20.0);
    // At the camera's key at 5 s the spline passes through the key's position (3.5, 0.2, 0.1);
    // between frames the path interpolates linearly, 1/40 s apart.
    let at_key = scene.camera_path.as_ref().unwrap().camera_at(5.0).unwrap();
    assert!((at_key.position - glam::Vec3::new(3.5, 0.2, 0.1)).length() < 1e-2);
    // The toy car drives from 3 s on.
    check_animation_moves(&scene, 0.0, 6.0);
    assert!(scene.materials.iter().any(|m| m.is_refractive()));
}

#[test]
fn bart_robots_play() {
    let Some(scene) = load_scene("bart-robots/Robot.aff") else {
        return;
    };
    assert_eq!(scene.triangle_count(), 71_708);
    assert_eq!(scene.lights.len(), 1);
    assert_eq!(scene.duration(), 50.0);
    check_camera_path(&scene, 800, 50.0);
    let at_key = scene.camera_path.as_ref().unwrap().camera_at(5.6).unwrap();
    assert!((at_key.position - glam::Vec3::new(-3.5, 2.0, -202.0)).length() < 1e-2);
    check_animation_moves(&scene, 0.0, 10.0);
}

#[test]
fn bart_museum_plays() {
    let Some(scene) = load_scene("bart-museum/museum5.aff") else {
        return;
    };
    // SOURCE.md's 11,298 (10,274 from `p` and `m` + 1,024 `tpa`), the 10 textured triangles
    // (`tt`, the paintings' canvases) its counting rule leaves out, and the 8 tessellated stands.
    assert_eq!(scene.triangle_count(), 11_298 + 10 + cylinder_triangles(8));
    assert_eq!(scene.lights.len(), 2);
    assert_eq!(scene.duration(), 6.0);
    check_camera_path(&scene, 300, 6.0);
    // Scene time 0 is BART time −1 (`a -1.0 5.0 300`): the camera key at BART 0.5 is at 1.5.
    let at_key = scene.camera_path.as_ref().unwrap().camera_at(1.5).unwrap();
    assert!((at_key.position - glam::Vec3::new(3.0, 2.4, -1.0)).length() < 2e-2);
    check_animation_moves(&scene, 0.0, 2.5);
    // The first `tpa` triangle (the art comes last) sits on its keys at BART times 0 and 1.
    let first_tpa = scene.triangle_count() - 1_024;
    let animation = scene.animation.as_ref().unwrap();
    let v0 = |t: f32| animation.mesh_at(t).triangles[first_tpa].v[0];
    assert_eq!(v0(1.0), glam::Vec3::new(-0.4474, 1.549333, 0.085189));
    assert_eq!(v0(2.0), glam::Vec3::new(-0.12107, 3.370914, 0.157006));
}
