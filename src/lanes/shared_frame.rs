//! The watertight frame a whole set of SIMD rays shares: one origin and one axis order
//! `kx, ky, kz` in every lane (camera rays from a pinhole: every SIMD ray of a packet). Then a
//! triangle's vertices relative to the origin, in that order, are the same numbers for every
//! lane of every SIMD ray — the subtractions `p[k] − o[k]` that `SimdRay::intersect` makes per
//! lane and per SIMD ray are made once per triangle (`relative`), and only the shear differs
//! lane by lane (`SimdRay::intersect_relative`). Equality is of the bits, so each lane's
//! coordinates are exactly the ones its own subtraction gives (−0.0 and 0.0 differ there).

use super::SimdRay;
use crate::geometry::Triangle;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SharedFrame {
    origin: [f32; 3],
    axes: [usize; 3],
}

impl SharedFrame {
    /// The frame every lane of every SIMD ray of `groups` has (padding lanes included), if
    /// there is one; `None` for no SIMD rays.
    pub fn of<'a, const L: usize>(
        mut groups: impl Iterator<Item = &'a SimdRay<L>>,
    ) -> Option<Self> {
        let first = groups.next()?;
        let frame = SharedFrame {
            origin: first.origin.map(|o| o[0]),
            axes: first.common_axes?,
        };
        (frame.holds_for(first) && groups.all(|g| frame.holds_for(g))).then_some(frame)
    }

    /// Whether every lane of `group` has this origin (bit for bit) and these axes.
    #[inline(always)]
    fn holds_for<const L: usize>(&self, group: &SimdRay<L>) -> bool {
        let mut differ = 0u32;
        for (lanes, o) in group.origin.iter().zip(self.origin) {
            for &x in lanes {
                differ |= (x.to_bits() != o.to_bits()) as u32;
            }
        }
        differ == 0 && group.common_axes == Some(self.axes)
    }

    /// `tri`'s vertices relative to the origin along `kx, ky, kz`: `[vertex][x, y, z]`, what
    /// `SimdRay::intersect` computes in every lane.
    #[inline(always)]
    pub fn relative(&self, tri: &Triangle) -> [[f32; 3]; 3] {
        let [kx, ky, kz] = self.axes;
        let o = glam::Vec3::from_array(self.origin);
        // Subtracted on every axis, then picked from an array: the same subtractions, where
        // picking `Vec3` components by a run-time index first branched per component (3% of
        // the packet tracer's camera-ray time in a profile).
        let relative = |p: glam::Vec3| {
            let d = (p - o).to_array();
            [d[kx], d[ky], d[kz]]
        };
        [relative(tri.v[0]), relative(tri.v[1]), relative(tri.v[2])]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{Ray, RayBatch, RayKind, Robust};
    use crate::random::SplitMix64;
    use glam::Vec3;

    /// Two SIMD rays of 16 lanes from `origin`, all looking roughly along −z (one frame).
    fn camera_groups(origin: Vec3, rng: &mut SplitMix64) -> Vec<SimdRay<16>> {
        let mut batch = RayBatch::new(RayKind::Primary);
        for _ in 0..32 {
            let d = Vec3::new(rng.range(-0.5, 0.5), rng.range(-0.5, 0.5), -1.0);
            batch.push(Ray::new(origin, d, 0.0, f32::INFINITY), 0);
        }
        (0..2)
            .map(|g| {
                let mut simd = SimdRay::<16>::default();
                simd.load::<Robust>(&batch.view(), g * 16, 16);
                simd
            })
            .collect()
    }

    #[test]
    fn relative_vertices_give_the_per_lane_test_bit_for_bit() {
        let mut rng = SplitMix64::new(5);
        let origin = Vec3::new(0.3, -0.7, 4.0);
        let groups = camera_groups(origin, &mut rng);
        let frame = SharedFrame::of(groups.iter()).expect("one origin, one frame");
        let mut hits = 0;
        for prim in 0..300 {
            let p = rng.vec3(-1.5, 1.5);
            let tri = Triangle::new(p, p + rng.vec3(-1.0, 1.0), p + rng.vec3(-1.0, 1.0));
            let rel = frame.relative(&tri);
            for g in &groups {
                let (mut own, mut shared) = (*g, *g);
                let n = own.intersect::<Robust, false>(&tri, prim);
                assert_eq!(shared.intersect_relative::<false>(&rel, prim), n);
                for l in 0..16 {
                    let (a, b) = (own.hit(l), shared.hit(l));
                    assert_eq!(
                        (a.t.to_bits(), a.prim, a.u.to_bits(), a.v.to_bits()),
                        (b.t.to_bits(), b.prim, b.u.to_bits(), b.v.to_bits())
                    );
                }
                hits += n;
            }
        }
        assert!(hits > 100, "the triangles are hit ({hits} lane hits)");
    }

    #[test]
    fn any_differing_origin_bit_or_axes_means_no_shared_frame() {
        let mut rng = SplitMix64::new(6);
        let groups = camera_groups(Vec3::new(0.0, 1.0, 2.0), &mut rng);
        assert!(SharedFrame::of(groups.iter()).is_some());
        assert_eq!(SharedFrame::of(std::iter::empty::<&SimdRay<16>>()), None);
        // 0.0 and −0.0 compare equal but subtract differently.
        let mut signed_zero = groups.clone();
        signed_zero[1].origin[0][9] = -0.0;
        assert_eq!(SharedFrame::of(signed_zero.iter()), None);
        let mut moved = groups.clone();
        moved[0].origin[2][3] = 2.0000002;
        assert_eq!(SharedFrame::of(moved.iter()), None);
        let mut turned = groups.clone();
        turned[1].common_axes = turned[1].common_axes.map(|[x, y, z]| [y, x, z]);
        assert_eq!(SharedFrame::of(turned.iter()), None);
        turned[1].common_axes = None;
        assert_eq!(SharedFrame::of(turned.iter()), None);
    }
}
