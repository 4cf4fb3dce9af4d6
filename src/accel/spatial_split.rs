//! Spatial splits for the SAH builder (Stich, Friedrich and Dietrich 2009, "Spatial Splits in
//! Bounding Volume Hierarchies", the SBVH). At a node whose best object split leaves children that
//! overlap much (overlap area over the root's area above α, §4.5), the builder also tries planes
//! that cut the node's box into two disjoint halves: a triangle reference straddling the plane is
//! split into one reference per side, each with the box of the part of the triangle on that side
//! (§4.2). The cost of every candidate plane comes from chopped binning (§4.3): each reference is
//! cut at every bin plane it crosses and each piece's box grows its bin; entry and exit counts give
//! the references on each side. Reference unsplitting (§4.4) then puts a straddling reference
//! wholly on one side when that is cheaper than duplicating it.
//!
//! The builder keeps the split with the lowest SAH cost among the object split, the spatial split
//! and a leaf, so the tree's SAH cost with spatial splits is never above the plain one at a node.

use super::presplit::{plane_crossing, widened_within, Reference};
use crate::geometry::{Aabb, Triangle};

/// A spatial split candidate: references whose box ends at or below `plane` on `axis` go left,
/// those starting at or above it go right, the others are split at it (or unsplit, §4.4).
#[derive(Clone, Copy, Debug)]
pub struct SpatialSplit {
    pub axis: usize,
    pub plane: f32,
    /// SAH cost in the builder's units: 1 + (A_L·price(N_L) + A_R·price(N_R)) / A_parent.
    pub cost: f32,
    /// Box of the left side's pieces and its reference count (straddling ones counted on both).
    pub left: Aabb,
    pub left_count: usize,
    pub right: Aabb,
    pub right_count: usize,
}

#[derive(Clone, Copy)]
struct SpatialBin {
    bounds: Aabb,
    /// References whose leftmost piece is in this bin.
    entries: u32,
    /// References whose rightmost piece is in this bin.
    exits: u32,
}

const EMPTY_BIN: SpatialBin = SpatialBin {
    bounds: Aabb::EMPTY,
    entries: 0,
    exits: 0,
};

/// The boxes of the parts of `tri` on either side of `plane` on `axis`, within the reference box
/// `bounds` (Stich et al. §4.2: each vertex goes to its side, each edge crossing the plane adds its
/// crossing point to both). Each box is the piece's box widened by a few ULPs (rounding of the
/// crossing points must not open a gap) and kept within `bounds`; empty when no part of the
/// triangle lies on that side.
pub fn split_reference(tri: &Triangle, bounds: &Aabb, axis: usize, plane: f32) -> (Aabb, Aabb) {
    let (mut left, mut right) = (Aabb::EMPTY, Aabb::EMPTY);
    for k in 0..3 {
        let (a, b) = (tri.v[k], tri.v[(k + 1) % 3]);
        if a[axis] <= plane {
            left = left.grow(a);
        }
        if a[axis] >= plane {
            right = right.grow(a);
        }
        if (a[axis] < plane && b[axis] > plane) || (b[axis] < plane && a[axis] > plane) {
            let p = plane_crossing(a, b, axis, plane);
            left = left.grow(p);
            right = right.grow(p);
        }
    }
    let clip = |piece: Aabb| {
        if piece.is_empty() {
            return Aabb::EMPTY;
        }
        let b = widened_within(piece, bounds);
        if b.is_empty() {
            Aabb::EMPTY
        } else {
            b
        }
    };
    (clip(left), clip(right))
}

/// The `bins − 1` interior planes of `bounds` on `axis`, evenly spaced.
fn planes(bounds: &Aabb, axis: usize, bins: usize) -> Vec<f32> {
    let (lo, extent) = (bounds.min[axis], bounds.extent()[axis]);
    (1..bins)
        .map(|k| lo + extent * k as f32 / bins as f32)
        .collect()
}

/// The first and last bin a reference spanning `[min, max]` on the axis has a piece in: bin `j`
/// lies between interior planes `j − 1` and `j`. Counted against the very planes the split
/// compares with, so binning and partitioning agree: the reference is left of plane `k` exactly
/// when its last bin is below `k` (`max ≤ plane`), right when its first bin is `k` or above.
fn bin_range(min: f32, max: f32, planes: &[f32]) -> (usize, usize) {
    let first = planes.partition_point(|&p| p <= min);
    let last = planes.partition_point(|&p| p < max).max(first);
    (first, last)
}

