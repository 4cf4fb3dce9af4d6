//! The path tracer (Gribble & Ramani 2008 §4; `render::path`): every tracer renders the same
//! image from the same rays and samples; energy tests with closed enclosures of known radiance
//! (white furnace, glass slab); next-event estimation agrees with hitting an emitting surface;
//! the error against a high-sample image falls as 1/√spp; shading runs as a counted filter stack
//! that does not change the image.

use glam::Vec3;
use raylab::geometry::Triangle;
use raylab::render::distribution::{
    render_sampled, DrtFrame, DrtSettings, FrameGeometry, Integrator,
};
use raylab::render::image::Image;
use raylab::render::wavefront::Tracing;
use raylab::scene::library::load_scene;
use raylab::scene::{Camera, Light, Material, Mesh, Scene};
use raylab::tracers::{tracer_for_frame, Params};

fn render(scene: &Scene, tracer: &str, settings: &DrtSettings) -> DrtFrame {
    let frame = scene.frame(0, 1);
    let tracer = tracer_for_frame(tracer, &Params::new(), &frame).unwrap();
    render_sampled(
        scene,
        &frame,
        FrameGeometry::Static(&frame.mesh),
        tracer.as_ref(),
        settings,
        Tracing::Timed,
    )
    .unwrap()
}

fn path_settings(width: u32, height: u32, spp: u32, max_depth: u32) -> DrtSettings {
    DrtSettings {
        integrator: Integrator::Path,
        width,
        height,
        spp,
        max_depth,
        ..DrtSettings::default()
    }
}

/// The 12 triangles of the box `[min, max]`, wound counter-clockwise seen from outside.
fn push_box(mesh: &mut Mesh, min: Vec3, max: Vec3, material: u32) {
    let centre = (min + max) * 0.5;
    let corner = |i: usize| {
        Vec3::new(
            if i & 1 == 0 { min.x } else { max.x },
            if i & 2 == 0 { min.y } else { max.y },
            if i & 4 == 0 { min.z } else { max.z },
        )
    };
    // Each face as four corner indices in cyclic order.
    let faces = [
        [0, 2, 6, 4],
        [1, 3, 7, 5],
        [0, 1, 5, 4],
        [2, 3, 7, 6],
        [0, 1, 3, 2],
        [4, 5, 7, 6],
    ];
    for f in faces {
        let [a, b, c, d] = f.map(corner);
        let face_centre = (a + b + c + d) * 0.25;
        for (p, q, r) in [(a, b, c), (a, c, d)] {
            let t = Triangle::new(p, q, r);
            let t = if t.normal().dot(face_centre - centre) < 0.0 {
                Triangle::new(p, r, q)
            } else {
                t
            };
            mesh.push(t, material);
        }
    }
}

/// A closed 4×4×4 enclosure of `wall` with the camera inside, looking at what `inside` adds.
fn enclosure(wall: Material, inside: &[(Vec3, Vec3, Material)]) -> Scene {
    let mut mesh = Mesh::default();
    push_box(&mut mesh, Vec3::splat(-2.0), Vec3::splat(2.0), 0);
    let mut materials = vec![wall];
    for (min, max, material) in inside {
        push_box(&mut mesh, *min, *max, materials.len() as u32);
        materials.push(material.clone());
    }
    Scene {
        name: "enclosure".into(),
        source: "test".into(),
        mesh,
        materials,
        lights: Vec::new(),
        camera: Camera {
            position: Vec3::new(0.3, 0.9, 1.8),
            target: Vec3::new(0.0, -0.2, 0.0),
            fov_y_deg: 70.0,
            ..Camera::default()
        },
        camera_path: None,
        animation: None,
    }
}

fn emitter(name: &str, albedo: f32, emission: f32) -> Material {
    Material {
        emission: Vec3::splat(emission),
        ..Material::diffuse(name, Vec3::splat(albedo))
    }
}

fn mean(image: &Image) -> f64 {
    image
        .pixels
        .iter()
        .map(|p| p.element_sum() as f64 / 3.0)
        .sum::<f64>()
        / image.pixels.len() as f64
}

