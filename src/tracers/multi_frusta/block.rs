//! One block of shading points through the BVH as a block of shadow frusta (Benthin & Wald 2009
//! §4, App. A): a stack of (node, mask of frusta) entries; at an inner node one test per child box
//! for all frusta of the mask (`Frusta::box_masks`); at a leaf, per triangle, culling for all frusta
//! (`cull::keep_mask`), then the rays of each remaining frustum, generated on demand when the
//! frustum first needs them (then kept while the block is traced), against the triangle, 16 rays
//! at a time. Occlusion is kept as bits; a
//! frustum retires when all its rays are occluded.
//!
//! The rays are `visibility::shadow_ray` of the per-query light points of each sample set (the
//! per-frame "delta vectors" of §4.4): the very rays of `VisibilityQuery::ray`, bit for bit, tested
//! by the reference tracer's watertight test, so the answer equals the reference tracer's.

use glam::Vec3;

use crate::accel::Bvh;
use crate::geometry::{Ray, RayTests};
use crate::lanes::vector::{Native, Vector};
use crate::lanes::SimdRay;
use crate::stats::{Event, Owners, Stats};
use crate::tracers::multi_frusta::descend::{keep_counted, next_leaf, start_at_root, FrustumTree};
use crate::tracers::multi_frusta::frusta::{bits, Frusta, Margins};
use crate::tracers::multi_frusta::MftConfig;
use crate::tracers::visibility::{shadow_ray, ShadingPoint, VisibilityQuery};

/// One worker's state, reused from block to block.
#[derive(Default)]
pub struct Scratch {
    pub frusta: Frusta,
    /// The light point of every sample of every set (`LightSamples` order).
    pub targets: Vec<Vec3>,
    /// The same light points as lanes, with each set's (s, t) rectangle.
    pub sets: SetLanes,
    /// Live (not yet occluded, casting a ray) samples: `words` per frustum.
    alive: Vec<u64>,
    /// The generated rays, 16 samples to a SIMD ray, `per_point.div_ceil(16)` per frustum.
    rays: Vec<SimdRay<LANES>>,
    stack: Vec<(u32, u64)>,
}

/// Rays per SIMD ray: the paper's 16-wide ray–triangle test, one frustum's 16 samples at once.
const LANES: usize = 16;

/// The light points of `query`'s sample sets, computed once per query (per frame).
pub fn light_points(query: &VisibilityQuery<'_>, targets: &mut Vec<Vec3>) {
    targets.clear();
    for set in 0..query.samples.sets() {
        let uv = query.samples.set(set as u32);
        targets.extend(uv.iter().map(|&[s, t]| query.light.point(s, t)));
    }
}

/// The light points of the query's sample sets as lanes (one array per axis, each set's samples
/// from a multiple of `SET_ALIGN`), so a point's samples in front of its surface are found one
/// vector of samples per pass, and the (s, t) rectangle of each whole set: the frustum of a point
/// all of whose samples are in front.
#[derive(Default)]
pub struct SetLanes {
    xyz: [Vec<f32>; 3],
    per_point: usize,
    /// Floats from one set's first sample to the next's.
    stride: usize,
    rect: Vec<[f32; 4]>,
}

/// Alignment of a set's samples in `SetLanes`: a multiple of every vector width.
const SET_ALIGN: usize = 16;

impl SetLanes {
    /// The lanes of `query`'s sample sets, from their light points `targets` (`light_points`).
    pub fn fill(&mut self, query: &VisibilityQuery<'_>, targets: &[Vec3]) {
        let per_point = query.samples.per_point();
        self.per_point = per_point;
        self.stride = per_point.next_multiple_of(SET_ALIGN);
        // Padding lanes past the last set too, so every vector load stays in bounds.
        let len = query.samples.sets() * self.stride + SET_ALIGN;
        for (a, axis) in self.xyz.iter_mut().enumerate() {
            axis.clear();
            axis.resize(len, 0.0);
            for (set, points) in targets.chunks(per_point).enumerate() {
                for (s, point) in points.iter().enumerate() {
                    axis[set * self.stride + s] = point[a];
                }
            }
        }
        self.rect.clear();
        self.rect.extend(
            (0..query.samples.sets()).map(|set| uv_rect(query.samples.set(set as u32).iter())),
        );
    }

    /// Sets in `alive` (zero on entry) the bits of point `p`'s samples in front of its surface
    /// (`shadow_ray`'s test, the same operations lane by lane) and returns their number.
    #[inline(always)]
    fn in_front<V: Vector>(&self, p: &ShadingPoint, alive: &mut [u64]) -> u32 {
        let first = p.set as usize * self.stride;
        let (position, normal) = (
            p.position.to_array().map(V::splat),
            p.normal.to_array().map(V::splat),
        );
        let mut count = 0;
        for s in (0..self.per_point).step_by(V::WIDTH) {
            let to = |a: usize| V::load(&self.xyz[a], first + s) - position[a];
            let facing = to(0) * normal[0] + to(1) * normal[1] + to(2) * normal[2];
            let samples = u64::MAX >> (64 - (self.per_point - s).min(V::WIDTH));
            let front = V::bits(facing.gt(V::splat(0.0))) & samples;
            alive[s / 64] |= front << (s % 64);
            count += front.count_ones();
        }
        count
    }
}

