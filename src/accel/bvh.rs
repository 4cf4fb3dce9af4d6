//! Binary BVH built with binned SAH (Wald 2007, "On fast construction of SAH-based bounding volume
//! hierarchies"). Leaf size and maximum depth are configurable because later work compares deep
//! and shallow trees; every node knows its depth for the per-depth histograms.
//!
//! Layout: the two children of an interior node are adjacent (`first`, `first + 1`), so a
//! traversal step tests both boxes at once. Triangles are copied in leaf order for locality;
//! `prim_ids` maps them back to scene primitive ids.

use std::time::Instant;

use glam::Vec3;

use super::child_pairs::{child_pairs, ChildPair};
use super::presplit::{split_references, Reference};
use crate::error::{Error, Result};
use crate::geometry::{Aabb, Triangle};
use crate::params::Params;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BvhConfig {
    /// A node with at most this many triangles becomes a leaf when SAH says splitting does not pay;
    /// a node with more is always split (unless `max_depth` is reached).
    pub max_leaf_size: usize,
    /// Nodes at this depth become leaves whatever they hold.
    pub max_depth: usize,
    /// SAH bins per axis.
    pub bins: usize,
    /// Early split clipping budget: at most this fraction of extra triangle references
    /// (0 disables it; see `presplit`).
    pub presplit: f32,
}

impl Default for BvhConfig {
    fn default() -> Self {
        BvhConfig {
            max_leaf_size: 4,
            max_depth: 48,
            bins: 16,
            presplit: 0.5,
        }
    }
}

impl BvhConfig {
    /// Deepest tree a traversal stack must hold; `max_depth` is capped to it.
    pub const DEPTH_LIMIT: usize = 62;
    pub const PARAMS: &'static [&'static str] = &["leaf_size", "max_depth", "bins", "presplit"];

    pub fn from_params(p: &Params) -> Result<Self> {
        let d = BvhConfig::default();
        let c = BvhConfig {
            max_leaf_size: p.get_or("leaf_size", d.max_leaf_size)?,
            max_depth: p.get_or("max_depth", d.max_depth)?,
            bins: p.get_or("bins", d.bins)?,
            presplit: p.get_or("presplit", d.presplit)?,
        };
        let presplit_ok = c.presplit.is_finite() && (0.0..=16.0).contains(&c.presplit);
        if c.max_leaf_size == 0 || c.bins < 2 || c.max_depth > Self::DEPTH_LIMIT || !presplit_ok {
            return Err(Error::usage(format!(
                "BVH parameters out of range: leaf_size ≥ 1, bins ≥ 2, max_depth ≤ {}, presplit in [0, 16] (got {c:?})",
                Self::DEPTH_LIMIT
            )));
        }
        Ok(c)
    }
}

/// 32 bytes: a box and either a leaf's triangle range (`count > 0`) or the index of the first child.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(32))]
pub struct BvhNode {
    pub bounds: Aabb,
    pub first: u32,
    pub count: u32,
}

impl BvhNode {
    #[inline(always)]
    pub fn is_leaf(&self) -> bool {
        self.count > 0
    }
}

#[derive(Clone, Debug)]
pub struct Bvh {
    pub nodes: Vec<BvhNode>,
    /// Depth of each node (root 0).
    pub depth: Vec<u8>,
    /// Triangles in leaf order (a presplit triangle appears once per leaf that references it).
    pub triangles: Vec<Triangle>,
    /// Scene primitive id of each entry of `triangles`.
    pub prim_ids: Vec<u32>,
    /// For a moving mesh (motion blur, `build_moving`): each entry of `triangles` at shutter
    /// close, `triangles` being it at shutter open; a ray at time τ meets the triangle linearly
    /// in between. `None` for static geometry.
    pub motion_end: Option<Vec<Triangle>>,
    /// Both children's boxes of every interior node, for SIMD single-ray traversal.
    pub pairs: Vec<ChildPair>,
    pub config: BvhConfig,
    pub build_seconds: f64,
}

#[derive(Clone, Copy)]
struct Bin {
    bounds: Aabb,
    count: u32,
}

const EMPTY_BIN: Bin = Bin {
    bounds: Aabb::EMPTY,
    count: 0,
};

