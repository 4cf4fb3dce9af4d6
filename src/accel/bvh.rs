//! Binary BVH built with binned SAH (Wald 2007, "On fast construction of SAH-based bounding volume
//! hierarchies"). Leaf size and maximum depth are configurable because later work compares deep
//! and shallow trees; every node knows its depth for the per-depth histograms. Beyond the papers'
//! plain SAH (`presplit = 0`, `spatial = 0`): early split clipping before the build (`presplit`,
//! off by default) and spatial splits during it (`spatial_split`, the SBVH, on by default: with 32
//! bins it gave the fewest visits of the settings measured, docs/REFERENCE.md); with either, a
//! triangle may be referenced by several leaves, each holding the box of its part only.
//! `sah_cost` measures the result. `builder = "embree"` builds the same layout with Embree's own
//! builder instead (`accel::embree::build_bvh`), to tell tree quality from traversal speed.
//!
//! Layout: the two children of an interior node are adjacent (`first`, `first + 1`), so a
//! traversal step tests both boxes at once. Triangles are copied in leaf order for locality;
//! `prim_ids` maps them back to scene primitive ids.

use std::time::Instant;

use super::child_pairs::{child_pairs, ChildPair};
use super::presplit::{split_references, Reference};
use super::spatial_split::{apply_spatial_split, best_spatial_split};
use crate::error::{Error, Result};
use crate::geometry::{Aabb, Triangle};
use crate::params::Params;

/// Who builds the tree: our binned SAH (with presplit and spatial splits as configured) or Embree's
/// `rtcBuildBVH` (high quality, its SBVH with our triangle splitter); the layout is the same.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BvhBuilder {
    Raylab,
    /// Embree's builder with our leaf policy: leaves priced per triangle, of 1 to `leaf_size`.
    Embree,
    /// Embree's builder with the leaf policy of Embree's own triangle scenes
    /// (`BVH8Triangle4SceneBuilderSAH`): leaves priced per block of 4 triangles and never split
    /// at 4 or fewer (`sahBlockSize 4, minLeafSize 4`), of up to `leaf_size` (28 for Embree's 7
    /// blocks), so that the tree Embree's kernel walks can be walked by ours.
    EmbreeBlocks,
}