/// The ray of sample `sample` of point `i`: `VisibilityQuery::ray`, from the precomputed light
/// point.
#[inline(always)]
pub fn sample_ray(
    query: &VisibilityQuery<'_>,
    targets: &[Vec3],
    i: usize,
    sample: usize,
) -> Option<Ray> {
    let p = &query.points[i];
    let target = targets[p.set as usize * query.samples.per_point() + sample];
    shadow_ray(p.position, p.normal, p.origin, target).map(|r| r.at_time(p.time))
}

/// Block `first..first + len` of `query`: `occluded` (the block's words) must hold every sample
/// occluded on entry; the samples found visible are cleared. The frusta walk `tree`, made from
/// `bvh` (`bvh` itself or a wide tree collapsed from it). `R`: the rays' box and triangle tests.
#[allow(clippy::too_many_arguments)]
pub fn trace_block<T: FrustumTree, R: RayTests, S: Stats>(
    bvh: &Bvh,
    tree: &T,
    config: &MftConfig,
    margins: &Margins,
    query: &VisibilityQuery<'_>,
    first: usize,
    len: usize,
    occluded: &mut [u64],
    scratch: &mut Scratch,
    stats: &mut S,
) {
    let per_point = query.samples.per_point();
    let words = query.samples.words_per_point();
    let Scratch {
        frusta,
        targets,
        sets,
        alive,
        rays,
        stack,
    } = scratch;
    alive.clear();
    alive.resize(len * words, 0);
    let groups = per_point.div_ceil(LANES);
    if rays.len() < len * groups {
        rays.resize(len * groups, SimdRay::default());
    }
    frusta.len = len;

    // Frusta: the samples in front of each point's surface (`shadow_ray`'s test) are live, and
    // bounded by the (s, t) rectangle of those samples (the whole set's when all are).
    let mut live = 0u64;
    for f in 0..len {
        let p = &query.points[first + f];
        let point_alive = &mut alive[f * words..(f + 1) * words];
        let in_front = sets.in_front::<Native>(p, point_alive);
        if S::ENABLED {
            (0..in_front).for_each(|_| stats.ray());
        }
        // A point without a finite origin casts only ill-formed rays, which meet nothing (as in
        // the reference tracer): its samples stay live and end visible, without a frustum.
        if in_front > 0 && p.origin.is_finite() {
            let rect = if in_front as usize == per_point {
                sets.rect[p.set as usize]
            } else {
                live_rect(query, first + f, point_alive)
            };
            frusta.set(f, p.origin, &query.light, rect);
            live |= 1 << f;
        }
    }
    frusta.derive(live, Some(margins));
    if live == 0 || bvh.is_empty() {
        return finish(occluded, alive, words, len);
    }

    // Children are visited nearer first along the block's mean direction to the light.
    let towards = query.light.point(0.5, 0.5) - query.points[first].origin;
    // Frusta whose rays exist: made at the first leaf that needs them, kept for the block.
    let mut generated = 0u64;
    start_at_root::<T, S>(bvh, live, frusta, margins, stack, stats);
    while let Some((leaf, mask)) = next_leaf(tree, live, frusta, margins, towards, stack, stats) {
        // A leaf: per triangle, cull for all frusta, then the remaining frusta's rays.
        if S::ENABLED {
            stats.event(Event::LeavesVisited, 1);
            let live_rays: u32 = bits(mask)
                .flat_map(|f| &alive[f * words..(f + 1) * words])
                .map(|w| w.count_ones())
                .sum();
            stats.event(Event::LeafActiveRays, live_rays as u64);
        }
        let mut newly_occluded = 0u64;
        // `leaf_rays` (§5.3 "Ray-AABB"): frusta whose live rays were tested against the leaf's
        // box, and those none of whose rays meets it (robust slabs, as the reference tracer
        // enters a leaf), which skip the leaf.
        let (mut box_tested, mut box_missed) = (0u64, 0u64);
        for tri in &bvh.triangles[leaf.first as usize..][..leaf.count as usize] {
            let candidates = mask & live & !box_missed;
            if candidates == 0 {
                break;
            }
            let keep = keep_counted(frusta, tri, candidates, config.backface, stats);
            for f in bits(keep) {
                stats.charge_ray(f);
                let point_alive = &mut alive[f * words..(f + 1) * words];
                let simd = &mut rays[f * groups..(f + 1) * groups];
                if generated & 1 << f == 0 {
                    generated |= 1 << f;
                    let point_occluded = &mut occluded[f * words..(f + 1) * words];
                    generate(
                        query,
                        targets,
                        first + f,
                        point_alive,
                        point_occluded,
                        simd,
                        stats,
                    );
                }
                if config.leaf_rays && box_tested & 1 << f == 0 {
                    box_tested |= 1 << f;
                    if S::ENABLED {
                        let lanes: u32 = point_alive.iter().map(|w| w.count_ones()).sum();
                        stats.aabb_tests(
                            leaf.depth,
                            Owners::Repeat {
                                ray: f as u32,
                                n: lanes,
                            },
                            (groups * LANES) as u32,
                        );
                    }
                    let (lo, hi) = (leaf.bounds.min.to_array(), leaf.bounds.max.to_array());
                    if !simd.iter().any(|ray| ray.hits_box::<R>(lo, hi)) {
                        box_missed |= 1 << f;
                        continue;
                    }
                }
                for (g, ray) in simd.iter_mut().enumerate() {
                    let word = &mut point_alive[g / 4];
                    let shift = 16 * (g % 4);
                    let lanes = *word >> shift & 0xffff;
                    if lanes == 0 {
                        continue;
                    }
                    if S::ENABLED {
                        stats.triangle_tests(
                            leaf.depth,
                            Owners::Repeat {
                                ray: f as u32,
                                n: lanes.count_ones(),
                            },
                            LANES as u32,
                        );
                    }
                    if ray.intersect::<R, true>(tri, 0) > 0 {
                        *word &= !((lanes & !ray.live_mask()) << shift);
                        newly_occluded |= 1 << f;
                    }
                }
                if point_alive.iter().all(|&w| w == 0) {
                    live &= !(1 << f);
                }
            }
        }
        // §5.3: after the leaf, shrink the frusta that lost rays here (CR: corner rays; FS: also
        // the traversal bounds).
        // A frustum whose live rectangle did not change (samples lost inside it) keeps its
        // corners and bounds: re-aiming would recompute the same values.
        if config.cr || config.fs {
            let mut aimed = 0u64;
            for f in bits(newly_occluded & live) {
                let rect = live_rect(query, first + f, &alive[f * words..(f + 1) * words]);
                if rect != frusta.rect[f] {
                    frusta.rect[f] = rect;
                    frusta.aim(f, &query.light);
                    aimed |= 1 << f;
                }
            }
            frusta.derive(aimed, config.fs.then_some(margins));
        }
        if live == 0 {
            break;
        }
    }
    finish(occluded, alive, words, len)
}

