//! Axis-aligned boxes and the conservative ray–box slab test (Ize 2013, "Robust BVH Ray Traversal").

use glam::Vec3;

use super::robustness::{RayTests, Robust};

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    pub min: Vec3,
    pub max: Vec3,
}

impl Default for Aabb {
    fn default() -> Self {
        Aabb::EMPTY
    }
}

impl Aabb {
    /// The empty box: growing it by anything gives that thing.
    pub const EMPTY: Aabb = Aabb {
        min: Vec3::splat(f32::INFINITY),
        max: Vec3::splat(f32::NEG_INFINITY),
    };

    pub fn new(min: Vec3, max: Vec3) -> Self {
        Aabb { min, max }
    }

    pub fn from_points(points: &[Vec3]) -> Self {
        points.iter().fold(Aabb::EMPTY, |b, &p| b.grow(p))
    }

    pub fn grow(self, p: Vec3) -> Self {
        Aabb {
            min: self.min.min(p),
            max: self.max.max(p),
        }
    }

    pub fn union(self, other: Aabb) -> Self {
        Aabb {
            min: self.min.min(other.min),
            max: self.max.max(other.max),
        }
    }

    pub fn is_empty(&self) -> bool {
        self.min.x > self.max.x || self.min.y > self.max.y || self.min.z > self.max.z
    }

    pub fn extent(&self) -> Vec3 {
        self.max - self.min
    }

    pub fn center(&self) -> Vec3 {
        (self.min + self.max) * 0.5
    }

    /// Surface area; 0 for the empty box (the SAH cost of an empty side).
    pub fn surface_area(&self) -> f32 {
        if self.is_empty() {
            return 0.0;
        }
        let e = self.extent();
        2.0 * (e.x * e.y + e.y * e.z + e.z * e.x)
    }

    pub fn largest_axis(&self) -> usize {
        let e = self.extent();
        if e.x >= e.y && e.x >= e.z {
            0
        } else if e.y >= e.z {
            1
        } else {
            2
        }
    }

    pub fn contains_point(&self, p: Vec3) -> bool {
        p.cmpge(self.min).all() && p.cmple(self.max).all()
    }

    pub fn contains(&self, other: &Aabb) -> bool {
        other.is_empty() || (self.contains_point(other.min) && self.contains_point(other.max))
    }
}

/// `1 + 2γ(3)`, γ(n) = nε/(1 − nε) with ε = 2⁻²⁴: scaling the far slab distance by it makes the
/// slab test conservative under f32 rounding (Ize 2013, §3; pbrt-v4 `Bounds3::IntersectP`). The
/// scale is applied to the ray's reciprocal direction, once per ray (`(plane − o)·(inv·scale)`,
/// as Embree's robust `rdir_far`), rather than to every far distance (`(plane − o)·inv·scale`):
/// both put the same four roundings (reciprocal, difference, two products) between the exact
/// distance times the scale and the computed one, so Ize's bound covers both, and the per-ray
/// form takes a multiplication off every box test's dependent chain.
pub const FAR_SCALE: f32 =
    1.0 + 2.0 * (3.0 * (f32::EPSILON * 0.5) / (1.0 - 3.0 * (f32::EPSILON * 0.5)));

/// A ray prepared for many box tests: reciprocal direction and which box corner is near per axis.
///
/// Zero and −0.0 direction components give ±∞ reciprocals; the near/far corner is chosen by the
/// sign *bit* so −0.0 behaves as a negative direction. An origin exactly on a slab plane with a
/// zero component makes `0 · ∞ = NaN`; `f32::max`/`f32::min` ignore NaN, so that axis does not
/// restrict the interval — the conservative answer (the ray lies in the box's face plane).
#[derive(Clone, Copy, Debug)]
pub struct RayBoxTest {
    pub origin: Vec3,
    pub inv_dir: Vec3,
    pub neg: [bool; 3],
}

impl RayBoxTest {
    #[inline(always)]
    pub fn new(origin: Vec3, dir: Vec3) -> Self {
        RayBoxTest {
            origin,
            inv_dir: Vec3::ONE / dir,
            neg: [
                dir.x.is_sign_negative(),
                dir.y.is_sign_negative(),
                dir.z.is_sign_negative(),
            ],
        }
    }

    /// Entry distance of the ray into `b` clipped to `[tmin, tmax]`, or `None` when it misses:
    /// the conservative test (`hit_with::<Robust>`).
    #[inline(always)]
    pub fn hit(&self, b: &Aabb, tmin: f32, tmax: f32) -> Option<f32> {
        self.hit_with::<Robust>(b, tmin, tmax)
    }