impl BvhBuilder {
    pub fn name(self) -> &'static str {
        match self {
            BvhBuilder::Raylab => "raylab",
            BvhBuilder::Embree => "embree",
            BvhBuilder::EmbreeBlocks => "embree-blocks",
        }
    }

    /// Whether Embree's `rtcBuildBVH` builds the tree.
    pub fn is_embree(self) -> bool {
        self != BvhBuilder::Raylab
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BvhConfig {
    pub builder: BvhBuilder,
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
    /// Spatial splits (SBVH, see `spatial_split`): tried at a node when its best object split's
    /// children overlap by more than this fraction of the root's surface area (the paper's α;
    /// 0 disables them).
    pub spatial: f32,
    /// Triangles per leaf block: the SAH prices a leaf's triangles in whole blocks (`leaf_price`)
    /// and never splits a node of this many or fewer, so leaves fill the 4-triangle blocks the
    /// wide single-ray walk tests at once (Embree's `sahBlockSize` and `minLeafSize`). 1: per
    /// triangle, the plain SAH.
    pub leaf_block: usize,
}

impl Default for BvhConfig {
    fn default() -> Self {
        BvhConfig {
            builder: BvhBuilder::Raylab,
            max_leaf_size: 4,
            max_depth: 48,
            bins: 32,
            presplit: 0.0,
            spatial: 1e-5,
            leaf_block: 1,
        }
    }
}

impl BvhConfig {
    /// Deepest tree a traversal stack must hold; `max_depth` is capped to it.
    pub const DEPTH_LIMIT: usize = 62;
    /// More SAH bins than this buy nothing and only cost memory and time.
    pub const BINS_LIMIT: usize = 4096;
    pub const PARAMS: &'static [&'static str] = &[
        "builder",
        "leaf_size",
        "max_depth",
        "bins",
        "presplit",
        "spatial",
        "leaf_block",
    ];
    /// The parameters only our builder reads: setting one with `builder = "embree"` is an error
    /// rather than a silent no-op (Embree bins and splits by its own rules).
    pub const RAYLAB_ONLY: &'static [&'static str] = &["bins", "presplit", "spatial", "leaf_block"];
    /// Embree's `RTC_BUILD_MAX_PRIMITIVES_PER_LEAF`: its builder's largest leaf.
    pub const EMBREE_LEAF_LIMIT: usize = 32;
    /// Triangles per leaf block of Embree's triangle scenes (`Triangle4`): `embree-blocks`
    /// prices leaves in these and never splits this many or fewer.
    pub const EMBREE_BLOCK: usize = 4;

    pub fn from_params(p: &Params) -> Result<Self> {
        let d = BvhConfig::default();
        let builder = match p.0.get("builder").map(String::as_str) {
            None | Some("raylab") => BvhBuilder::Raylab,
            Some("embree") => BvhBuilder::Embree,
            Some("embree-blocks") => BvhBuilder::EmbreeBlocks,
            Some(other) => {
                return Err(Error::usage(format!(
                    "parameter builder = {other:?} is not a BVH builder (raylab, embree or embree-blocks)"
                )))
            }
        };
        if builder.is_embree() {
            if let Some(key) = Self::RAYLAB_ONLY.iter().find(|k| p.0.contains_key(**k)) {
                return Err(Error::usage(format!(
                    "parameter {key} is not used by builder = \"{}\" (Embree's builder bins and \
                     splits by its own rules; it reads leaf_size and max_depth only)",
                    builder.name()
                )));
            }
        }
        let c = BvhConfig {
            builder,
            max_leaf_size: p.get_or("leaf_size", d.max_leaf_size)?,
            max_depth: p.get_or("max_depth", d.max_depth)?,
            bins: p.get_or("bins", d.bins)?,
            presplit: p.get_or("presplit", d.presplit)?,
            spatial: p.get_or("spatial", d.spatial)?,
            leaf_block: p.get_or("leaf_block", d.leaf_block)?,
        };
        let presplit_ok = c.presplit.is_finite() && (0.0..=16.0).contains(&c.presplit);
        let spatial_ok = c.spatial.is_finite() && (0.0..=1.0).contains(&c.spatial);
        if builder.is_embree() && c.max_leaf_size > Self::EMBREE_LEAF_LIMIT {
            return Err(Error::usage(format!(
                "builder = \"{}\" makes leaves of at most {} triangles (got leaf_size = {})",
                builder.name(),
                Self::EMBREE_LEAF_LIMIT,
                c.max_leaf_size
            )));
        }
        if builder == BvhBuilder::EmbreeBlocks && c.max_leaf_size < Self::EMBREE_BLOCK {
            return Err(Error::usage(format!(
                "builder = \"embree-blocks\" never splits {0} or fewer triangles: leaf_size must be at least {0} (got {1})",
                Self::EMBREE_BLOCK,
                c.max_leaf_size
            )));
        }
        if c.max_leaf_size == 0
            || !(1..=c.max_leaf_size).contains(&c.leaf_block)
            || !(2..=Self::BINS_LIMIT).contains(&c.bins)
            || c.max_depth > Self::DEPTH_LIMIT
            || !presplit_ok
            || !spatial_ok
        {
            return Err(Error::usage(format!(
                "BVH parameters out of range: leaf_size ≥ 1, leaf_block in [1, leaf_size], bins in [2, {}], max_depth ≤ {}, presplit in [0, 16], spatial in [0, 1] (got {c:?})",
                Self::BINS_LIMIT,
                Self::DEPTH_LIMIT
            )));
        }
        Ok(c)
    }

    /// The configuration for a moving mesh, which only our builder handles (swept boxes).
    pub fn for_moving(self) -> Result<Self> {
        match self.builder {
            BvhBuilder::Raylab => Ok(self),
            BvhBuilder::Embree | BvhBuilder::EmbreeBlocks => Err(Error::usage(format!(
                "builder = \"{}\" has no motion blur: a moving mesh needs builder = \"raylab\"",
                self.builder.name()
            ))),
        }
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
    /// The two children's boxes (their overlap decides whether spatial splits are tried).
    left: Aabb,
    right: Aabb,
}

