//! Multi-frusta tracing (MFT, registry name `mft`; Benthin & Wald 2009, "Efficient Ray Traced Soft Shadows using
//! Multi-Frusta Tracing"), answering the light-visibility query natively.
//!
//! - **Blocks** (`block` = B, default 16): B consecutive shading points of the query, one shadow
//!   frustum each (`frusta`), traverse the BVH together (`block`; the paper's 16 frusta of a 4×4
//!   pixel block). Consecutive primary hits are a screen block: camera rays come in Morton-ordered
//!   tiles, so 16 consecutive hits are a 4×4 block (less where rays miss). Grouping happens here,
//!   not through `ShadingPoints::packet_start`, so the packet tracer keeps its one packet of S
//!   rays per point (the paper's 16-ray "S-Packet" baseline). B ≤ 64 (one mask word).
//! - **On-demand rays**: a frustum's rays exist only at a leaf where a triangle survived culling
//!   for it, made from the per-query light points of its sample set (`block::sample_ray`, the same
//!   expression as `VisibilityQuery::ray`, so bit-identical rays).
//! - **Culling** (`cull`): boxes by interval arithmetic on the frusta's reciprocal directions plus
//!   their side planes, one vector test for all frusta per box (`lanes::vector`: 16 lanes on
//!   AVX-512, 8 on AVX2); triangles by plane culling and corner-ray culling per frustum, and, with
//!   `backface = true`, the paper's back-face culling (exact on closed meshes only; shadow
//!   frusta).
//! - **Shrinking** (§5.3, Table 2): `cr` recomputes a frustum's corner rays around its live
//!   samples after a leaf where it lost rays; `fs` also recomputes its traversal bounds (and
//!   implies `cr`); `leaf_rays` tests a frustum's live rays against a leaf's box before its
//!   triangles (the paper's "Ray-AABB"). All three on by default: in a sanity run (512², loaded
//!   machine) CR made conference and sibenik 8–10 % faster (the paper: up to 10 %), FS 2–10 % more
//!   and the leaf test 23 % more on conference (5× fewer ray–triangle tests: 16 sparse rays miss
//!   most leaves their frustum's hull reaches) but 5 % less on sibenik. The paper found FS and
//!   Ray-AABB not paying on Larrabee.
//! - **Wide trees** (`width` = 4 or 8; ours, not the paper's; 2, the binary tree, is the
//!   default): the same walk (`descend::FrustumTree`) over the wide BVH collapsed from the binary
//!   one (`wide_walk`), all frusta tested against a node's children at once; the leaves are the
//!   binary tree's, so the leaf stage and the answers are the same. Width 4 was 1.6–4.8 % faster
//!   than the binary walk on conference and sibenik at 1 and 2 threads in the quiet run of
//!   `raylab run experiments/benthin09-benchmark.toml` (results/benthin2009); width 8 tests more
//!   boxes per frustum (a child is culled only at its wide node: sibenik 6.3 box tests per ray
//!   against 5.1) and was slower on sibenik in a same-run A/B on a loaded machine.
//! - **Exact answers**: the sample rays meet triangles through the reference tracer's watertight
//!   test (with `robust = false` its Möller–Trumbore, and plain slabs), and all culling is conservative with rounding margins, so the bits equal the reference
//!   tracer's on the same rays.
//! - **Primary frusta** (`primary` = frusta, the paper's P-Frusta): closest hits of a batch of pinhole
//!   camera rays (one carrying its `CameraGrid`) as blocks of `block` frusta of 4×4 rays each,
//!   the rays generated on demand at leaves from the camera grid (bit for bit the batch's).
//!   The default, `primary = "packets"`, traces them as the other batches.
//! - **Ordinary rays** (`intersect` / `occluded` of any other batch, and camera rays on moving
//!   geometry): answered by the packet tracer on 4×4 packets with a frustum (the paper's
//!   "P-Packet").
//!
//! Counters: `ray` per sample ray (in front of its surface); `node` per node (of the tree walked)
//! and leaf a block visits;
//! `aabb_test` per frustum per box tested (lane count, as the packet tracer counts lanes);
//! `triangle_test` per ray–triangle test. Events: `FrustumBoxTests` one per box per block (the
//! paper's "#AABB tests"), `FrustaAtNodes` the frusta tested at inner nodes (÷ inner-node visits
//! = frusta per node), `BoxesCulled` boxes rejected for every frustum, `TrianglesAccessed` per
//! triangle per block at a leaf (the paper's "#tris", Fig. 6 "accessed triangles"),
//! `TrianglesKept` those left to at least one frustum after culling ("+culling"),
//! `FrustumTriangleTests` per (frustum, triangle) pair tested ("#isec": one 16-wide test in the
//! paper), `TrianglesCulled` per (frustum, triangle) culled, `RaysOnDemand` rays generated,
//! `LeavesVisited` / `LeafActiveRays` as for packets. Primary frusta count the same (`ray` per
//! camera ray, `triangle_test` per ray–triangle test, `RaysOnDemand` per ray made at a leaf).