/// Generates the rays of point `i`'s live samples into its SIMD rays, sample `s` in lane `s % 16`
/// of ray `s / 16` (dead samples are padding). A sample whose ray is ill-formed is answered at
/// once, as the reference tracer answers such a ray: not occluded.
#[inline(always)]
fn generate<S: Stats>(
    query: &VisibilityQuery<'_>,
    targets: &[Vec3],
    i: usize,
    alive: &mut [u64],
    occluded: &mut [u64],
    simd: &mut [SimdRay<LANES>],
    stats: &mut S,
) {
    for (g, lanes) in simd.iter_mut().enumerate() {
        for l in 0..LANES {
            let s = g * LANES + l;
            let (w, b) = (s / 64, s % 64);
            let ray = if s < query.samples.per_point() && alive[w] >> b & 1 == 1 {
                if S::ENABLED {
                    stats.event(Event::RaysOnDemand, 1);
                }
                let ray = sample_ray(query, targets, i, s).filter(Ray::is_well_formed);
                if ray.is_none() {
                    alive[w] &= !(1 << b);
                    occluded[w] &= !(1 << b);
                }
                ray
            } else {
                None
            };
            lanes.set_lane(l, ray.as_ref());
        }
        lanes.set_common_axes();
    }
}

/// The (s, t) rectangle of point `i`'s live samples (§5.3 CR).
fn live_rect(query: &VisibilityQuery<'_>, i: usize, alive: &[u64]) -> [f32; 4] {
    let uv = query.samples.set(query.points[i].set);
    let live = alive
        .iter()
        .enumerate()
        .flat_map(|(w, &word)| bits(word).map(move |b| &uv[w * 64 + b]));
    uv_rect(live)
}

/// The (s, t) rectangle `[s_min, s_max, t_min, t_max]` of light samples `uv` (empty: min > max).
fn uv_rect<'a>(uv: impl Iterator<Item = &'a [f32; 2]>) -> [f32; 4] {
    uv.fold(
        [
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::INFINITY,
            f32::NEG_INFINITY,
        ],
        |r, &[u, v]| [r[0].min(u), r[1].max(u), r[2].min(v), r[3].max(v)],
    )
}

/// The samples still live at the end see the light: their bits are cleared.
fn finish(occluded: &mut [u64], alive: &[u64], words: usize, len: usize) {
    for (o, a) in occluded[..len * words].iter_mut().zip(alive) {
        *o &= !a;
    }
}