/// Spatial splits stop once they have added this many references per triangle: a guard against
/// pathological scenes (the α threshold keeps real ones far below it).
const MAX_SPATIAL_GROWTH: usize = 1;

/// When the builder tries spatial splits.
struct SpatialBudget {
    /// The α of Stich et al. (§4.5); 0: never.
    alpha: f32,
    root_area: f32,
    /// Extra references spatial splits may still add.
    references_left: usize,
}

/// The state of one build: the tree so far and the references of the finished leaves.
struct Builder<'a> {
    config: BvhConfig,
    triangles: &'a [Triangle],
    spatial: SpatialBudget,
    nodes: Vec<BvhNode>,
    depth: Vec<u8>,
    /// References of the leaves in tree order (what `triangles` and `prim_ids` are made from).
    order: Vec<Reference>,
    bins: Vec<[Bin; 3]>,
}

impl Builder<'_> {
    /// Splits node `index` holding `refs` into its two children's references, or makes it a leaf
    /// (then `None`): the cheapest of object split, spatial split and leaf by SAH, a node over
    /// `max_leaf_size` always split (unless at `max_depth`).
    fn split(
        &mut self,
        index: usize,
        mut refs: Vec<Reference>,
    ) -> Option<(Vec<Reference>, Vec<Reference>)> {
        let count = refs.len();
        let config = self.config;
        if count > config.leaf_block
            && (self.depth[index] as usize) < config.max_depth.min(BvhConfig::DEPTH_LIMIT)
        {
            let centre_bounds = refs
                .iter()
                .fold(Aabb::EMPTY, |b, r| b.grow(r.bounds.center()));
            let price = |n: usize| leaf_price(n, config.leaf_block);
            let object = best_split(&refs, &centre_bounds, &mut self.bins, price);
            let must_split = count > config.max_leaf_size;
            let spatial = object
                .as_ref()
                .filter(|o| {
                    let overlap = intersection(&o.left, &o.right).surface_area();
                    self.spatial.alpha > 0.0
                        && self.spatial.references_left > 0
                        && overlap > self.spatial.alpha * self.spatial.root_area
                })
                .and_then(|o| {
                    let bounds = self.nodes[index].bounds;
                    best_spatial_split(&refs, self.triangles, &bounds, config.bins, price)
                        .filter(|s| s.cost < o.cost)
                });
            let leaf_cost = price(count);
            if let Some(s) = spatial.filter(|s| must_split || s.cost < leaf_cost) {
                let (left, right) = apply_spatial_split(refs, self.triangles, &s);
                let added = (left.len() + right.len()).saturating_sub(count);
                self.spatial.references_left = self.spatial.references_left.saturating_sub(added);
                return Some((left, right));
            }
            let mid = match object {
                Some(s) if must_split || s.cost < leaf_cost => {
                    let (lo, extent) = (centre_bounds.min[s.axis], centre_bounds.extent()[s.axis]);
                    let nb = config.bins;
                    partition(&mut refs, |r| {
                        bin_of(r.bounds.center()[s.axis], lo, extent, nb) < s.bin
                    })
                }
                // All centroids coincide: SAH cannot separate them; split by count if we must.
                None if must_split => count / 2,
                _ => 0,
            };
            if mid > 0 {
                let right = refs.split_off(mid);
                return Some((refs, right));
            }
        }
        self.nodes[index].first = self.order.len() as u32;
        self.order.extend(refs);
        None
    }
}