/// The cheapest spatial split of `refs` (the references of a node with box `bounds`), over
/// `bins` bins per axis, or `None` when no plane leaves references on both sides or every plane
/// keeps all of them on both sides (no progress).
pub fn best_spatial_split(
    refs: &[Reference],
    triangles: &[Triangle],
    bounds: &Aabb,
    bins: usize,
    price: impl Fn(usize) -> f32,
) -> Option<SpatialSplit> {
    let parent_area = bounds.surface_area().max(f32::MIN_POSITIVE);
    let n = refs.len();
    let mut best: Option<SpatialSplit> = None;
    let mut table = vec![EMPTY_BIN; bins];
    let mut right_bounds = vec![Aabb::EMPTY; bins];
    let mut right_count = vec![0usize; bins];
    for axis in (0..3).filter(|&a| bounds.extent()[a] > 0.0) {
        let planes = planes(bounds, axis, bins);
        table.fill(EMPTY_BIN);
        for r in refs {
            let tri = &triangles[r.prim as usize];
            let (first, last) = bin_range(r.bounds.min[axis], r.bounds.max[axis], &planes);
            table[first].entries += 1;
            table[last].exits += 1;
            // Chopped binning (§4.3): cut the reference at each plane it crosses.
            let mut rest = r.bounds;
            for (j, &plane) in planes.iter().enumerate().take(last).skip(first) {
                let (piece, remainder) = split_reference(tri, &rest, axis, plane);
                table[j].bounds = table[j].bounds.union(piece);
                rest = remainder;
            }
            table[last].bounds = table[last].bounds.union(rest);
        }
        // Plane k (between bins k−1 and k): left = bins < k, counted by entries; right = bins ≥ k,
        // counted by exits.
        let (mut acc, mut cnt) = (Aabb::EMPTY, 0);
        for k in (1..bins).rev() {
            acc = acc.union(table[k].bounds);
            cnt += table[k].exits as usize;
            right_bounds[k] = acc;
            right_count[k] = cnt;
        }
        let (mut acc, mut cnt) = (Aabb::EMPTY, 0);
        for k in 1..bins {
            acc = acc.union(table[k - 1].bounds);
            cnt += table[k - 1].entries as usize;
            let (rc, rb) = (right_count[k], right_bounds[k]);
            if cnt == 0 || rc == 0 || (cnt == n && rc == n) {
                continue;
            }
            let cost = 1.0
                + (acc.surface_area() * price(cnt) + rb.surface_area() * price(rc)) / parent_area;
            if best.as_ref().is_none_or(|b| cost < b.cost) {
                best = Some(SpatialSplit {
                    axis,
                    plane: planes[k - 1],
                    cost,
                    left: acc,
                    left_count: cnt,
                    right: rb,
                    right_count: rc,
                });
            }
        }
    }
    best
}