/// The room lit by its quad light, with all three materials of the paper: a coupled glossy
/// (Ashikhmin–Shirley) floor with its mirror coat, a glass box floating above the red box, the
/// rest Lambertian. The glass touches nothing: a glass box standing on the floor meets it in a
/// coplanar tie, which tracers break differently (tests/suite/whitted.rs), sending paths apart.
fn three_material_room() -> Scene {
    let mut scene = load_scene("room-area-light", None).unwrap();
    for m in &mut scene.materials {
        if m.name == "floor" {
            m.glossy = Some((40.0, 0.3));
        }
    }
    let glass = Material {
        dielectric: Some((1.5, 0.95)),
        ..Material::diffuse("glass", Vec3::ZERO)
    };
    scene.materials.push(glass);
    let id = scene.materials.len() as u32 - 1;
    push_box(
        &mut scene.mesh,
        Vec3::new(2.0, 2.0, 3.0),
        Vec3::new(3.5, 3.2, 4.5),
        id,
    );
    scene
}

#[test]
fn every_tracer_renders_the_same_image() {
    let scene = three_material_room();
    let settings = DrtSettings {
        aperture: Some(0.05),
        focus_distance: Some(8.0),
        ..path_settings(64, 48, 4, 5)
    };
    let reference = render(&scene, "reference", &settings);
    assert!(mean(&reference.image) > 0.0);
    // The same rays (counts per batch) for everyone.
    let shape = |f: &DrtFrame| -> Vec<(u32, &str, usize)> {
        f.batches
            .iter()
            .map(|b| (b.depth, b.kind.name(), b.rays))
            .collect()
    };
    // The same camera rays and first bounce for everyone, and the same image up to a path or
    // two that a last-bit difference in a hit point (tests/suite/whitted.rs) sends elsewhere, e.g.
    // through an edge of the glass box or past a Russian roulette threshold.
    let mean_value = mean(&reference.image);
    for tracer in ["packet", "stream", "obvhs", "embree16"] {
        let frame = render(&scene, tracer, &settings);
        assert_eq!(shape(&frame)[..3], shape(&reference)[..3], "{tracer}");
        let apart = frame
            .image
            .pixels
            .iter()
            .zip(&reference.image.pixels)
            .filter(|(a, b)| (**a - **b).abs().max_element() > 1e-4)
            .count();
        let rmse = frame.image.rmse(&reference.image);
        println!("{tracer}: {apart} pixels apart, RMSE {rmse:e} (mean {mean_value:e})");
        assert!(
            apart * 200 <= frame.image.pixels.len(),
            "{tracer}: {apart} apart"
        );
        assert!(rmse < 0.01 * mean_value, "{tracer}: RMSE {rmse}");
    }
    // And the same image again: the samples are fixed.
    assert!(render(&scene, "reference", &settings).image == reference.image);
}

/// White furnace: inside a closed enclosure of black walls emitting E, surfaces of albedo 1
/// (two boxes, so paths bounce between them too) reflect exactly E: every pixel reads E.
#[test]
fn white_furnace_reads_the_emission_everywhere() {
    let white = Material::diffuse("white", Vec3::ONE);
    let scene = enclosure(
        emitter("wall", 0.0, 0.5),
        &[
            (
                Vec3::new(-1.0, -2.0, -1.0),
                Vec3::new(0.0, -0.5, 0.0),
                white.clone(),
            ),
            (Vec3::new(0.0, -2.0, -1.0), Vec3::new(1.0, 0.5, 0.0), white),
        ],
    );
    let frame = render(&scene, "reference", &path_settings(48, 36, 4, 64));
    for p in &frame.image.pixels {
        assert!((*p - Vec3::splat(0.5)).abs().max_element() < 1e-3, "{p}");
    }
    // The albedo-1 boxes are seen and bounced from: more path rays than camera rays.
    let bounced: usize = frame
        .batches
        .iter()
        .filter(|b| b.depth > 0)
        .map(|b| b.rays)
        .sum();
    assert!(bounced > 48 * 36 * 4 / 4, "{bounced}");
}

/// Furnace with grey walls: an enclosure of albedo a emitting E has radiance E / (1 − a)
/// everywhere; here a = 0.5, so 2E, through Russian roulette and up to 64 bounces.
#[test]
fn grey_furnace_reads_the_geometric_series() {
    let scene = enclosure(emitter("wall", 0.5, 0.25), &[]);
    let frame = render(&scene, "reference", &path_settings(48, 36, 16, 64));
    let m = mean(&frame.image);
    assert!((m - 0.5).abs() < 0.01, "mean {m}, expected 0.5");
    // Russian roulette ended most paths well before the depth limit.
    assert!(
        frame.batches.iter().all(|b| b.depth < 40),
        "{:?}",
        frame.batches.len()
    );
}