struct Split {
    axis: usize,
    /// Primitives with bin index < `bin` go left.
    bin: usize,
    cost: f32,
}

impl Bvh {
    pub const ROOT: usize = 0;

    pub fn build(triangles: &[Triangle], config: BvhConfig) -> Bvh {
        let start = Instant::now();
        let refs = split_references(triangles, config.presplit);
        Self::build_over(&refs, triangles, None, config, start)
    }

    /// The tree over a mesh moving linearly from `open` to `close` (same count and order) during
    /// the shutter interval: each triangle's box is the union of its boxes at both ends, which
    /// holds it at every time in between (a box of linearly moving points is bounded by their
    /// end boxes). No early split clipping: a piece clipped at one end is not that piece later.
    pub fn build_moving(open: &[Triangle], close: &[Triangle], config: BvhConfig) -> Bvh {
        assert_eq!(open.len(), close.len(), "both ends of a moving mesh");
        let start = Instant::now();
        let refs: Vec<Reference> = open
            .iter()
            .zip(close)
            .enumerate()
            .map(|(i, (a, b))| Reference {
                bounds: a.bounds().union(b.bounds()),
                prim: i as u32,
            })
            .collect();
        Self::build_over(&refs, open, Some(close), config, start)
    }

    fn build_over(
        refs: &[Reference],
        triangles: &[Triangle],
        close: Option<&[Triangle]>,
        config: BvhConfig,
        start: Instant,
    ) -> Bvh {
        let n = refs.len();
        let boxes: Vec<Aabb> = refs.iter().map(|r| r.bounds).collect();
        let centroids: Vec<Vec3> = boxes.iter().map(Aabb::center).collect();
        let mut order: Vec<u32> = (0..n as u32).collect();
        let mut nodes = Vec::with_capacity((2 * n).max(1));
        let mut depth = Vec::with_capacity((2 * n).max(1));
        nodes.push(BvhNode {
            bounds: boxes.iter().fold(Aabb::EMPTY, |b, x| b.union(*x)),
            first: 0,
            count: n as u32,
        });
        depth.push(0u8);

        // Work list of nodes still to split, each owning order[first .. first + count].
        let mut pending = if n > 0 { vec![0usize] } else { vec![] };
        let mut bins = vec![[EMPTY_BIN; 3]; config.bins];
        while let Some(index) = pending.pop() {
            let node = nodes[index];
            let (first, count) = (node.first as usize, node.count as usize);
            let range = &mut order[first..first + count];
            let node_depth = depth[index] as usize;
            if count == 1 || node_depth >= config.max_depth.min(BvhConfig::DEPTH_LIMIT) {
                continue;
            }
            let centre_bounds = range
                .iter()
                .fold(Aabb::EMPTY, |b, &i| b.grow(centroids[i as usize]));
            let split = best_split(range, &boxes, &centroids, &centre_bounds, &mut bins);
            let leaf_cost = count as f32;
            let mid = match split {
                Some(s) if count > config.max_leaf_size || s.cost < leaf_cost => {
                    let (lo, extent) = (centre_bounds.min[s.axis], centre_bounds.extent()[s.axis]);
                    let nb = config.bins;
                    partition(range, |i| {
                        bin_of(centroids[i as usize][s.axis], lo, extent, nb) < s.bin
                    })
                }
                // All centroids coincide: SAH cannot separate them; split by count if we must.
                None if count > config.max_leaf_size => count / 2,
                _ => continue,
            };
            let child = nodes.len();
            for (offset, len) in [(0, mid), (mid, count - mid)] {
                let sub = &order[first + offset..first + offset + len];
                nodes.push(BvhNode {
                    bounds: sub
                        .iter()
                        .fold(Aabb::EMPTY, |b, &i| b.union(boxes[i as usize])),
                    first: (first + offset) as u32,
                    count: len as u32,
                });
                depth.push((node_depth + 1) as u8);
            }
            nodes[index].first = child as u32;
            nodes[index].count = 0;
            pending.push(child + 1);
            pending.push(child);
        }

        Bvh {
            triangles: order
                .iter()
                .map(|&i| triangles[refs[i as usize].prim as usize])
                .collect(),
            prim_ids: order.iter().map(|&i| refs[i as usize].prim).collect(),
            motion_end: close.map(|close| {
                order
                    .iter()
                    .map(|&i| close[refs[i as usize].prim as usize])
                    .collect()
            }),
            pairs: child_pairs(&nodes),
            nodes,
            depth,
            config,
            build_seconds: start.elapsed().as_secs_f64(),
        }
    }

