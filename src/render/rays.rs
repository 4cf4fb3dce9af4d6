//! The ray batches every tracer is given: camera rays, and the shadow and diffuse rays that leave
//! their hit points. Generated once per frame and handed unchanged to each tracer.

use glam::Vec3;

use crate::geometry::{CameraGrid, Hit, Ray, RayBatch, RayKind, Triangle};
use crate::render::offset::{coordinate_scale, offset_ray_origin};
use crate::render::sampling::{concentric_disk, cosine_hemisphere, uniform};
use crate::scene::{Camera, Light, Mesh, Scene};
use crate::tracers::visibility;

/// Side of the square screen tiles rays are ordered by.
pub const TILE: u32 = 32;

/// Seed of the lens samples of thin-lens primary rays (primary rays take no seed of their own so
/// that every run of a scene sees the same camera rays).
const LENS_SEED: u64 = 0x5EED_1E45;

/// Precomputed pinhole / thin-lens projection of one camera at one resolution.
pub struct CameraProjection {
    camera: Camera,
    /// The directions through the image (from the lens centre): a pinhole's rays are this grid's,
    /// and a thin lens aims each ray through the plane in focus along them.
    grid: CameraGrid,
}

impl CameraProjection {
    pub fn new(camera: &Camera, width: u32, height: u32) -> Self {
        CameraProjection {
            camera: *camera,
            grid: camera.grid(width, height),
        }
    }

    /// The grid of the camera's rays through pixel centres, for a pinhole (a thin lens's rays
    /// start across the lens).
    pub fn pinhole_grid(&self) -> Option<&CameraGrid> {
        (self.camera.aperture <= 0.0).then_some(&self.grid)
    }

    /// The ray through image position `(x, y)` in pixels (pixel centres at +0.5), `lens` a sample
    /// in [0,1)² used only when the camera has an aperture.
    pub fn ray(&self, x: f32, y: f32, lens: (f32, f32)) -> Ray {
        let c = &self.camera;
        if c.aperture <= 0.0 {
            return self.grid.ray_through(x, y);
        }
        // Thin lens: every ray through the pixel meets the others on the plane in focus.
        let dir = self.grid.through(x, y).normalize();
        let focus = c.position + dir * (c.focus_distance / dir.dot(self.grid.forward));
        let (lx, ly) = concentric_disk(lens.0, lens.1);
        let origin = c.position + (self.grid.right * lx + self.grid.up * ly) * c.aperture;
        Ray::new(origin, (focus - origin).normalize(), 0.0, f32::INFINITY)
    }

    /// Camera rays of the pixels of one tile, Morton order inside the tile; a pinhole's carry
    /// their grid (`RayBatch::push_camera_ray`).
    pub fn tile_rays(&self, tile_x: u32, tile_y: u32, batch: &mut RayBatch) {
        let (width, height) = (self.grid.width, self.grid.height);
        for code in 0..TILE * TILE {
            let (dx, dy) = morton_decode(code);
            let (x, y) = (tile_x * TILE + dx, tile_y * TILE + dy);
            if x < width && y < height {
                let pixel = y * width + x;
                match self.pinhole_grid() {
                    Some(grid) => batch.push_camera_ray(grid, pixel, false),
                    None => {
                        let lens = (
                            uniform(LENS_SEED, pixel as u64, 0),
                            uniform(LENS_SEED, pixel as u64, 1),
                        );
                        batch.push(self.ray(x as f32 + 0.5, y as f32 + 0.5, lens), pixel)
                    }
                }
            }
        }
    }

    pub fn tiles(&self) -> (u32, u32) {
        (
            self.grid.width.div_ceil(TILE),
            self.grid.height.div_ceil(TILE),
        )
    }
}

/// Splits a Morton code into its (x, y): x takes the even bits, y the odd ones.
pub fn morton_decode(code: u32) -> (u32, u32) {
    let compact = |mut v: u32| {
        v &= 0x5555_5555;
        v = (v | (v >> 1)) & 0x3333_3333;
        v = (v | (v >> 2)) & 0x0F0F_0F0F;
        v = (v | (v >> 4)) & 0x00FF_00FF;
        (v | (v >> 8)) & 0x0000_FFFF
    };
    (compact(code), compact(code >> 1))
}

