//! Early split clipping (Ernst & Greiner 2007, "Early Split Clipping for Bounding Volume
//! Hierarchies"): before the SAH build, triangles whose boxes are large are cut into pieces by
//! axis-aligned planes, and each piece gets the box of the part of the triangle inside it. Long
//! diagonal slivers (the cylinders of SPD rings, thin architectural strips) otherwise have boxes
//! that are mostly empty space and overlap everything around them. A triangle may then be
//! referenced by several leaves; hits are unaffected (each copy is the same triangle).

use glam::Vec3;

use crate::geometry::{Aabb, Triangle};

/// One box of (part of) one triangle: what the SAH builder sorts.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Reference {
    pub bounds: Aabb,
    pub prim: u32,
}

/// At most 2^MAX_LEVELS pieces per triangle.
const MAX_LEVELS: u32 = 4;

/// A box surface area at most this many times the triangle's area is tight enough: an
/// axis-aligned right triangle's flat box has exactly 4× its area, ordinary facets of curved
/// meshes a small multiple of it; splitting those only adds nodes. Slivers exceed it by far.
const TIGHT_RATIO: f32 = 32.0;

/// References for `triangles`, with at most `budget · N` extra pieces spent on the triangles
/// whose boxes waste the most surface area (box area beyond `TIGHT_RATIO` × triangle area); a
/// global waste threshold, found by bisection, decides how many times each triangle is halved.
pub fn split_references(triangles: &[Triangle], budget: f32) -> Vec<Reference> {
    let boxes: Vec<Aabb> = triangles.iter().map(Triangle::bounds).collect();
    let areas: Vec<f32> = boxes
        .iter()
        .zip(triangles)
        .map(|(b, t)| {
            // Zero-area triangles are never hit: pieces of them would only add nodes.
            let area = t.area();
            if area > 0.0 {
                (b.surface_area() - TIGHT_RATIO * area).max(0.0)
            } else {
                0.0
            }
        })
        .collect();
    let extra_allowed = (budget.max(0.0) * triangles.len() as f32) as usize;
    let levels = |area: f32, threshold: f32| -> u32 {
        if area <= threshold || threshold <= 0.0 {
            0
        } else {
            ((area / threshold).log2().ceil() as u32).min(MAX_LEVELS)
        }
    };
    let extra = |threshold: f32| -> usize {
        areas
            .iter()
            .map(|&a| (1usize << levels(a, threshold)) - 1)
            .sum()
    };
    // Smallest threshold whose extra pieces fit the budget (extra() falls as the threshold rises);
    // an infinite threshold splits nothing.
    let largest = areas.iter().copied().fold(0.0, f32::max);
    let threshold = if extra_allowed == 0 || largest <= 0.0 {
        f32::INFINITY
    } else {
        let (mut lo, mut hi) = (0.0f32, largest);
        for _ in 0..40 {
            let mid = 0.5 * (lo + hi);
            if extra(mid) <= extra_allowed {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        hi
    };
    let mut refs = Vec::with_capacity(triangles.len() + extra_allowed);
    for (i, tri) in triangles.iter().enumerate() {
        let pieces = 1u32 << levels(areas[i], threshold);
        split(tri, i as u32, boxes[i], pieces, &boxes[i], &mut refs);
    }
    refs
}

/// Pushes the boxes of `tri ∩ region`, halving `region` along its longest axis while `pieces > 1`.
fn split(
    tri: &Triangle,
    prim: u32,
    region: Aabb,
    pieces: u32,
    whole: &Aabb,
    out: &mut Vec<Reference>,
) {
    let bounds = clipped_bounds(tri, &region, whole);
    if bounds.is_empty() {
        return;
    }
    if pieces <= 1 {
        out.push(Reference { bounds, prim });
        return;
    }
    let axis = bounds.largest_axis();
    let mid = bounds.center()[axis];
    let (mut left, mut right) = (bounds, bounds);
    left.max[axis] = mid;
    right.min[axis] = mid;
    split(tri, prim, left, pieces / 2, whole, out);
    split(tri, prim, right, pieces / 2, whole, out);
}

/// Box of the part of `tri` inside `region` (Sutherland–Hodgman against the region's six planes),
/// widened by a few ULPs so rounding in the clipped vertices cannot open a gap between pieces, and
/// kept inside the triangle's own box `whole`.
fn clipped_bounds(tri: &Triangle, region: &Aabb, whole: &Aabb) -> Aabb {
    let mut poly: Vec<Vec3> = tri.v.to_vec();
    for axis in 0..3 {
        for (plane, keep_below) in [(region.min[axis], false), (region.max[axis], true)] {
            let inside = |p: Vec3| {
                if keep_below {
                    p[axis] <= plane
                } else {
                    p[axis] >= plane
                }
            };
            let mut clipped = Vec::with_capacity(poly.len() + 1);
            for k in 0..poly.len() {
                let (a, b) = (poly[k], poly[(k + 1) % poly.len()]);
                if inside(a) {
                    clipped.push(a);
                }
                if inside(a) != inside(b) {
                    clipped.push(plane_crossing(a, b, axis, plane));
                }
            }
            poly = clipped;
            if poly.is_empty() {
                return Aabb::EMPTY;
            }
        }
    }
    widened_within(Aabb::from_points(&poly), whole)
}

/// Where the edge `a`–`b`, whose ends lie on opposite sides of the plane `axis = plane`, crosses
/// it (on it exactly along `axis`).
pub(super) fn plane_crossing(a: Vec3, b: Vec3, axis: usize, plane: f32) -> Vec3 {
    let s = (plane - a[axis]) / (b[axis] - a[axis]);
    let mut p = a + (b - a) * s;
    p[axis] = plane;
    p
}

/// `b` widened by a few ULPs of its largest coordinate, so rounding in computed (clipped) vertices
/// cannot open a gap between the pieces of a triangle, and kept inside `whole`.
pub(super) fn widened_within(b: Aabb, whole: &Aabb) -> Aabb {
    let margin = Vec3::splat(4.0 * f32::EPSILON * b.min.abs().max(b.max.abs()).max_element());
    Aabb::new(
        (b.min - margin).max(whole.min),
        (b.max + margin).min(whole.max),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sliver(i: usize) -> Triangle {
        // Long diagonal slivers: boxes far larger than the triangles.
        let o = Vec3::new(i as f32 * 0.37, (i % 7) as f32, (i % 5) as f32 * 0.5);
        Triangle::new(
            o,
            o + Vec3::new(10.0, 8.0, 6.0),
            o + Vec3::new(10.05, 8.0, 6.0),
        )
    }

    #[test]
    fn budget_caps_the_extra_references() {
        let tris: Vec<Triangle> = (0..1000).map(sliver).collect();
        for budget in [0.0, 0.25, 1.0] {
            let refs = split_references(&tris, budget);
            assert!(refs.len() >= tris.len());
            assert!(
                refs.len() <= tris.len() + (budget * 1000.0) as usize,
                "{budget}: {}",
                refs.len()
            );
        }
        assert_eq!(split_references(&tris, 0.0).len(), 1000);
        assert!(
            split_references(&tris, 1.0).len() > 1500,
            "slivers are worth splitting"
        );
    }

    #[test]
    fn pieces_cover_their_triangle_and_are_tighter() {
        let tris: Vec<Triangle> = (0..50).map(sliver).collect();
        let refs = split_references(&tris, 3.0);
        for (i, tri) in tris.iter().enumerate() {
            let mine: Vec<&Reference> = refs.iter().filter(|r| r.prim == i as u32).collect();
            assert!(mine.len() > 1);
            let area: f32 = mine.iter().map(|r| r.bounds.surface_area()).sum();
            assert!(
                area < tri.bounds().surface_area(),
                "pieces should be tighter in total"
            );
            // Every point of the triangle lies in one of its pieces.
            for a in 0..=20 {
                for b in 0..=(20 - a) {
                    // Clamped: evaluating the point rounds it up to an ULP outside the triangle's box.
                    let whole = tri.bounds();
                    let p = tri
                        .point(a as f32 / 20.0, b as f32 / 20.0)
                        .clamp(whole.min, whole.max);
                    assert!(
                        mine.iter().any(|r| r.bounds.contains_point(p)),
                        "triangle {i}: {p:?} uncovered"
                    );
                }
            }
        }
    }
}