    pub fn is_empty(&self) -> bool {
        self.triangles.is_empty()
    }

    pub fn max_depth(&self) -> usize {
        self.depth.iter().copied().max().unwrap_or(0) as usize
    }

    pub fn leaf_count(&self) -> usize {
        self.nodes.iter().filter(|n| n.is_leaf()).count()
    }
}

#[inline(always)]
fn bin_of(c: f32, lo: f32, extent: f32, bins: usize) -> usize {
    (((c - lo) / extent * bins as f32) as usize).min(bins - 1)
}

/// The cheapest SAH plane over all axes and bins, or `None` when every centroid is the same point.
fn best_split(
    range: &[u32],
    boxes: &[Aabb],
    centroids: &[Vec3],
    centre_bounds: &Aabb,
    bins: &mut [[Bin; 3]],
) -> Option<Split> {
    let nb = bins.len();
    let extent = centre_bounds.extent();
    bins.fill([EMPTY_BIN; 3]);
    for &i in range {
        let c = centroids[i as usize];
        for axis in 0..3 {
            if extent[axis] > 0.0 {
                let b = &mut bins[bin_of(c[axis], centre_bounds.min[axis], extent[axis], nb)][axis];
                b.bounds = b.bounds.union(boxes[i as usize]);
                b.count += 1;
            }
        }
    }
    let parent_area = range
        .iter()
        .fold(Aabb::EMPTY, |b, &i| b.union(boxes[i as usize]))
        .surface_area()
        .max(f32::MIN_POSITIVE);
    let mut best: Option<Split> = None;
    let mut right_area = vec![0.0f32; nb];
    let mut right_count = vec![0u32; nb];
    for axis in (0..3).filter(|&a| extent[a] > 0.0) {
        // Sweep from the right to get the cost of every "bins ≥ k go right" side.
        let (mut acc, mut cnt) = (Aabb::EMPTY, 0);
        for k in (1..nb).rev() {
            acc = acc.union(bins[k][axis].bounds);
            cnt += bins[k][axis].count;
            right_area[k] = acc.surface_area();
            right_count[k] = cnt;
        }
        let (mut acc, mut cnt) = (Aabb::EMPTY, 0);
        for k in 1..nb {
            acc = acc.union(bins[k - 1][axis].bounds);
            cnt += bins[k - 1][axis].count;
            if cnt == 0 || right_count[k] == 0 {
                continue;
            }
            // Traversal cost 1, intersection cost 1 per triangle, relative to the parent's area.
            let cost = 1.0
                + (acc.surface_area() * cnt as f32 + right_area[k] * right_count[k] as f32)
                    / parent_area;
            if best.as_ref().is_none_or(|b| cost < b.cost) {
                best = Some(Split { axis, bin: k, cost });
            }
        }
    }
    best
}