/// Dielectric energy: a glass slab (transmittance 1) inside an enclosure of black walls emitting
/// E neither absorbs nor creates light: every pixel, through the glass or not, reads E; with
/// transmittance 0.5 the slab's pixels darken (the slab is seen).
#[test]
fn glass_slab_conserves_energy() {
    let slab = |transmittance: f32| {
        let glass = Material {
            dielectric: Some((1.5, transmittance)),
            ..Material::diffuse("glass", Vec3::ZERO)
        };
        enclosure(
            emitter("wall", 0.0, 0.5),
            &[(
                Vec3::new(-1.0, -0.6, -1.0),
                Vec3::new(1.0, -0.3, 1.0),
                glass,
            )],
        )
    };
    let settings = path_settings(48, 36, 4, 64);
    let clear = render(&slab(1.0), "reference", &settings).image;
    let off = clear
        .pixels
        .iter()
        .filter(|p| (**p - Vec3::splat(0.5)).abs().max_element() > 1e-3)
        .count();
    assert!(off * 200 <= clear.pixels.len(), "{off} pixels off");
    assert!((mean(&clear) - 0.5).abs() < 2e-3, "mean {}", mean(&clear));
    let tinted = render(&slab(0.5), "reference", &settings).image;
    let dark = tinted.pixels.iter().filter(|p| p.x < 0.45).count();
    assert!(
        dark * 10 > tinted.pixels.len(),
        "{dark} pixels see the slab"
    );
}

/// Next-event estimation is normalised like a BRDF-sampled hit: a floor lit by a quad light
/// (NEE) is as bright as the same floor under an emitting, black quad of the same radiance
/// found by the path rays alone.
#[test]
fn next_event_estimation_agrees_with_hitting_the_emitter() {
    let mut mesh = Mesh::default();
    push_box(
        &mut mesh,
        Vec3::new(-3.0, -1.0, -3.0),
        Vec3::new(3.0, 0.0, 3.0),
        0,
    );
    let (corner, edge_u, edge_v) = (Vec3::new(-0.5, 1.5, -0.5), Vec3::X, Vec3::Z);
    let camera = Camera {
        position: Vec3::new(0.0, 4.0, 0.01),
        target: Vec3::ZERO,
        fov_y_deg: 50.0,
        ..Camera::default()
    };
    let mut lit = Scene {
        name: "floor".into(),
        source: "test".into(),
        mesh,
        materials: vec![Material::diffuse("floor", Vec3::splat(0.8))],
        lights: vec![Light::Quad {
            corner,
            edge_u,
            edge_v,
            emission: Vec3::splat(4.0),
        }],
        camera,
        camera_path: None,
        animation: None,
    };
    let settings = path_settings(32, 32, 64, 1);
    let nee = render(&lit, "reference", &settings).image;
    // The same light as geometry: two triangles facing down, black, emitting.
    lit.lights.clear();
    lit.materials.push(emitter("lamp", 0.0, 4.0));
    let c = corner;
    lit.mesh
        .push(Triangle::new(c, c + edge_u, c + edge_u + edge_v), 1);
    lit.mesh
        .push(Triangle::new(c, c + edge_u + edge_v, c + edge_v), 1);
    let hit = render(&lit, "reference", &settings).image;
    // Pixels the lamp does not cover (camera rays pass a light but hit the emitting quad).
    let floor = |img: &Image| -> f64 {
        let px: Vec<f64> = img
            .pixels
            .iter()
            .enumerate()
            .filter(|(i, _)| {
                let (x, y) = (i % 32, i / 32);
                !(8..24).contains(&x) || !(8..24).contains(&y)
            })
            .map(|(_, p)| p.x as f64)
            .collect();
        px.iter().sum::<f64>() / px.len() as f64
    };
    let (a, b) = (floor(&nee), floor(&hit));
    assert!(a > 0.05, "the floor is lit: {a}");
    assert!((a - b).abs() < 0.05 * a, "NEE {a} vs emitter hits {b}");
}