/// The box both `a` and `b` contain (empty when they do not overlap).
fn intersection(a: &Aabb, b: &Aabb) -> Aabb {
    Aabb::new(a.min.max(b.min), a.max.min(b.max))
}

impl Bvh {
    pub const ROOT: usize = 0;

    /// The tree by our builder (`config.builder` must be `Raylab`; `build_with` takes either).
    pub fn build(triangles: &[Triangle], config: BvhConfig) -> Bvh {
        debug_assert_eq!(
            config.builder,
            BvhBuilder::Raylab,
            "Bvh::build is our builder"
        );
        let start = Instant::now();
        let refs = split_references(triangles, config.presplit);
        Self::build_over(refs, triangles, None, config, start)
    }

    /// The tree by the builder `config` names: ours, or Embree's (which can fail, e.g. at its
    /// depth limit).
    pub fn build_with(triangles: &[Triangle], config: BvhConfig) -> Result<Bvh> {
        match config.builder {
            BvhBuilder::Raylab => Ok(Self::build(triangles, config)),
            BvhBuilder::Embree | BvhBuilder::EmbreeBlocks => {
                super::embree::build_bvh(triangles, config)
            }
        }
    }

    /// The tree over a mesh moving linearly from `open` to `close` (same count and order) during
    /// the shutter interval: each triangle's box is the union of its boxes at both ends, which
    /// holds it at every time in between (a box of linearly moving points is bounded by their
    /// end boxes). No early split clipping: a piece clipped at one end is not that piece later.
    pub fn build_moving(open: &[Triangle], close: &[Triangle], config: BvhConfig) -> Bvh {
        assert_eq!(open.len(), close.len(), "both ends of a moving mesh");
        debug_assert_eq!(config.builder, BvhBuilder::Raylab, "moving trees are ours");
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
        Self::build_over(refs, open, Some(close), config, start)
    }

    fn build_over(
        refs: Vec<Reference>,
        triangles: &[Triangle],
        close: Option<&[Triangle]>,
        config: BvhConfig,
        start: Instant,
    ) -> Bvh {
        let n = refs.len();
        let root_bounds = refs.iter().fold(Aabb::EMPTY, |b, r| b.union(r.bounds));
        // Spatial splits cut triangles at a plane: not for a moving mesh, whose references bound
        // a triangle over the whole shutter interval (as for early split clipping).
        let spatial = SpatialBudget {
            alpha: if close.is_none() { config.spatial } else { 0.0 },
            root_area: root_bounds.surface_area(),
            references_left: n.saturating_mul(MAX_SPATIAL_GROWTH),
        };
        let mut builder = Builder {
            config,
            triangles,
            spatial,
            nodes: Vec::with_capacity((2 * n).max(1)),
            depth: Vec::with_capacity((2 * n).max(1)),
            order: Vec::with_capacity(n),
            bins: vec![[EMPTY_BIN; 3]; config.bins],
        };
        builder.nodes.push(BvhNode {
            bounds: root_bounds,
            first: 0,
            count: n as u32,
        });
        builder.depth.push(0u8);
        // Work list of nodes still to split with their references; popped depth first, left child
        // first, so leaves take their triangle ranges in tree order.
        let mut pending = if n > 0 { vec![(0usize, refs)] } else { vec![] };
        while let Some((index, refs)) = pending.pop() {
            if let Some((left, right)) = builder.split(index, refs) {
                let child = builder.nodes.len();
                let node_depth = builder.depth[index];
                for side in [&left, &right] {
                    builder.nodes.push(BvhNode {
                        bounds: side.iter().fold(Aabb::EMPTY, |b, r| b.union(r.bounds)),
                        first: 0,
                        count: side.len() as u32,
                    });
                    builder.depth.push(node_depth + 1);
                }
                builder.nodes[index].first = child as u32;
                builder.nodes[index].count = 0;
                pending.push((child + 1, right));
                pending.push((child, left));
            }
        }

        let Builder {
            nodes,
            depth,
            order,
            ..
        } = builder;
        Self::from_leaf_order(nodes, depth, &order, triangles, close, config, start)
    }