/// Camera rays, one per pixel centre, in 32×32 tiles (row-major) with Morton order inside each
/// tile, so every aligned n×n block (n a power of two ≤ 32) of a full tile is a contiguous range
/// of the batch — the packets of the packet tracers. `pixel` = y·width + x.
pub fn primary_rays(camera: &Camera, width: u32, height: u32) -> RayBatch {
    let projection = CameraProjection::new(camera, width, height);
    let mut batch = RayBatch::with_capacity(RayKind::Primary, (width * height) as usize);
    let (tiles_x, tiles_y) = projection.tiles();
    for ty in 0..tiles_y {
        for tx in 0..tiles_x {
            projection.tile_rays(tx, ty, &mut batch);
        }
    }
    batch
}

/// Where a ray hit a surface: the point, the geometric normal turned to face the incoming ray,
/// and the coordinate scale that sets how far new rays must start from it.
#[derive(Clone, Copy, Debug)]
pub struct SurfacePoint {
    pub p: Vec3,
    pub n: Vec3,
    pub scale: f32,
}

impl SurfacePoint {
    pub fn of_hit(mesh: &Mesh, ray: &Ray, hit: &Hit) -> Self {
        Self::on_triangle(&mesh.triangles[hit.prim as usize], ray, hit)
    }

    /// Where `ray` hit `tri` (the hit's triangle, as the ray saw it).
    pub fn on_triangle(tri: &Triangle, ray: &Ray, hit: &Hit) -> Self {
        let n = tri.normal().normalize_or_zero();
        SurfacePoint {
            p: tri.point(hit.u, hit.v),
            n: if n.dot(ray.dir) > 0.0 { -n } else { n },
            scale: coordinate_scale(tri),
        }
    }

    /// The origin of a ray leaving the surface on the side the normal faces.
    pub fn ray_origin(&self) -> Vec3 {
        offset_ray_origin(self.p, self.n, self.scale)
    }
}

/// A shadow ray from `surface` towards `target`, or `None` when the target is behind the surface
/// (the renderer would not cast it: the point is in its own shadow).
pub fn shadow_ray(surface: &SurfacePoint, target: Vec3) -> Option<Ray> {
    visibility::shadow_ray(surface.p, surface.n, surface.ray_origin(), target)
}

/// One shadow ray per primary hit per light (quad lights: one seeded sample point).
pub fn shadow_rays(
    scene: &Scene,
    mesh: &Mesh,
    primary: &RayBatch,
    hits: &[Hit],
    seed: u64,
) -> RayBatch {
    let mut batch = RayBatch::new(RayKind::Shadow);
    for (i, hit) in hits.iter().enumerate().filter(|(_, h)| h.is_hit()) {
        let surface = SurfacePoint::of_hit(mesh, &primary.ray(i), hit);
        for (l, light) in scene.lights.iter().enumerate() {
            let sample = i as u64 * scene.lights.len() as u64 + l as u64;
            let target = match light {
                Light::Point { .. } => light.sample_point(0.0, 0.0),
                Light::Quad { .. } => {
                    light.sample_point(uniform(seed, sample, 0), uniform(seed, sample, 1))
                }
            };
            if let Some(ray) = shadow_ray(&surface, target) {
                batch.push(ray, primary.pixel[i]);
            }
        }
    }
    batch
}