/// RMSE against a 256-spp image of the same frame falls as 1/√spp: 4× the samples roughly halve
/// it (the reference's own noise adds σ²/256 to both).
#[test]
fn rmse_falls_as_one_over_root_spp() {
    let scene = three_material_room();
    let reference = render(&scene, "reference", &path_settings(40, 30, 256, 4)).image;
    let rmse: Vec<f64> = [4, 16, 64]
        .iter()
        .map(|&spp| {
            render(&scene, "reference", &path_settings(40, 30, spp, 4))
                .image
                .rmse(&reference)
        })
        .collect();
    println!("rmse at 4, 16, 64 spp: {rmse:?}");
    for pair in rmse.windows(2) {
        let ratio = pair[1] / pair[0];
        assert!((0.35..=0.65).contains(&ratio), "{rmse:?}: ratio {ratio}");
    }
}

/// Shading runs as Fig. 4's filter stack over streams of the bounce's rays: the image does not
/// depend on the stream size or width, the counted closest-hit batches carry the shading
/// filters' counts (every ray passes at least the miss or hit filter), utilisation is at most 1,
/// and longer initial streams give longer shading streams (Gribble & Ramani Table 4's trend).
#[test]
fn shading_filters_are_counted_and_do_not_change_the_image() {
    use raylab::render::path::ShadeStreams;
    use raylab::stats::Event;
    let scene = three_material_room();
    let frame = scene.frame(0, 1);
    let tracer = tracer_for_frame("stream", &Params::new(), &frame).unwrap();
    let run = |stream: usize, width: usize| {
        let settings = DrtSettings {
            shade: ShadeStreams { stream, width },
            ..path_settings(48, 32, 4, 4)
        };
        render_sampled(
            &scene,
            &frame,
            FrameGeometry::Static(&frame.mesh),
            tracer.as_ref(),
            &settings,
            Tracing::Counted,
        )
        .unwrap()
    };
    let mut lengths = Vec::new();
    let mut image = None;
    for (stream, width) in [(16, 16), (1024, 16), (4096, 16), (4096, 8)] {
        let out = run(stream, width);
        if let Some(first) = &image {
            assert!(out.image == *first, "stream {stream}, width {width}");
        }
        image.get_or_insert(out.image.clone());
        let (mut filters, mut active, mut issued) = (0, 0, 0);
        for b in out.batches.iter().filter(|b| b.kind.name() != "shadow") {
            let c = &b.counters;
            assert!(c.get(Event::ShadeLanesActive) >= b.rays as u64, "{b:?}");
            filters += c.get(Event::ShadeFilters);
            active += c.get(Event::ShadeLanesActive);
            issued += c.get(Event::ShadeLanesIssued);
        }
        assert!(active <= issued && issued < active + filters * width as u64);
        lengths.push(active as f64 / filters as f64);
    }
    assert!(
        lengths[0] < lengths[1] && lengths[1] < lengths[2],
        "{lengths:?}"
    );
    assert!(lengths[0] <= 16.0, "{lengths:?}");
}

/// Gribble & Ramani fill their input buffer with one camera ray per pixel (§4); pass by pass
/// (`order = "passes"`), a wave's camera rays come every pixel's sample 0 first, and the image is
/// the same, bit for bit. A tile subset (`tiles = 2`: the 32×32 tiles on every second diagonal)
/// traces those tiles exactly as the whole frame does, and nothing else.
#[test]
fn pass_order_and_tile_subsets_change_which_rays_go_together_not_what_they_see() {
    use raylab::geometry::RayKind;
    let scene = three_material_room();
    let settings = path_settings(64, 64, 4, 2);
    let whole = render(&scene, "reference", &settings);
    let by_pass = DrtSettings {
        passes: true,
        ..settings
    };
    let passes = render(&scene, "reference", &by_pass);
    assert!(passes.image == whole.image);
    let camera = |f: &DrtFrame| f.totals(RayKind::Primary).rays;
    assert_eq!(camera(&passes), 64 * 64 * 4);
    let subset = render(
        &scene,
        "reference",
        &DrtSettings {
            tiles: 2,
            ..settings
        },
    );
    assert_eq!(camera(&subset), 2 * 32 * 32 * 4, "tiles (0, 0) and (1, 1)");
    for (i, (&ours, &all)) in subset
        .image
        .pixels
        .iter()
        .zip(&whole.image.pixels)
        .enumerate()
    {
        let (x, y) = (i % 64, i / 64);
        let traced = (x / 32 + y / 32) % 2 == 0;
        assert_eq!(
            ours,
            if traced { all } else { Vec3::ZERO },
            "pixel ({x}, {y})"
        );
    }
}
