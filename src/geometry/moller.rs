//! The fast, non-watertight ray–triangle test of Möller and Trumbore (1997, "Fast, minimum storage
//! ray/triangle intersection"): the triangle test of `robust = false` (`robustness::Fast`), the
//! role Embree's non-robust mode gives it (`TriangleMIntersector1Moeller`). Plain f32, no f64
//! redo and no tie rule: a ray through a shared edge or vertex may miss every triangle meeting
//! there (the stability suite counts these leaks).

use glam::Vec3;

use super::Triangle;

/// A ray as the Möller–Trumbore test reads it: nothing is precomputed per ray.
#[derive(Clone, Copy, Debug)]
pub struct MollerRay {
    pub origin: Vec3,
    pub dir: Vec3,
}

impl MollerRay {
    #[inline(always)]
    pub fn new(origin: Vec3, dir: Vec3) -> Self {
        MollerRay { origin, dir }
    }

    /// `(t, u, v)` if the ray hits `tri` with `tmin ≤ t ≤ tmax`; both faces count. `u` weights
    /// v1 and `v` weights v2 (Embree's convention, as `WatertightRay::intersect`).
    // The tests are written to fail on NaN (a degenerate triangle's 0/0): a miss.
    #[inline(always)]
    pub fn intersect(&self, tri: &Triangle, tmin: f32, tmax: f32) -> Option<(f32, f32, f32)> {
        let [v0, v1, v2] = tri.v;
        let (e1, e2) = (v1 - v0, v2 - v0);
        // §2: Cramer's rule on [−d, e1, e2] (t, u, v)ᵀ = o − v0, with scalar triple products.
        let p = self.dir.cross(e2);
        let det = e1.dot(p);
        if det == 0.0 {
            return None;
        }
        let inv = 1.0 / det;
        let s = self.origin - v0;
        let u = s.dot(p) * inv;
        if !(0.0..=1.0).contains(&u) {
            return None;
        }
        let q = s.cross(e1);
        let v = self.dir.dot(q) * inv;
        if !(v >= 0.0 && u + v <= 1.0) {
            return None;
        }
        let t = e2.dot(q) * inv;
        (t >= tmin && t <= tmax && t.is_finite()).then_some((t, u, v))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::WatertightRay;
    use crate::random::SplitMix64;

    fn tri() -> Triangle {
        Triangle::new(Vec3::ZERO, Vec3::X, Vec3::Y)
    }

    #[test]
    fn hits_both_faces_inside_and_misses_outside_and_beyond_the_segment() {
        let down = MollerRay::new(Vec3::new(0.25, 0.5, 2.0), -Vec3::Z);
        assert_eq!(
            down.intersect(&tri(), 0.0, f32::INFINITY),
            Some((2.0, 0.25, 0.5))
        );
        let up = MollerRay::new(Vec3::new(0.25, 0.5, -1.0), Vec3::Z);
        assert_eq!(
            up.intersect(&tri(), 0.0, f32::INFINITY),
            Some((1.0, 0.25, 0.5))
        );
        assert_eq!(up.intersect(&tri(), 0.0, 0.5), None, "beyond tmax");
        assert_eq!(up.intersect(&tri(), 1.5, 9.0), None, "before tmin");
        let outside = MollerRay::new(Vec3::new(0.75, 0.5, -1.0), Vec3::Z);
        assert_eq!(outside.intersect(&tri(), 0.0, f32::INFINITY), None);
        let parallel = MollerRay::new(Vec3::new(-1.0, 0.2, 0.0), Vec3::X);
        assert_eq!(parallel.intersect(&tri(), 0.0, f32::INFINITY), None);
        let degenerate = Triangle::new(Vec3::ZERO, Vec3::X, Vec3::X * 2.0);
        assert_eq!(up.intersect(&degenerate, 0.0, f32::INFINITY), None);
    }

    /// Away from edges (where the two tests may round differently) Möller–Trumbore finds the
    /// watertight test's hits, at nearly the same distance and barycentrics.
    #[test]
    fn agrees_with_the_watertight_test_away_from_edges() {
        let mut rng = SplitMix64::new(29);
        let mut hits = 0;
        for _ in 0..5000 {
            let t = Triangle::new(
                rng.vec3(-2.0, 2.0),
                rng.vec3(-2.0, 2.0),
                rng.vec3(-2.0, 2.0),
            );
            let o = rng.vec3(-5.0, 5.0);
            let d = rng.vec3(-2.0, 2.0) - o;
            let fast = MollerRay::new(o, d).intersect(&t, 0.0, f32::INFINITY);
            let exact = WatertightRay::new(o, d).intersect(&t, 0.0, f32::INFINITY);
            let margin = |(_, u, v): (f32, f32, f32)| u.min(v).min(1.0 - u - v);
            match (fast, exact) {
                (Some(f), Some(e)) => {
                    hits += 1;
                    assert!(
                        (f.0 - e.0).abs() <= 1e-4 * e.0.abs().max(1.0),
                        "{f:?} {e:?}"
                    );
                    assert!((f.1 - e.1).abs() < 1e-3 && (f.2 - e.2).abs() < 1e-3);
                }
                (Some(h), None) | (None, Some(h)) => assert!(margin(h) < 1e-4, "{h:?}"),
                (None, None) => {}
            }
        }
        assert!(hits > 300, "{hits}");
    }
}
