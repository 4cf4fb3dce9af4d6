//! Large ray packets through the binary BVH (Overbeck, Ramamoorthi and Mark 2008, "Large Ray
//! Packets for Real-time Whitted Ray Tracing"), with the first-hit and interval-arithmetic
//! traversal of Wald et al. 2007 as used by Boulos et al. 2007 §3.3.
//!
//! - **Packets** (`packet` = n): `Rays::packets(n²)`, so explicit packets of the batch are kept;
//!   camera rays come in Morton-ordered 32×32 tiles, so n² consecutive camera rays are an n×n
//!   screen block. A packet is `⌈n²/L⌉` SIMD rays of `lanes` = L rays each (`simd`); the last
//!   one's unused lanes are padding that no box or triangle can hit.
//! - **Traversals** (`traversal`): `masked` (§3.1, Fig. 2), `ranged` (§3.2, App. A.1),
//!   `partition` (§3.3, App. A.2), `ia` (first hit + interval arithmetic, `first_hit`). Each file
//!   says which choices it makes where the paper leaves one. All visit children front to back by
//!   the signs of the packet's summed direction (`order`).
//! - **Frustum culling** (`frustum` = true, §4): a frustum bounding every ray of the packet, of
//!   the class the data shows (shared origin §4.1, shared end point §4.2, general §4.3; see
//!   `frustum`), culls boxes (Masked: before the ray tests; Ranged/IA: when the first active ray
//!   misses; Partition: before partitioning) and triangles at the leaves. Its far plane follows
//!   the packet's farthest current closest hit.
//! - **Exact closest hits**: every lane runs the reference tracer's slab and watertight tests
//!   bit for bit (`simd`), and culling is conservative, so each ray gets the reference's closest
//!   hit (up to the order in which triangles at exactly equal distance are met). With `robust =
//!   false` the lanes run plain slabs and Möller–Trumbore instead, bit for bit the reference's
//!   with `robust = false` (`geometry::robustness`).
//! - **Motion blur**: on a moving BVH (`Bvh::build_moving`, swept boxes) each lane meets a leaf's
//!   triangle where it is at that lane's time (`SimdRay::intersect_moving`: the reference tracer's
//!   interpolation, so hits stay bit-exact); frustum culling then skips triangles (a static
//!   triangle says nothing about where it is at the rays' times) but still culls swept boxes.
//! - **Occlusion**: a lane ends at its first hit (its `tmax` becomes −∞, so it hits nothing
//!   more) and the packet stops as soon as every lane has.
//! - **Wide trees** (`width` = 4 or 8; our addition, not the paper's): the binary tree collapsed
//!   into a 4- or 8-wide one (`accel::WideBvh`, built by the tracer when asked for) and walked by
//!   `wide`: Ranged traversal with one SIMD interval test of all of a node's children against
//!   the whole packet. `width` = 2 (the default) is the binary tree and the four traversals
//!   above, untouched; a wider tree runs only with `traversal = "ranged"`. Motion blur works as
//!   on the binary tree (the wide boxes are its swept boxes).
//!
//! - **Per-packet setup and results** (our engineering, not the paper's): a SIMD ray is loaded in
//!   one vectorized lane pass straight from the batch's arrays (`SimdRay::load`), the packet's
//!   bounds are folded lane-wise (`Packet::farthest_hit`, `IntervalPacket::from_lanes`) and only
//!   when a culling bound reads them, the next packet's rays and hit slots are prefetched while
//!   the current one is traced, and hits go straight into the caller's slice (every ray is
//!   written by its packet, so the output is not cleared first).
//!
//! Counters: `ray` per ray; `node(depth)` per node a packet visits (tests in any way);
//! `aabb_test(depth)` and `triangle_test(depth)` once per lane in use of every SIMD ray tested
//! against a box or a triangle — so per-ray averages compare with single-ray tracers, and count
//! the work a SIMD test really does, including lanes already dead (Overbeck's "active but not
//! alive" rays). Events: `Packets` per packet, `BoxesCulled` per box rejected for the whole packet
//! by the frustum or the interval test, `TrianglesCulled` per frustum–triangle cull,
//! `LeavesVisited` per leaf reached by a packet, `LeafActiveRays` the live lanes (in use, not yet
//! occluded) of the SIMD rays tested at those leaves, `TrianglesAccessed` per triangle of those
//! leaves the packet reads (Benthin & Wald 2009 Table 1's "#tris", as mft counts it per block).

mod first_hit;
mod frustum;
mod interval;
mod masked;
mod order;
mod partition;
mod ranged;
mod walk;
mod wide;
mod workspace;

use std::str::FromStr;
use std::sync::Arc;

use crate::accel::{Bvh, BvhOfWidth, WideNodes};
use crate::error::{Error, Result};
use crate::geometry::ray::prefetch;
use crate::geometry::robustness::robust_param;
use crate::geometry::{Fast, Hit, RayTests, Rays, Robust};
use crate::lanes::with_lanes;
use crate::params::Params;
use crate::stats::{Event, Stats};
use crate::tracers::kernel::Kernel;

