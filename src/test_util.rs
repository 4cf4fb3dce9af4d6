//! Fixtures shared by the unit tests and the integration tests in `tests/`: seeded triangle
//! soups, awkward rays for slab tests, and the exact-tie check hit comparisons allow. Not part of the testbed's interface (hidden from the docs).

use glam::Vec3;

use crate::geometry::{Hit, Ray, RayBatch, RayKind, RayTests, Robust, Triangle};
use crate::random::SplitMix64;

/// A seeded triangle soup: triangles with centres uniform in the cube `[lo, hi]³`, each corner
/// up to `size` away from the centre along every axis.
#[derive(Clone, Copy, Debug)]
pub struct Soup {
    pub lo: f32,
    pub hi: f32,
    pub size: f32,
    /// Every `n`-th triangle is this many times larger: long thin triangles across many cells.
    pub long: Option<(usize, f32)>,
    /// Every `n`-th triangle is degenerate: three collinear corners (zero area).
    pub collinear_every: Option<usize>,
}

impl Soup {
    /// Triangles in `[-1, 1]³` of corner spread `size`, none long or degenerate.
    pub fn unit(size: f32) -> Soup {
        Soup {
            lo: -1.0,
            hi: 1.0,
            size,
            long: None,
            collinear_every: None,
        }
    }

    pub fn triangles(&self, n: usize, seed: u64) -> Vec<Triangle> {
        let mut rng = SplitMix64::new(seed);
        (0..n)
            .map(|i| {
                let c = rng.vec3(self.lo, self.hi);
                let size = match self.long {
                    Some((every, factor)) if i % every == 0 => self.size * factor,
                    _ => self.size,
                };
                let d = rng.vec3(-size, size);
                match self.collinear_every {
                    Some(every) if i % every == 0 => Triangle::new(c, c + d, c + 2.0 * d),
                    _ => Triangle::new(c + d, c + rng.vec3(-size, size), c + rng.vec3(-size, size)),
                }
            })
            .collect()
    }
}

/// `small` with 40 long diagonal slivers laid across the box [0, 10]³: their boxes cover the whole
/// scene, so every object split leaves heavily overlapping children (where spatial splits pay).
pub fn with_slivers(mut small: Vec<Triangle>) -> Vec<Triangle> {
    for i in 0..40 {
        let o = Vec3::new(0.0, i as f32 * 0.25, 0.0);
        small.push(Triangle::new(
            o,
            o + Vec3::new(10.0, 0.0, 10.0),
            o + Vec3::new(10.0, 0.1, 10.0),
        ));
    }
    small
}

/// Whether `got` is `want`, or an exact tie: the same distance, and the ray's watertight test
/// really hits `got`'s triangle at that distance (two triangles meeting at an edge).
pub fn same_or_tie(triangles: &[Triangle], ray: &Ray, got: &Hit, want: &Hit) -> bool {
    same_or_tie_with::<Robust>(triangles, ray, got, want)
}

/// `same_or_tie` for answers of the triangle test `R` (`robust = false`: Möller–Trumbore).
pub fn same_or_tie_with<R: RayTests>(
    triangles: &[Triangle],
    ray: &Ray,
    got: &Hit,
    want: &Hit,
) -> bool {
    let test = R::triangle_ray(ray.origin, ray.dir);
    got == want
        || got.is_hit()
            && want.is_hit()
            && got.t == want.t
            && R::intersect(&test, &triangles[got.prim as usize], ray.tmin, ray.tmax).map(|h| h.0)
                == Some(got.t)
}

/// Origins and directions for box tests that must equal `RayBoxTest` bit for bit on boxes near
/// the unit cube: zero and −0.0 direction components, origins on slab planes, inside and behind.
pub fn awkward_slab_rays() -> ([Vec3; 5], [Vec3; 7]) {
    let origins = [
        Vec3::new(0.5, 0.5, -1.0),
        Vec3::new(0.0, 0.5, -1.0),
        Vec3::new(1.0, 0.0, 0.5),
        Vec3::splat(0.3),
        Vec3::new(4.0, 0.5, 0.5),
    ];
    let dirs = [
        Vec3::Z,
        Vec3::new(0.0, -0.0, 1.0),
        Vec3::new(-0.0, 0.0, -1.0),
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(-1.0, -0.0, 0.0),
        Vec3::new(0.3, -0.2, 0.9),
        Vec3::new(-0.7, 0.1, 0.0),
    ];
    (origins, dirs)
}

/// A batch's rays, field by field (kind, the f32 columns and times, pixels, packet starts): what
/// two ways of making the same batch must agree on.
pub fn batch_fields(b: &RayBatch) -> (Option<RayKind>, [Vec<f32>; 9], Vec<u32>, Vec<bool>) {
    let f = [
        &b.ox, &b.oy, &b.oz, &b.dx, &b.dy, &b.dz, &b.tmin, &b.tmax, &b.time,
    ];
    (
        b.kind,
        f.map(|v| v.clone()),
        b.pixel.clone(),
        b.packet_start.clone(),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn soups_are_seeded_bounded_and_have_their_slivers() {
        let soup = Soup {
            lo: 0.0,
            hi: 10.0,
            size: 0.5,
            long: Some((10, 4.0)),
            collinear_every: Some(5),
        };
        let a = soup.triangles(100, 7);
        assert_eq!(a, soup.triangles(100, 7));
        assert_ne!(a, soup.triangles(100, 8));
        for (i, t) in a.iter().enumerate() {
            let reach = if i % 10 == 0 {
                2.0 * 4.0 * 0.5
            } else {
                2.0 * 0.5
            };
            let b = t.bounds();
            assert!(b.min.min_element() >= -reach && b.max.max_element() <= 10.0 + reach);
            // Collinear up to rounding: the cross product of the edges all but vanishes.
            let sliver = t.normal().length() < 1e-4;
            assert_eq!(sliver, i % 5 == 0, "triangle {i}: {t:?}");
        }
    }
}