/// In-place partition; returns how many elements satisfy `left` (they come first).
fn partition(v: &mut [u32], left: impl Fn(u32) -> bool) -> usize {
    let mut mid = 0;
    for i in 0..v.len() {
        if left(v[i]) {
            v.swap(i, mid);
            mid += 1;
        }
    }
    mid
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid_of_triangles(n: usize) -> Vec<Triangle> {
        let mut tris = Vec::new();
        let mut seed = 7u32;
        let mut rnd = || {
            seed = seed.wrapping_mul(1664525).wrapping_add(1013904223);
            (seed >> 8) as f32 / (1u32 << 24) as f32
        };
        for _ in 0..n {
            let p = Vec3::new(rnd(), rnd(), rnd()) * 10.0;
            let e1 = Vec3::new(rnd(), rnd(), rnd()) * 0.5;
            let e2 = Vec3::new(rnd(), rnd(), rnd()) * 0.5;
            tris.push(Triangle::new(p, p + e1, p + e2));
        }
        tris
    }

    /// Without presplitting: every triangle in exactly one leaf whose box contains it.
    fn check_invariants(tris: &[Triangle], bvh: &Bvh) {
        // Every triangle in exactly one leaf.
        let mut seen = vec![0u32; tris.len()];
        for node in bvh.nodes.iter().filter(|n| n.is_leaf()) {
            for i in node.first..node.first + node.count {
                let id = bvh.prim_ids[i as usize];
                seen[id as usize] += 1;
                assert!(node.bounds.contains(&tris[id as usize].bounds()));
                assert_eq!(bvh.triangles[i as usize], tris[id as usize]);
            }
        }
        assert!(
            seen.iter().all(|&c| c == 1),
            "a triangle is in {:?} leaves",
            seen.iter().find(|&&c| c != 1)
        );
        // Boxes contain their children; depths increase by one.
        for (i, node) in bvh.nodes.iter().enumerate() {
            if !node.is_leaf() {
                for c in [node.first as usize, node.first as usize + 1] {
                    assert!(
                        node.bounds.contains(&bvh.nodes[c].bounds),
                        "node {i} does not contain child {c}"
                    );
                    assert_eq!(bvh.depth[c], bvh.depth[i] + 1);
                }
            }
        }
        assert!(bvh.max_depth() <= bvh.config.max_depth);
    }

    #[test]
    fn every_triangle_in_one_leaf_and_boxes_nest() {
        let tris = grid_of_triangles(5000);
        let unsplit = BvhConfig {
            presplit: 0.0,
            ..BvhConfig::default()
        };
        for config in [
            unsplit,
            BvhConfig {
                max_leaf_size: 1,
                ..unsplit
            },
            BvhConfig {
                max_leaf_size: 16,
                bins: 4,
                ..unsplit
            },
            BvhConfig {
                max_depth: 6,
                ..unsplit
            },
        ] {
            let bvh = Bvh::build(&tris, config);
            check_invariants(&tris, &bvh);
            if config.max_depth > 20 {
                let largest = bvh
                    .nodes
                    .iter()
                    .filter(|n| n.is_leaf())
                    .map(|n| n.count)
                    .max()
                    .unwrap();
                assert!(
                    largest as usize <= config.max_leaf_size,
                    "{config:?}: leaf of {largest}"
                );
            }
        }
    }

    #[test]
    fn presplit_tree_references_every_triangle_within_budget() {
        let tris = grid_of_triangles(3000);
        let bvh = Bvh::build(&tris, BvhConfig::default());
        let mut seen = vec![0u32; tris.len()];
        for node in bvh.nodes.iter().filter(|n| n.is_leaf()) {
            for i in node.first..node.first + node.count {
                let id = bvh.prim_ids[i as usize];
                seen[id as usize] += 1;
                assert_eq!(bvh.triangles[i as usize], tris[id as usize]);
            }
        }
        assert!(seen.iter().all(|&c| c >= 1), "a triangle is in no leaf");
        let refs: u32 = seen.iter().sum();
        assert!(refs as f32 <= 1.5 * tris.len() as f32, "{refs} references");
        assert!(refs > tris.len() as u32, "large triangles were split");
        for (i, node) in bvh.nodes.iter().enumerate().filter(|(_, n)| !n.is_leaf()) {
            for c in [node.first as usize, node.first as usize + 1] {
                assert!(
                    node.bounds.contains(&bvh.nodes[c].bounds),
                    "node {i} does not contain child {c}"
                );
            }
        }
    }

    #[test]
    fn identical_triangles_are_split_by_count() {
        let t = Triangle::new(Vec3::ZERO, Vec3::X, Vec3::Y);
        let tris = vec![t; 100];
        // Equal areas: presplitting all of them would exceed the budget, so none is split.
        let bvh = Bvh::build(&tris, BvhConfig::default());
        check_invariants(&tris, &bvh);
        assert!(bvh
            .nodes
            .iter()
            .filter(|n| n.is_leaf())
            .all(|n| n.count <= 4));
    }

    #[test]
    fn empty_and_single() {
        assert!(Bvh::build(&[], BvhConfig::default()).is_empty());
        let one = [Triangle::new(Vec3::ZERO, Vec3::X, Vec3::Y)];
        let bvh = Bvh::build(&one, BvhConfig::default());
        assert_eq!(bvh.nodes.len(), 1);
        assert!(bvh.nodes[0].is_leaf());
    }
}