    /// `hit` with the far distances taken by the reciprocal direction scaled by `R::FAR_SCALE`
    /// (`FAR_SCALE`'s doc): conservative (`Robust`) or plain (`Fast`, `robust = false`).
    #[inline(always)]
    pub fn hit_with<R: RayTests>(&self, b: &Aabb, tmin: f32, tmax: f32) -> Option<f32> {
        let (nx, fx) = if self.neg[0] {
            (b.max.x, b.min.x)
        } else {
            (b.min.x, b.max.x)
        };
        let (ny, fy) = if self.neg[1] {
            (b.max.y, b.min.y)
        } else {
            (b.min.y, b.max.y)
        };
        let (nz, fz) = if self.neg[2] {
            (b.max.z, b.min.z)
        } else {
            (b.min.z, b.max.z)
        };
        let o = self.origin;
        let i = self.inv_dir;
        let f = i * R::FAR_SCALE;
        let enter = tmin
            .max((nx - o.x) * i.x)
            .max((ny - o.y) * i.y)
            .max((nz - o.z) * i.z);
        let exit = tmax
            .min((fx - o.x) * f.x)
            .min((fy - o.y) * f.y)
            .min((fz - o.z) * f.z);
        (enter <= exit).then_some(enter)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit() -> Aabb {
        Aabb::new(Vec3::ZERO, Vec3::ONE)
    }

    fn hit(o: Vec3, d: Vec3) -> Option<f32> {
        RayBoxTest::new(o, d).hit(&unit(), 0.0, f32::INFINITY)
    }

    #[test]
    fn axis_parallel_rays_hit_inside_and_miss_outside() {
        assert_eq!(hit(Vec3::new(0.5, 0.5, -1.0), Vec3::Z), Some(1.0));
        assert_eq!(hit(Vec3::new(1.5, 0.5, -1.0), Vec3::Z), None);
        assert_eq!(hit(Vec3::new(0.5, -0.5, -1.0), Vec3::Z), None);
        assert_eq!(hit(Vec3::new(0.5, 0.5, 2.0), -Vec3::Z), Some(1.0));
    }

    #[test]
    fn negative_zero_components_behave_like_zero() {
        for d in [
            Vec3::new(0.0, -0.0, 1.0),
            Vec3::new(-0.0, 0.0, 1.0),
            Vec3::new(-0.0, -0.0, 1.0),
        ] {
            assert_eq!(hit(Vec3::new(0.5, 0.5, -1.0), d), Some(1.0), "dir {d:?}");
            assert_eq!(hit(Vec3::new(1.5, 0.5, -1.0), d), None, "dir {d:?}");
        }
        // −0.0 in the travel axis: a ray pointing down −x with zero y/z.
        assert_eq!(
            hit(Vec3::new(2.0, 0.5, 0.5), Vec3::new(-1.0, -0.0, 0.0)),
            Some(1.0)
        );
    }

    #[test]
    fn origin_on_slab_plane_with_zero_component_is_conservative() {
        // The ray runs inside the box's y = 0 face plane: it must not be culled, whatever the sign of zero.
        for d in [Vec3::new(0.0, 0.0, 1.0), Vec3::new(0.0, -0.0, 1.0)] {
            assert_eq!(
                hit(Vec3::new(0.5, 0.0, -1.0), d),
                Some(1.0),
                "min plane, dir {d:?}"
            );
            assert_eq!(
                hit(Vec3::new(0.5, 1.0, -1.0), d),
                Some(1.0),
                "max plane, dir {d:?}"
            );
        }
    }

    #[test]
    fn origin_inside_enters_at_tmin_and_interval_is_clipped() {
        assert_eq!(hit(Vec3::splat(0.5), Vec3::new(0.3, -0.2, 0.9)), Some(0.0));
        let t = RayBoxTest::new(Vec3::new(0.5, 0.5, -1.0), Vec3::Z);
        assert_eq!(t.hit(&unit(), 0.0, 0.5), None, "box beyond tmax");
        assert_eq!(t.hit(&unit(), 3.0, 10.0), None, "box before tmin");
    }

    #[test]
    fn grazing_far_corner_is_kept_by_the_far_scale() {
        // Diagonal ray through the exact corner (1,1,1): rounding must not drop it.
        let d = Vec3::new(1.0, 1.0, 1.0).normalize();
        assert!(hit(Vec3::new(1.0, 1.0, 1.0) - d * 3.0, d).is_some());
    }

    #[test]
    fn union_and_contains() {
        let a = Aabb::new(Vec3::ZERO, Vec3::ONE);
        let b = Aabb::new(Vec3::splat(2.0), Vec3::splat(3.0));
        let u = a.union(b);
        assert!(u.contains(&a) && u.contains(&b));
        assert!(!a.contains(&b));
        assert_eq!(Aabb::EMPTY.surface_area(), 0.0);
        assert_eq!(a.surface_area(), 6.0);
    }
}