mod block;
mod cull;
mod descend;
mod frusta;
mod primary;
#[cfg(test)]
mod primary_tests;
#[cfg(test)]
mod tests;
mod wide_walk;

use std::cell::RefCell;
use std::ops::Range;
use std::str::FromStr;
use std::sync::Arc;

use crate::accel::{Bvh, BvhOfWidth, WideNodes};
use crate::error::{Error, Result};
use crate::geometry::robustness::robust_param;
use crate::geometry::{CameraGrid, Fast, Hit, RayTests, Rays, Robust};
use crate::params::Params;
use crate::stats::Stats;
use crate::tracers::kernel::Kernel;
use crate::tracers::packet::{PacketConfig, PacketTracer, Traversal};
use crate::tracers::visibility::VisibilityQuery;
use descend::FrustumTree;

pub use block::{light_points, sample_ray};
pub use cull::keep_mask;
pub use frusta::{Frusta, Margins, MAX_FRUSTA};

/// How `mft` traces batches of pinhole camera rays.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PrimaryRays {
    /// Primary frusta (P-Frusta, `primary`).
    Frusta,
    /// 4×4 packets, as every other batch (P-Packet).
    Packets,
}

impl FromStr for PrimaryRays {
    type Err = ();
    fn from_str(s: &str) -> std::result::Result<Self, ()> {
        match s {
            "frusta" => Ok(PrimaryRays::Frusta),
            "packets" => Ok(PrimaryRays::Packets),
            _ => Err(()),
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MftConfig {
    /// Frusta per block traversed together: shading points, or 4×4 pixel blocks of camera rays.
    pub block: usize,
    /// Corner-ray recomputation (§5.3 CR).
    pub cr: bool,
    /// Frustum shrinking of the traversal bounds too (§5.3 FS; implies `cr`).
    pub fs: bool,
    /// At a leaf, each frustum's live rays against the leaf's box first (§5.3 "Ray-AABB").
    pub leaf_rays: bool,
    /// Camera rays as primary frusta (`block` of them together) or as packets.
    pub primary: PrimaryRays,
    /// The paper's back-face culling of triangles for shadow frusta (`cull`): exact on closed
    /// meshes only, so off by default.
    pub backface: bool,
    /// Children per node of the tree the frusta walk (`WIDTHS`): 2 is the binary tree (the
    /// paper's), 4 and 8 a wide tree collapsed from it (`wide_walk`).
    pub width: usize,
    /// The tests every lane runs (`robust`, set by the registry; `geometry::robustness`).
    pub robust: bool,
}

impl Default for MftConfig {
    fn default() -> Self {
        MftConfig {
            block: 16,
            cr: true,
            fs: true,
            leaf_rays: true,
            // Same-run sanity ratios (loaded machine) put frusta at 0.93–1.65× the packets' speed
            // at 1024² but 0.3–1.1× at 256² (wider frusta cull less): packets unless asked.
            primary: PrimaryRays::Packets,
            backface: false,
            width: 2,
            robust: true,
        }
    }
}

impl MftConfig {
    pub const PARAMS: &'static [&'static str] = &[
        "block",
        "cr",
        "fs",
        "leaf_rays",
        "primary",
        "backface",
        "width",
    ];
    pub const WIDTHS: &'static [usize] = &[2, 4, 8];

    pub fn from_params(p: &Params) -> Result<Self> {
        let d = MftConfig::default();
        let c = MftConfig {
            block: p.get_or("block", d.block)?,
            cr: p.get_or("cr", d.cr)?,
            fs: p.get_or("fs", d.fs)?,
            leaf_rays: p.get_or("leaf_rays", d.leaf_rays)?,
            primary: p.get_or("primary", d.primary)?,
            backface: p.get_or("backface", d.backface)?,
            width: p.get_or("width", d.width)?,
            robust: robust_param(p)?,
        };
        if !Self::WIDTHS.contains(&c.width) {
            return Err(Error::usage(format!(
                "mft tracer: width must be one of {:?} (children per BVH node; got {})",
                Self::WIDTHS,
                c.width
            )));
        }
        if !(1..=MAX_FRUSTA).contains(&c.block) {
            return Err(Error::usage(format!(
                "mft tracer: block must be 1 to {MAX_FRUSTA} frusta (got {})",
                c.block
            )));
        }
        Ok(c)
    }
}

pub struct MftTracer {
    bvh: Arc<Bvh>,
    /// The tree the frusta walk (`MftConfig::width`): the binary one or a wide one.
    tree: BvhOfWidth,
    config: MftConfig,
    /// Ordinary ray batches (P-Packet, see the module doc).
    packets: PacketTracer,
}

impl MftTracer {
    /// Over `tree`: the binary BVH, or the wide tree the run built for `config.width`.
    pub fn new(tree: impl Into<BvhOfWidth>, config: MftConfig) -> Self {
        let tree = tree.into();
        debug_assert_eq!(
            tree.wide().map_or(2, WideNodes::children),
            config.width,
            "the tree of the configured width"
        );
        let bvh = tree.bvh().clone();
        let packets = PacketTracer::new(
            bvh.clone(),
            PacketConfig {
                packet: 4,
                lanes: 16,
                traversal: Traversal::Ranged,
                frustum: true,
                robust: config.robust,
            },
        );
        MftTracer {
            bvh,
            tree,
            config,
            packets,
        }
    }

    /// The rounding margins for `query`: scaled by the largest coordinate of the scene, the light
    /// and the points' origins.
    fn margins(&self, query: &VisibilityQuery<'_>) -> Margins {
        let largest = |v: glam::Vec3| v.abs().max_element();
        let light = &query.light;
        let mut scale =
            largest(light.corner).max(largest(light.corner + light.edge_u + light.edge_v));
        scale = scale
            .max(largest(light.corner + light.edge_u))
            .max(largest(light.corner + light.edge_v));
        if !self.bvh.is_empty() {
            let root = &self.bvh.nodes[Bvh::ROOT].bounds;
            scale = scale.max(largest(root.min)).max(largest(root.max));
        }
        for p in query.points {
            scale = scale.max(largest(p.origin)).max(largest(p.position));
        }
        Margins::new(scale)
    }

    /// Camera rays as primary frusta through the configured tree, with the tests `R`.
    fn primary_frusta<R: RayTests, S: Stats>(
        &self,
        grid: &CameraGrid,
        rays: Rays<'_>,
        hits: &mut [Hit],
        stats: &mut S,
    ) {
        let (bvh, config) = (&*self.bvh, &self.config);
        match self.tree.wide() {
            None => primary::intersect::<_, R, S>(bvh, bvh, grid, config, rays, hits, stats),
            Some(WideNodes::Four(w)) => {
                primary::intersect::<_, R, S>(bvh, w, grid, config, rays, hits, stats)
            }
            Some(WideNodes::Eight(w)) => {
                primary::intersect::<_, R, S>(bvh, w, grid, config, rays, hits, stats)
            }
        }
    }

    /// `light_visibility_with` with the frusta walking `tree` (`self.bvh` or a wide tree from it).
    fn visibility_over<T: FrustumTree, S: Stats>(
        &self,
        tree: &T,
        query: VisibilityQuery<'_>,
        occluded: &mut [u64],
        stats: &mut S,
    ) {
        let words = query.samples.words_per_point();
        // `trace_block` clears the samples that see the light.
        query.samples.set_all_occluded(occluded);
        let margins = self.margins(&query);
        SCRATCH.with_borrow_mut(|scratch| {
            block::light_points(&query, &mut scratch.targets);
            scratch.sets.fill(&query, &scratch.targets);
            for first in (0..query.len()).step_by(self.config.block) {
                let len = self.config.block.min(query.len() - first);
                // Per-ray counters: frustum `f`'s counts go to shading point `first + f`.
                let points: Vec<Range<u32>> = match S::ENABLED {
                    true => (first as u32..(first + len) as u32)
                        .map(|p| p..p + 1)
                        .collect(),
                    false => Vec::new(),
                };
                let occluded = &mut occluded[first * words..(first + len) * words];
                let (bvh, config) = (&*self.bvh, &self.config);
                stats.relabelled(&points, |stats| match config.robust {
                    true => block::trace_block::<T, Robust, S>(
                        bvh, tree, config, &margins, &query, first, len, occluded, scratch, stats,
                    ),
                    false => block::trace_block::<T, Fast, S>(
                        bvh, tree, config, &margins, &query, first, len, occluded, scratch, stats,
                    ),
                });
            }
        })
    }
}

thread_local! {
    static SCRATCH: RefCell<block::Scratch> = RefCell::default();
}

impl Kernel for MftTracer {
    /// Rays are generated inside the frusta, at the leaves that need them (§4).
    const ANSWERS_VISIBILITY_NATIVELY: bool = true;

    fn intersect_with<S: Stats>(&self, rays: Rays<'_>, hits: &mut [Hit], stats: &mut S) {
        match rays.camera {
            // Primary frusta test static triangles only.
            Some(grid)
                if self.config.primary == PrimaryRays::Frusta && self.bvh.motion_end.is_none() =>
            {
                match self.config.robust {
                    true => self.primary_frusta::<Robust, S>(grid, rays, hits, stats),
                    false => self.primary_frusta::<Fast, S>(grid, rays, hits, stats),
                }
            }
            _ => self.packets.intersect_with(rays, hits, stats),
        }
    }

    fn occluded_with<S: Stats>(&self, rays: Rays<'_>, occluded: &mut [bool], stats: &mut S) {
        self.packets.occluded_with(rays, occluded, stats)
    }

    fn light_visibility_with<S: Stats>(
        &self,
        query: VisibilityQuery<'_>,
        occluded: &mut [u64],
        stats: &mut S,
    ) {
        match self.tree.wide() {
            None => self.visibility_over(&*self.bvh, query, occluded, stats),
            Some(WideNodes::Four(w)) => self.visibility_over(w, query, occluded, stats),
            Some(WideNodes::Eight(w)) => self.visibility_over(w, query, occluded, stats),
        }
    }
}
