//! Renderer v0: ray casting with point-light shadows and Lambert shading. Screen tiles (32×32, the
//! same tiles as `rays::primary_rays`) are spread over the rayon pool; each tile traces its camera
//! rays and then its shadow rays as batches. No randomness: the image is the same on every run and
//! at every thread count.

use glam::Vec3;
use rayon::prelude::*;

use crate::geometry::{Hit, RayBatch, RayKind};
use crate::render::image::Image;
use crate::render::rays::{shadow_ray, CameraProjection, SurfacePoint};
use crate::render::shading::{light_as_point, AMBIENT, BACKGROUND};
use crate::scene::{Frame, Scene};
use crate::tracers::Tracer;

pub fn render_raycast(
    scene: &Scene,
    frame: &Frame,
    tracer: &dyn Tracer,
    width: u32,
    height: u32,
) -> Image {
    let projection = CameraProjection::new(&frame.camera, width, height);
    let (tiles_x, tiles_y) = projection.tiles();
    let lights: Vec<(Vec3, Vec3)> = scene.lights.iter().map(light_as_point).collect();
    let shaded: Vec<Vec<(u32, Vec3)>> = (0..tiles_x * tiles_y)
        .into_par_iter()
        .map(|tile| {
            let mut primary = RayBatch::new(RayKind::Primary);
            projection.tile_rays(tile % tiles_x, tile / tiles_x, &mut primary);
            let mut hits = vec![Hit::MISS; primary.len()];
            tracer.intersect(primary.view(), &mut hits);

            // Shadow rays of the tile, remembering which (ray, light) each one serves.
            let mut shadows = RayBatch::new(RayKind::Shadow);
            let mut served = Vec::new();
            for (i, hit) in hits.iter().enumerate().filter(|(_, h)| h.is_hit()) {
                let surface = SurfacePoint::of_hit(&frame.mesh, &primary.ray(i), hit);
                let (p, n) = (surface.p, surface.n);
                for (l, (position, _)) in lights.iter().enumerate() {
                    if let Some(ray) = shadow_ray(&surface, *position) {
                        shadows.push(ray, primary.pixel[i]);
                        served.push((
                            i,
                            l,
                            n.dot((*position - p).normalize()),
                            (*position - p).length_squared(),
                        ));
                    }
                }
            }
            let mut occluded = vec![false; shadows.len()];
            tracer.occluded(shadows.view(), &mut occluded);

            let mut colour: Vec<Vec3> = hits
                .iter()
                .map(|h| {
                    if h.is_hit() {
                        Vec3::splat(AMBIENT)
                    } else {
                        BACKGROUND
                    }
                })
                .collect();
            for (&(i, l, cos, d2), _) in served.iter().zip(&occluded).filter(|(_, o)| !**o) {
                colour[i] += lights[l].1 * (cos / d2);
            }
            (0..primary.len())
                .map(|i| {
                    let hit = &hits[i];
                    let c = if hit.is_hit() {
                        let m =
                            &scene.materials[frame.mesh.material_ids[hit.prim as usize] as usize];
                        m.diffuse * colour[i] + m.emission
                    } else {
                        colour[i]
                    };
                    (primary.pixel[i], c)
                })
                .collect()
        })
        .collect();
    let mut image = Image::new(width, height);
    for (pixel, c) in shaded.into_iter().flatten() {
        image.pixels[pixel as usize] = c;
    }
    image
}