    /// The finished tree from its nodes (children adjacent, leaves' ranges into `order`) and the
    /// leaves' references in tree order: triangles copied in that order, child pairs, build time
    /// since `start`. Shared by both builders, so their trees differ in shape only.
    pub(crate) fn from_leaf_order(
        nodes: Vec<BvhNode>,
        depth: Vec<u8>,
        order: &[Reference],
        triangles: &[Triangle],
        close: Option<&[Triangle]>,
        config: BvhConfig,
        start: Instant,
    ) -> Bvh {
        Bvh {
            triangles: order.iter().map(|r| triangles[r.prim as usize]).collect(),
            prim_ids: order.iter().map(|r| r.prim).collect(),
            motion_end: close.map(|close| order.iter().map(|r| close[r.prim as usize]).collect()),
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

    /// The tree's SAH cost with the builder's constants (traversal 1 per interior node, 1 per
    /// triangle reference in a leaf), each node weighted by its surface area over the root's: the
    /// expected work of a random ray through the root box (Goldsmith & Salmon 1987; MacDonald &
    /// Booth 1990). 0 for an empty tree.
    pub fn sah_cost(&self) -> f64 {
        if self.is_empty() {
            return 0.0;
        }
        let root_area = f64::from(self.nodes[Self::ROOT].bounds.surface_area());
        self.nodes
            .iter()
            .map(|n| {
                let work = if n.is_leaf() { f64::from(n.count) } else { 1.0 };
                // A scene flat to a segment or a point: every ray through it meets every node.
                let share = if root_area > 0.0 {
                    f64::from(n.bounds.surface_area()) / root_area
                } else {
                    1.0
                };
                work * share
            })
            .sum()
    }
}

/// The SAH's intersection cost of `count` triangles tested in blocks of `block`: whole blocks, a
/// block costing as many triangles as it holds (Embree's `sahBlockSize`); `block = 1`: the count.
#[inline(always)]
pub fn leaf_price(count: usize, block: usize) -> f32 {
    count.div_ceil(block.max(1)) as f32 * block.max(1) as f32
}

#[inline(always)]
fn bin_of(c: f32, lo: f32, extent: f32, bins: usize) -> usize {
    (((c - lo) / extent * bins as f32) as usize).min(bins - 1)
}

/// The cheapest SAH plane over all axes and bins, or `None` when every centroid is the same point.
/// `price`: a side's intersection cost from its triangle count (`leaf_price`).
fn best_split(
    refs: &[Reference],
    centre_bounds: &Aabb,
    bins: &mut [[Bin; 3]],
    price: impl Fn(usize) -> f32,
) -> Option<Split> {
    let nb = bins.len();
    let extent = centre_bounds.extent();
    bins.fill([EMPTY_BIN; 3]);
    for r in refs {
        let c = r.bounds.center();
        for axis in 0..3 {
            if extent[axis] > 0.0 {
                let b = &mut bins[bin_of(c[axis], centre_bounds.min[axis], extent[axis], nb)][axis];
                b.bounds = b.bounds.union(r.bounds);
                b.count += 1;
            }
        }
    }
    let parent_area = refs
        .iter()
        .fold(Aabb::EMPTY, |b, r| b.union(r.bounds))
        .surface_area()
        .max(f32::MIN_POSITIVE);
    let mut best: Option<Split> = None;
    let mut right_bounds = vec![Aabb::EMPTY; nb];
    let mut right_count = vec![0u32; nb];
    for axis in (0..3).filter(|&a| extent[a] > 0.0) {
        // Sweep from the right to get the cost of every "bins ≥ k go right" side.
        let (mut acc, mut cnt) = (Aabb::EMPTY, 0);
        for k in (1..nb).rev() {
            acc = acc.union(bins[k][axis].bounds);
            cnt += bins[k][axis].count;
            right_bounds[k] = acc;
            right_count[k] = cnt;
        }
        let (mut acc, mut cnt) = (Aabb::EMPTY, 0);
        for k in 1..nb {
            acc = acc.union(bins[k - 1][axis].bounds);
            cnt += bins[k - 1][axis].count;
            if cnt == 0 || right_count[k] == 0 {
                continue;
            }
            // Traversal cost 1, intersection cost `price`, relative to the parent's area.
            let right = right_bounds[k];
            let cost = 1.0
                + (acc.surface_area() * price(cnt as usize)
                    + right.surface_area() * price(right_count[k] as usize))
                    / parent_area;
            if best.as_ref().is_none_or(|b| cost < b.cost) {
                best = Some(Split {
                    axis,
                    bin: k,
                    cost,
                    left: acc,
                    right,
                });
            }
        }
    }
    best
}

/// In-place partition; returns how many elements satisfy `left` (they come first).
fn partition<T>(v: &mut [T], left: impl Fn(&T) -> bool) -> usize {
    let mut mid = 0;
    for i in 0..v.len() {
        if left(&v[i]) {
            v.swap(i, mid);
            mid += 1;
        }
    }
    mid
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;
    use crate::geometry::{RayBoxTest, WatertightRay};
    use crate::random::SplitMix64;
    use crate::test_util::with_slivers;

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
            spatial: 0.0,
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
    fn sah_cost_of_two_separate_triangles_by_hand() {
        // Two unit right triangles in z = 0, at x ∈ [0, 1] and x ∈ [3, 4]: each box has area
        // 2·(1·1) = 2, the root's [0, 4] × [0, 1] has 2·(4·1) = 8. Split (cost 1 + (2 + 2)/8 = 1.5)
        // beats a leaf of 2: SAH = 1 (root) + 1·2/8 + 1·2/8 = 1.5.
        let tris = [
            Triangle::new(Vec3::ZERO, Vec3::X, Vec3::Y),
            Triangle::new(
                Vec3::new(3.0, 0.0, 0.0),
                Vec3::new(4.0, 0.0, 0.0),
                Vec3::new(3.0, 1.0, 0.0),
            ),
        ];
        let bvh = Bvh::build(&tris, BvhConfig::default());
        assert_eq!(bvh.nodes.len(), 3);
        assert!((bvh.sah_cost() - 1.5).abs() < 1e-9, "{}", bvh.sah_cost());
        // Forced into one leaf (max_depth 0): 2 triangles over the root's own area.
        let leaf = Bvh::build(
            &tris,
            BvhConfig {
                max_depth: 0,
                ..BvhConfig::default()
            },
        );
        assert_eq!(leaf.sah_cost(), 2.0);
        assert_eq!(Bvh::build(&[], BvhConfig::default()).sah_cost(), 0.0);
    }

    /// Long diagonal slivers crossing a field of small triangles: their boxes cover the whole
    /// scene, so every object split leaves heavily overlapping children.
    fn slivers_over_small_triangles() -> Vec<Triangle> {
        with_slivers(grid_of_triangles(2000))
    }

    fn spatial(alpha: f32) -> BvhConfig {
        BvhConfig {
            presplit: 0.0,
            spatial: alpha,
            ..BvhConfig::default()
        }
    }

    #[test]
    fn spatial_splits_lower_the_sah_cost_where_slivers_overlap_everything() {
        let tris = slivers_over_small_triangles();
        let plain = Bvh::build(&tris, spatial(0.0));
        let split = Bvh::build(&tris, spatial(1e-5));
        assert_eq!(plain.triangles.len(), tris.len());
        assert!(split.triangles.len() > tris.len(), "slivers were split");
        assert!(
            split.sah_cost() < 0.9 * plain.sah_cost(),
            "SAH {} with spatial splits, {} without",
            split.sah_cost(),
            plain.sah_cost()
        );
        // On triangles that overlap little no split pays much, and none costs more.
        let small = grid_of_triangles(2000);
        let (a, b) = (
            Bvh::build(&small, spatial(0.0)),
            Bvh::build(&small, spatial(1e-5)),
        );
        assert!(
            b.sah_cost() <= a.sah_cost() * 1.0001,
            "{} > {}",
            b.sah_cost(),
            a.sah_cost()
        );
    }

    #[test]
    fn spatial_split_references_lie_in_their_leaves_and_cover_their_triangles() {
        let tris = slivers_over_small_triangles();
        for config in [
            spatial(1e-5),
            BvhConfig {
                spatial: 1e-5,
                ..BvhConfig::default()
            },
        ] {
            let bvh = Bvh::build(&tris, config);
            // Boxes nest, and each leaf's box lies within the triangles' own boxes' union.
            for (i, node) in bvh.nodes.iter().enumerate().filter(|(_, n)| !n.is_leaf()) {
                for c in [node.first as usize, node.first as usize + 1] {
                    assert!(
                        node.bounds.contains(&bvh.nodes[c].bounds),
                        "node {i}, child {c}"
                    );
                }
            }
            // Every sampled point of every triangle lies in a leaf that references it.
            let mut leaves_of = vec![Vec::new(); tris.len()];
            for node in bvh.nodes.iter().filter(|n| n.is_leaf()) {
                assert!(node.count as usize <= config.max_leaf_size);
                for k in node.first..node.first + node.count {
                    let id = bvh.prim_ids[k as usize] as usize;
                    assert_eq!(bvh.triangles[k as usize], tris[id]);
                    leaves_of[id].push(node.bounds);
                }
            }
            for (id, tri) in tris.iter().enumerate() {
                let whole = tri.bounds();
                for a in 0..=10 {
                    for b in 0..=(10 - a) {
                        let p = tri
                            .point(a as f32 / 10.0, b as f32 / 10.0)
                            .clamp(whole.min, whole.max);
                        assert!(
                            leaves_of[id].iter().any(|l| l.contains_point(p)),
                            "triangle {id}: {p:?} in no leaf of it"
                        );
                    }
                }
            }
        }
    }

    /// Closest hit of a ray by walking the tree (every box the ray enters, nothing pruned but by
    /// the slab test and the closest hit so far).
    fn closest_in_tree(bvh: &Bvh, origin: Vec3, dir: Vec3) -> Option<(f32, u32)> {
        let (boxes, ray) = (
            RayBoxTest::new(origin, dir),
            WatertightRay::new(origin, dir),
        );
        let mut best: Option<(f32, u32)> = None;
        let mut stack = vec![Bvh::ROOT];
        while let Some(i) = stack.pop() {
            let node = &bvh.nodes[i];
            let tmax = best.map_or(f32::INFINITY, |b| b.0);
            if boxes.hit(&node.bounds, 0.0, tmax).is_none() {
                continue;
            }
            if node.is_leaf() {
                for k in node.first..node.first + node.count {
                    let tmax = best.map_or(f32::INFINITY, |b| b.0);
                    if let Some((t, _, _)) = ray.intersect(&bvh.triangles[k as usize], 0.0, tmax) {
                        best = Some((t, bvh.prim_ids[k as usize]));
                    }
                }
            } else {
                stack.extend([node.first as usize, node.first as usize + 1]);
            }
        }
        best
    }

    #[test]
    fn spatial_split_trees_find_every_closest_hit_of_a_brute_force_search() {
        let tris = slivers_over_small_triangles();
        let bvh = Bvh::build(
            &tris,
            BvhConfig {
                spatial: 1e-5,
                ..BvhConfig::default()
            },
        );
        assert!(bvh.triangles.len() > tris.len());
        let mut rng = SplitMix64::new(11);
        let mut hits = 0;
        for _ in 0..4000 {
            let origin = rng.vec3(-2.0, 12.0);
            let target = rng.vec3(0.0, 10.0);
            let dir = target - origin;
            let ray = WatertightRay::new(origin, dir);
            let brute = tris
                .iter()
                .enumerate()
                .filter_map(|(i, t)| {
                    ray.intersect(t, 0.0, f32::INFINITY)
                        .map(|h| (h.0, i as u32))
                })
                .min_by(|a, b| a.0.total_cmp(&b.0));
            let walked = closest_in_tree(&bvh, origin, dir);
            assert_eq!(
                walked.map(|h| h.0),
                brute.map(|h| h.0),
                "ray {origin:?} → {target:?}"
            );
            hits += usize::from(brute.is_some());
        }
        assert!(hits > 1000, "only {hits} rays hit");
    }

    #[test]
    fn bvh_parameters_out_of_range_are_usage_errors() {
        for (key, value) in [
            ("spatial", "-0.1"),
            ("spatial", "2"),
            ("spatial", "nan"),
            ("spatial", "inf"),
            ("bins", "1"),
            ("bins", "100000"),
            ("leaf_size", "0"),
            ("presplit", "17"),
            ("leaf_block", "0"),
            ("leaf_block", "5"),
        ] {
            let err = BvhConfig::from_params(&Params::new().with(key, value)).unwrap_err();
            assert_eq!(err.exit_code(), 2, "{key} = {value}: {err}");
        }
        let ok = BvhConfig::from_params(&Params::new().with("spatial", 1e-5)).unwrap();
        assert_eq!(ok.spatial, 1e-5);
    }

    /// Block pricing by hand: a side costs its triangles rounded up to whole blocks. Eight far
    /// apart triangles in two clusters of four: per triangle, SAH splits down to single
    /// triangles; priced in blocks of 4, a node of 4 or fewer is never split, so the tree is the
    /// two clusters as two full leaves. In a random soup no node of 4 or fewer is split.
    #[test]
    fn leaves_priced_in_blocks_fill_them() {
        assert_eq!(leaf_price(5, 4), 8.0);
        assert_eq!(leaf_price(4, 4), 4.0);
        assert_eq!(leaf_price(3, 1), 3.0);
        let tris: Vec<Triangle> = (0..8)
            .map(|i| {
                let p = Vec3::new((i / 4) as f32 * 100.0 + (i % 4) as f32 * 3.0, 0.0, 0.0);
                Triangle::new(p, p + Vec3::X, p + Vec3::Y)
            })
            .collect();
        let plain = BvhConfig {
            spatial: 0.0,
            ..BvhConfig::default()
        };
        let blocks = BvhConfig {
            leaf_block: 4,
            ..plain
        };
        let leaves = |config| {
            let bvh = Bvh::build(&tris, config);
            let mut counts: Vec<u32> = bvh
                .nodes
                .iter()
                .filter(|n| n.is_leaf())
                .map(|n| n.count)
                .collect();
            counts.sort_unstable();
            counts
        };
        assert_eq!(leaves(plain), [1; 8]);
        assert_eq!(leaves(blocks), [4, 4]);
        let soup = grid_of_triangles(3000);
        let bvh = Bvh::build(&soup, blocks);
        check_invariants(&soup, &bvh);
        fn below(bvh: &Bvh, i: usize) -> u32 {
            let node = &bvh.nodes[i];
            match node.is_leaf() {
                true => node.count,
                false => below(bvh, node.first as usize) + below(bvh, node.first as usize + 1),
            }
        }
        for i in (0..bvh.nodes.len()).filter(|&i| !bvh.nodes[i].is_leaf()) {
            assert!(
                below(&bvh, i) > 4,
                "node {i} of {} was split",
                below(&bvh, i)
            );
        }
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