pub use frustum::{Frustum, FrustumKind};

use first_hit::FirstHit;
use masked::Masked;
pub use order::ChildOrder;
use partition::Partition;
use ranged::Ranged;
use walk::traverse;
use wide::{traverse_wide, WideStack};
use workspace::{Packet, Tree};

/// The packet traversal algorithm.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Traversal {
    Masked,
    Ranged,
    Partition,
    /// First-hit test, then interval-arithmetic culling (Wald et al. 2007).
    Ia,
}

impl Traversal {
    pub const ALL: [Traversal; 4] = [
        Traversal::Masked,
        Traversal::Ranged,
        Traversal::Partition,
        Traversal::Ia,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Traversal::Masked => "masked",
            Traversal::Ranged => "ranged",
            Traversal::Partition => "partition",
            Traversal::Ia => "ia",
        }
    }
}

impl FromStr for Traversal {
    type Err = ();
    fn from_str(s: &str) -> std::result::Result<Self, ()> {
        Traversal::ALL.into_iter().find(|t| t.name() == s).ok_or(())
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PacketConfig {
    /// Packet side n: packets of n×n rays.
    pub packet: usize,
    /// SIMD width L: rays per SIMD ray.
    pub lanes: usize,
    pub traversal: Traversal,
    pub frustum: bool,
    /// The tests every lane runs (`robust`; `geometry::robustness`): conservative slabs and
    /// watertight triangles, or plain slabs and Möller–Trumbore.
    pub robust: bool,
}

impl Default for PacketConfig {
    fn default() -> Self {
        PacketConfig {
            packet: 16,
            lanes: 16,
            traversal: Traversal::Ranged,
            frustum: true,
            robust: true,
        }
    }
}

impl PacketConfig {
    pub const PARAMS: &'static [&'static str] =
        &["packet", "lanes", "traversal", "frustum", "width"];
    pub const PACKET_SIDES: [usize; 5] = [2, 4, 8, 16, 32];
    pub const LANES: [usize; 3] = [4, 8, 16];
    /// Children per BVH node (`width`): 2 is the binary tree (the paper's), 4 and 8 a wide one
    /// collapsed from it.
    pub const WIDTHS: [usize; 3] = [2, 4, 8];

    /// The `width` parameter (default 2), checked against this configuration.
    pub fn width_from_params(&self, p: &Params) -> Result<TreeWidth> {
        let width = p.get_or("width", 2usize)?;
        let tree = TreeWidth::of(width)?;
        if width > 2 && self.traversal != Traversal::Ranged {
            return Err(Error::usage(format!(
                "packet tracer: width = {width} walks the wide tree by its own ranged traversal; traversal = {:?} runs only on the binary tree (width = 2)",
                self.traversal.name()
            )));
        }
        Ok(tree)
    }

    pub fn from_params(p: &Params) -> Result<Self> {
        let d = PacketConfig::default();
        let c = PacketConfig {
            packet: p.get_or("packet", d.packet)?,
            lanes: p.get_or("lanes", d.lanes)?,
            traversal: p.get_or("traversal", d.traversal)?,
            frustum: p.get_or("frustum", d.frustum)?,
            robust: robust_param(p)?,
        };
        if !Self::PACKET_SIDES.contains(&c.packet) || !Self::LANES.contains(&c.lanes) {
            return Err(Error::usage(format!(
                "packet tracer: packet must be one of {:?} (n×n rays) and lanes one of {:?} (got packet = {}, lanes = {})",
                Self::PACKET_SIDES,
                Self::LANES,
                c.packet,
                c.lanes
            )));
        }
        Ok(c)
    }
}

/// Children per node of the tree a packet walks (`width` = 2, 4 or 8).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TreeWidth {
    /// The binary SAH tree: the paper's.
    Binary,
    Four,
    Eight,
}

impl TreeWidth {
    /// The tree of `children` per node, or a usage error naming `PacketConfig::WIDTHS`.
    pub fn of(children: usize) -> Result<TreeWidth> {
        match children {
            2 => Ok(TreeWidth::Binary),
            4 => Ok(TreeWidth::Four),
            8 => Ok(TreeWidth::Eight),
            _ => Err(Error::usage(format!(
                "packet tracer: width must be one of {:?} (children per BVH node; got {children})",
                PacketConfig::WIDTHS
            ))),
        }
    }

    pub fn children(self) -> usize {
        match self {
            TreeWidth::Binary => 2,
            TreeWidth::Four => 4,
            TreeWidth::Eight => 8,
        }
    }
}

pub struct PacketTracer {
    bvh: Arc<Bvh>,
    order: ChildOrder,
    nodes: BvhOfWidth,
    config: PacketConfig,
}