/// One cosine-weighted diffuse bounce per primary hit, seeded per ray.
pub fn diffuse_rays(mesh: &Mesh, primary: &RayBatch, hits: &[Hit], seed: u64) -> RayBatch {
    let mut batch = RayBatch::new(RayKind::Diffuse);
    for (i, hit) in hits.iter().enumerate().filter(|(_, h)| h.is_hit()) {
        let surface = SurfacePoint::of_hit(mesh, &primary.ray(i), hit);
        let dir = cosine_hemisphere(
            surface.n,
            uniform(seed, i as u64, 0),
            uniform(seed, i as u64, 1),
        );
        batch.push(
            Ray::new(surface.ray_origin(), dir, 0.0, f32::INFINITY),
            primary.pixel[i],
        );
    }
    batch
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn morton_tiles_make_aligned_blocks_contiguous() {
        let cam = Camera::default();
        let batch = primary_rays(&cam, 64, 64);
        assert_eq!(batch.len(), 64 * 64);
        // Every aligned 4×4 block is 16 consecutive rays.
        for block in batch.pixel.chunks(16) {
            let xs: Vec<u32> = block.iter().map(|p| p % 64).collect();
            let ys: Vec<u32> = block.iter().map(|p| p / 64).collect();
            let (x0, y0) = (xs.iter().min().unwrap(), ys.iter().min().unwrap());
            assert_eq!(x0 % 4, 0);
            assert_eq!(y0 % 4, 0);
            assert!(xs.iter().all(|x| x - x0 < 4) && ys.iter().all(|y| y - y0 < 4));
        }
        // Every pixel exactly once.
        let mut seen = batch.pixel.clone();
        seen.sort();
        assert!(seen.iter().enumerate().all(|(i, &p)| i as u32 == p));
    }

    #[test]
    fn pinhole_batches_carry_their_grid_and_thin_lens_batches_none() {
        let batch = primary_rays(&Camera::default(), 50, 37);
        let grid = batch
            .camera
            .as_deref()
            .expect("a pinhole batch carries its grid");
        assert_eq!(*grid, Camera::default().grid(50, 37));
        let bits = |r: Ray| [r.origin, r.dir].map(|v| v.to_array().map(f32::to_bits));
        for i in 0..batch.len() {
            assert_eq!(bits(grid.pixel_ray(batch.pixel[i])), bits(batch.ray(i)));
        }
        let lens = Camera {
            aperture: 0.1,
            focus_distance: 4.0,
            ..Camera::default()
        };
        assert!(primary_rays(&lens, 50, 37).camera.is_none());
    }

    #[test]
    fn partial_tiles_cover_odd_resolutions() {
        let batch = primary_rays(&Camera::default(), 50, 37);
        let mut seen = batch.pixel.clone();
        seen.sort();
        assert_eq!(seen, (0..50 * 37).collect::<Vec<u32>>());
    }

    #[test]
    fn centre_pixel_looks_at_the_target_and_corners_span_the_fov() {
        let cam = Camera {
            position: Vec3::ZERO,
            target: -Vec3::Z,
            up: Vec3::Y,
            fov_y_deg: 90.0,
            ..Camera::default()
        };
        let proj = CameraProjection::new(&cam, 100, 100);
        let centre = proj.ray(50.0, 50.0, (0.5, 0.5));
        assert!(centre.dir.distance(-Vec3::Z) < 1e-6);
        let top = proj.ray(50.0, 0.0, (0.5, 0.5));
        // 90° vertical fov: the top edge ray is 45° up.
        assert!((top.dir.y - std::f32::consts::FRAC_1_SQRT_2).abs() < 1e-5);
        let right = proj.ray(100.0, 50.0, (0.5, 0.5));
        assert!(right.dir.x > 0.7, "x grows to the right");
    }

    #[test]
    fn thin_lens_rays_converge_on_the_focus_plane() {
        let cam = Camera {
            position: Vec3::ZERO,
            target: -Vec3::Z,
            aperture: 0.5,
            focus_distance: 4.0,
            ..Camera::default()
        };
        let proj = CameraProjection::new(&cam, 64, 64);
        let a = proj.ray(10.5, 20.5, (0.1, 0.9));
        let b = proj.ray(10.5, 20.5, (0.8, 0.3));
        assert!(a.origin.distance(b.origin) > 0.1);
        let pa = a.at(4.0 / -a.dir.z);
        let pb = b.at(4.0 / -b.dir.z);
        assert!(pa.distance(pb) < 1e-4, "{pa:?} vs {pb:?}");
    }

    #[test]
    fn shadow_ray_is_skipped_behind_the_surface_and_stops_short_of_the_light() {
        let surface = SurfacePoint {
            p: Vec3::ZERO,
            n: Vec3::Y,
            scale: 1.0,
        };
        assert!(shadow_ray(&surface, Vec3::new(0.0, -1.0, 0.0)).is_none());
        let r = shadow_ray(&surface, Vec3::new(0.0, 2.0, 0.0)).unwrap();
        assert!(r.origin.y > 0.0 && r.tmax < 2.0 && r.tmax > 1.99);
    }
}