/// Distributes `refs` over the two sides of `split`, splitting the references that straddle its
/// plane unless putting one wholly on a side costs less (reference unsplitting, §4.4: compare
/// A_L·N_L + A_R·N_R with the areas and counts after moving it).
pub fn apply_spatial_split(
    refs: Vec<Reference>,
    triangles: &[Triangle],
    split: &SpatialSplit,
) -> (Vec<Reference>, Vec<Reference>) {
    let (axis, plane) = (split.axis, split.plane);
    let (mut left, mut right) = (Vec::new(), Vec::new());
    let mut straddling = Vec::new();
    for r in refs {
        if r.bounds.max[axis] <= plane {
            left.push(r);
        } else if r.bounds.min[axis] >= plane {
            right.push(r);
        } else {
            straddling.push(r);
        }
    }
    let (mut left_box, mut right_box) = (split.left, split.right);
    let (mut nl, mut nr) = (split.left_count as f32, split.right_count as f32);
    for r in straddling {
        let (l, rr) = split_reference(&triangles[r.prim as usize], &r.bounds, axis, plane);
        let duplicate = left_box.surface_area() * nl + right_box.surface_area() * nr;
        let all_left =
            left_box.union(r.bounds).surface_area() * nl + right_box.surface_area() * (nr - 1.0);
        let all_right =
            left_box.surface_area() * (nl - 1.0) + right_box.union(r.bounds).surface_area() * nr;
        if l.is_empty() || (all_right < duplicate && all_right <= all_left && !rr.is_empty()) {
            right_box = right_box.union(r.bounds);
            nl -= 1.0;
            right.push(r);
        } else if rr.is_empty() || all_left < duplicate {
            left_box = left_box.union(r.bounds);
            nr -= 1.0;
            left.push(r);
        } else {
            left.push(Reference {
                bounds: l,
                prim: r.prim,
            });
            right.push(Reference {
                bounds: rr,
                prim: r.prim,
            });
        }
    }
    (left, right)
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;

    #[test]
    fn a_reference_splits_into_the_boxes_of_its_two_parts() {
        // Right triangle (0,0,0), (4,0,0), (0,4,0) cut at x = 1: left part x ∈ [0, 1], y ∈ [0, 4];
        // right part x ∈ [1, 4], y ∈ [0, 3] (the hypotenuse at x = 1 is y = 3).
        let tri = Triangle::new(
            Vec3::ZERO,
            Vec3::new(4.0, 0.0, 0.0),
            Vec3::new(0.0, 4.0, 0.0),
        );
        let (l, r) = split_reference(&tri, &tri.bounds(), 0, 1.0);
        let near = |a: Vec3, b: Vec3| (a - b).abs().max_element() < 1e-5;
        assert!(
            near(l.min, Vec3::ZERO) && near(l.max, Vec3::new(1.0, 4.0, 0.0)),
            "{l:?}"
        );
        assert!(
            near(r.min, Vec3::new(1.0, 0.0, 0.0)) && near(r.max, Vec3::new(4.0, 3.0, 0.0)),
            "{r:?}"
        );
        // Within a smaller reference box, the pieces stay inside it.
        let region = Aabb::new(Vec3::new(0.5, 0.0, 0.0), Vec3::new(3.0, 2.0, 0.0));
        let (l, r) = split_reference(&tri, &region, 0, 1.0);
        assert!(region.contains(&l) && region.contains(&r));
        // A plane beside the triangle leaves one side empty.
        let (l, r) = split_reference(&tri, &tri.bounds(), 0, 5.0);
        assert!(r.is_empty() && l == tri.bounds());
    }

    #[test]
    fn bin_ranges_agree_with_the_plane_comparisons() {
        let planes = [1.0, 2.0, 3.0];
        assert_eq!(bin_range(0.0, 0.5, &planes), (0, 0));
        // Ending exactly on plane 0 (x = 1): entirely left of it, last bin 0.
        assert_eq!(bin_range(0.0, 1.0, &planes), (0, 0));
        // Starting exactly on it: entirely right, first bin 1.
        assert_eq!(bin_range(1.0, 2.5, &planes), (1, 2));
        assert_eq!(bin_range(0.5, 3.5, &planes), (0, 3));
        // A flat reference on a plane: one bin.
        assert_eq!(bin_range(2.0, 2.0, &planes), (2, 2));
    }

    #[test]
    fn straddling_slivers_are_split_and_counted_on_both_sides() {
        // In z = 0: two slivers along x ∈ [0, 8] (y within [0, 0.6]) and two small triangles at
        // either end. Any x plane between the small ones costs the same, 3 references a side
        // (both slivers cut, one small each), and beats every y plane, which the small triangles
        // and slivers all straddle. Keeping a sliver whole on one side costs more (§4.4).
        let sliver = |y: f32| {
            Triangle::new(
                Vec3::new(0.0, y, 0.0),
                Vec3::new(8.0, 0.5, 0.0),
                Vec3::new(8.0, 0.6, 0.0),
            )
        };
        let small = |x: f32| {
            Triangle::new(
                Vec3::new(x, 0.0, 0.0),
                Vec3::new(x + 0.5, 0.0, 0.0),
                Vec3::new(x, 0.5, 0.0),
            )
        };
        let tris = vec![sliver(0.0), sliver(0.1), small(0.0), small(7.5)];
        let refs: Vec<Reference> = tris
            .iter()
            .enumerate()
            .map(|(i, t)| Reference {
                bounds: t.bounds(),
                prim: i as u32,
            })
            .collect();
        let bounds = refs.iter().fold(Aabb::EMPTY, |b, r| b.union(r.bounds));
        let split =
            best_spatial_split(&refs, &tris, &bounds, 16, |n| n as f32).expect("a spatial split");
        assert_eq!(split.axis, 0, "{split:?}");
        assert_eq!((split.left_count, split.right_count), (3, 3), "{split:?}");
        assert!((0.5..=7.5).contains(&split.plane), "{split:?}");
        let (left, right) = apply_spatial_split(refs, &tris, &split);
        let prims = |side: &[Reference]| {
            let mut p: Vec<u32> = side.iter().map(|r| r.prim).collect();
            p.sort_unstable();
            p
        };
        assert_eq!(prims(&left), [0, 1, 2]);
        assert_eq!(prims(&right), [0, 1, 3]);
        for r in &left {
            assert!(r.bounds.max.x <= split.plane + 1e-5, "{r:?}");
        }
        for r in &right {
            assert!(r.bounds.min.x >= split.plane - 1e-5, "{r:?}");
        }
    }
}