impl PacketTracer {
    /// Over `tree`: the binary BVH, or a wide tree the run built for this tracer's `width`
    /// (which only ranged traversal walks).
    pub fn new(tree: impl Into<BvhOfWidth>, config: PacketConfig) -> Self {
        let nodes = tree.into();
        let bvh = nodes.bvh().clone();
        PacketTracer {
            order: ChildOrder::new(&bvh),
            bvh,
            nodes,
            config,
        }
    }

    pub fn config(&self) -> PacketConfig {
        self.config
    }

    /// Traces `rays` packet by packet with the tests `R`, handing each packet's results to
    /// `out(first ray, hits)`.
    fn run<const L: usize, R: RayTests, S: Stats, const ANY: bool>(
        &self,
        rays: Rays<'_>,
        stats: &mut S,
        mut out: impl FnMut(usize, &Packet<L, R>),
    ) {
        let size = self.config.packet * self.config.packet;
        if S::ENABLED {
            (0..rays.len()).for_each(|_| stats.ray());
        }
        if self.bvh.is_empty() {
            return;
        }
        let tree = Tree {
            bvh: &self.bvh,
            order: &self.order,
        };
        let traversal = self.config.traversal;
        let mut packet = Packet::<L, R>::with_capacity(size);
        let mut wide_stack = WideStack::default();
        let mut packets = rays.packets(size).peekable();
        while let Some(range) = packets.next() {
            if S::ENABLED {
                stats.event(Event::Packets, 1);
            }
            if let Some(next) = packets.peek() {
                rays.prefetch(next.clone());
            }
            let first = range.start;
            // The wide traversal's node test is the interval test.
            let interval = traversal == Traversal::Ia || self.nodes.wide().is_some();
            packet.load(rays.slice(range), &tree, self.config.frustum, interval);
            packet.first = first;
            match (self.nodes.wide(), traversal) {
                (Some(WideNodes::Four(wide)), _) => traverse_wide::<4, L, R, S, ANY>(
                    &mut packet,
                    &tree,
                    wide,
                    &mut wide_stack,
                    stats,
                ),
                (Some(WideNodes::Eight(wide)), _) => traverse_wide::<8, L, R, S, ANY>(
                    &mut packet,
                    &tree,
                    wide,
                    &mut wide_stack,
                    stats,
                ),
                (None, traversal) => match traversal {
                    Traversal::Masked => {
                        traverse::<Masked, L, R, S, ANY>(&mut packet, &tree, stats)
                    }
                    Traversal::Ranged => {
                        traverse::<Ranged, L, R, S, ANY>(&mut packet, &tree, stats)
                    }
                    Traversal::Partition => {
                        traverse::<Partition, L, R, S, ANY>(&mut packet, &tree, stats)
                    }
                    Traversal::Ia => traverse::<FirstHit, L, R, S, ANY>(&mut packet, &tree, stats),
                },
            }
            out(first, &packet);
        }
    }

    fn intersect_lanes<const L: usize, R: RayTests, S: Stats>(
        &self,
        rays: Rays<'_>,
        hits: &mut [Hit],
        stats: &mut S,
    ) {
        // Every ray is in a packet that writes its hit; an empty tree makes no packets.
        if self.bvh.is_empty() {
            hits.fill(Hit::MISS);
        }
        self.run::<L, R, S, false>(rays, stats, |first, packet| {
            packet.store_hits(&mut hits[first..]);
            // The next packet's slots, cached by the time it has been traced.
            let next = first + packet.rays;
            prefetch(&hits[next..(next + packet.rays).min(hits.len())]);
        });
    }

    fn occluded_lanes<const L: usize, R: RayTests, S: Stats>(
        &self,
        rays: Rays<'_>,
        occluded: &mut [bool],
        stats: &mut S,
    ) {
        if self.bvh.is_empty() {
            occluded.fill(false);
        }
        self.run::<L, R, S, true>(rays, stats, |first, packet| {
            packet.store_occluded(&mut occluded[first..]);
        });
    }
}

impl Kernel for PacketTracer {
    fn intersect_with<S: Stats>(&self, rays: Rays<'_>, hits: &mut [Hit], stats: &mut S) {
        // The tests are a type parameter of every traversal, so each is built once per `robust`
        // value with only its own tests inline (a value branched on at each test cost the robust
        // camera rays 25% at 512²).
        with_lanes!(self.config.lanes, L => match self.config.robust {
            true => self.intersect_lanes::<L, Robust, S>(rays, hits, stats),
            false => self.intersect_lanes::<L, Fast, S>(rays, hits, stats),
        })
    }

    fn occluded_with<S: Stats>(&self, rays: Rays<'_>, occluded: &mut [bool], stats: &mut S) {
        with_lanes!(self.config.lanes, L => match self.config.robust {
            true => self.occluded_lanes::<L, Robust, S>(rays, occluded, stats),
            false => self.occluded_lanes::<L, Fast, S>(rays, occluded, stats),
        })
    }
}
