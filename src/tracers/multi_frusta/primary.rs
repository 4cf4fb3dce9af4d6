//! Primary frusta (P-Frusta, Benthin & Wald 2009 §4 and App. A): closest hits of a batch of
//! pinhole camera rays (`Rays::camera`) as blocks of frusta through the BVH.
//!
//! - **Frusta**: one per packet of ≤ 16 consecutive rays (`Rays::packets`; camera rays come in
//!   Morton-ordered tiles, so a 4×4 pixel block), from the camera through the rectangle of its
//!   pixels. `block` frusta (16 by default: a 16×16 pixel block) traverse the BVH together with
//!   the shadow frusta's machinery: one box test for all frusta per box (`Frusta::box_masks`) and
//!   plane and corner-ray triangle culling (`cull::keep_mask`).
//! - **Rays on demand**: a frustum's 16 rays are made at the first leaf where a triangle survives
//!   culling for it, from the batch's camera grid and the rays' pixels (`CameraGrid::pixel_ray`,
//!   the function that made the batch's rays, so they are the batch's rays bit for bit); the
//!   batch's own ray arrays are never read. In the paper's terms, the unnormalized direction of
//!   pixel (x, y) is the corner ray `D(x0, y0)` plus `(x − x0)·Δx + (y − y0)·Δy`, with the
//!   per-frame delta vectors `Δx = right·2·half_width/width` and `Δy = −up·2·half_height/height`;
//!   `CameraGrid::through` evaluates that affine function in the camera's own order, so it rounds
//!   as the batch's rays did.
//! - **Far distance** (App. A's per-frustum `distance`): a frustum's corner rays are its corner
//!   directions scaled to reach `far`: first past the scene's box, then, once every ray of the
//!   frustum has a hit, the farthest hit. Boxes and triangles beyond it are culled. Directions
//!   have length ≥ 1, so a ray's point at distance t lies within the frustum's first t.
//! - **Exact closest hits**: the reference tracer's watertight test in 16-lane SIMD rays
//!   (`SimdRay`), all culling conservative, so each ray gets the reference's closest hit (up to
//!   the order in which triangles at exactly equal distance are met).
//! - **Leaf ray tests** (`leaf_rays`, as for shadow frusta): at a leaf, a frustum's rays are
//!   tested against the leaf's box (each up to its closest hit so far) before its triangles; a
//!   frustum none of whose rays meets the box skips the leaf. The frustum hull reaches boxes
//!   that fall between its 16 rays, and a rays' own closest hits cull far more than the
//!   frustum's far distance.
//!
//! The paper's back-face culling of primary rays is left out (it would change answers on open
//! meshes); `cull`'s plane test drops triangles behind the camera or beyond `far` instead.

use std::cell::RefCell;
use std::ops::Range;

use crate::accel::Bvh;
use crate::geometry::{CameraGrid, Hit, RayTests, Rays};
use crate::lanes::SimdRay;
use crate::stats::{Event, Owners, Stats};
use crate::tracers::multi_frusta::descend::{keep_counted, next_leaf, start_at_root, FrustumTree};
use crate::tracers::multi_frusta::frusta::{bits, Frusta, Margins, MAX_FRUSTA};
use crate::tracers::multi_frusta::MftConfig;

/// Rays per primary frustum: a 4×4 pixel block, one 16-lane SIMD ray.
pub const FRUSTUM_RAYS: usize = 16;

/// Relative allowance on a frustum's far distance: the rays' directions are normalized in f32
/// (length 1 within 1e-7) and `far` scales the corner directions in f32.
const FAR_SLACK: f32 = 1e-5;

/// One worker's state, reused from block to block.
struct Scratch {
    frusta: Frusta,
    /// Each frustum's rays once generated (lane l = its packet's ray l).
    rays: [SimdRay<FRUSTUM_RAYS>; MAX_FRUSTA],
    /// Each frustum's far distance (see the module doc).
    far: [f32; MAX_FRUSTA],
    packets: Vec<Range<usize>>,
    stack: Vec<(u32, u64)>,
}

impl Default for Scratch {
    fn default() -> Self {
        Scratch {
            frusta: Frusta::default(),
            rays: [SimdRay::default(); MAX_FRUSTA],
            far: [0.0; MAX_FRUSTA],
            packets: Vec::new(),
            stack: Vec::new(),
        }
    }
}

thread_local! {
    static SCRATCH: RefCell<Box<Scratch>> = RefCell::default();
}

/// `hits[i]` becomes the closest hit of camera ray `i` of `rays` (`grid`'s rays through the
/// centres of `rays.pixel`), `config.block` frusta at a time, walking `tree` (`bvh` or a wide tree
/// collapsed from it).
pub fn intersect<T: FrustumTree, R: RayTests, S: Stats>(
    bvh: &Bvh,
    tree: &T,
    grid: &CameraGrid,
    config: &MftConfig,
    rays: Rays<'_>,
    hits: &mut [Hit],
    stats: &mut S,
) {
    if S::ENABLED {
        (0..rays.len()).for_each(|_| stats.ray());
    }
    hits.fill(Hit::MISS);
    // A camera whose rays are ill-formed (`Ray::is_well_formed`) meets nothing, as in the
    // reference tracer.
    let sane = grid.origin.is_finite()
        && [grid.forward, grid.right, grid.up]
            .iter()
            .all(|v| v.is_finite())
        && grid.half_width.is_finite()
        && grid.half_height.is_finite();
    if bvh.is_empty() || !sane {
        return;
    }
    let root = &bvh.nodes[Bvh::ROOT].bounds;
    let largest = |v: glam::Vec3| v.abs().max_element();
    let margins = Margins::new(
        largest(grid.origin)
            .max(largest(root.min))
            .max(largest(root.max)),
    );
    // Past every point of the scene's box.
    let far = (0..8)
        .map(|c| {
            let corner = glam::Vec3::select(
                glam::BVec3::new(c & 1 != 0, c & 2 != 0, c & 4 != 0),
                root.max,
                root.min,
            );
            corner.distance(grid.origin)
        })
        .fold(0.0f32, f32::max)
        * (1.0 + FAR_SLACK)
        + margins.distance;
    SCRATCH.with_borrow_mut(|scratch| {
        let mut packets = std::mem::take(&mut scratch.packets);
        packets.clear();
        packets.extend(rays.packets(FRUSTUM_RAYS));
        for group in packets.chunks(config.block) {
            let frame = Frame {
                bvh,
                tree,
                grid,
                margins: &margins,
                scene_far: far,
                leaf_rays: config.leaf_rays,
            };
            // Per-ray counters: frustum `f`'s counts go to its pixels' rays.
            let pixels: Vec<Range<u32>> = match S::ENABLED {
                true => group.iter().map(|r| r.start as u32..r.end as u32).collect(),
                false => Vec::new(),
            };
            stats.relabelled(&pixels, |stats| {
                trace_block::<T, R, S>(&frame, group, rays, hits, scratch, stats)
            });
        }
        scratch.packets = packets;
    })
}

/// Frustum `f` from the camera through the pixel rectangle `frusta.rect[f]` (pixel centres
/// `x0..=x1`, `y0..=y1`), its corner rays reaching `far` (then `Frusta::derive`).
fn aim(frusta: &mut Frusta, f: usize, grid: &CameraGrid, far: f32) {
    let [x0, x1, y0, y1] = frusta.rect[f];
    let corners = [(x0, y0), (x1, y0), (x0, y1), (x1, y1)]
        .map(|(x, y)| (grid.through(x, y) * far).to_array());
    for (a, o) in grid.origin.to_array().into_iter().enumerate() {
        frusta.origin[a][f] = o;
    }
    frusta.set_corners(f, corners);
}

/// What every block of a batch shares.
struct Frame<'a, T> {
    bvh: &'a Bvh,
    /// The tree the frusta walk: `bvh` or a wide tree collapsed from it.
    tree: &'a T,
    grid: &'a CameraGrid,
    margins: &'a Margins,
    /// A far distance past the scene's box.
    scene_far: f32,
    leaf_rays: bool,
}

/// The frusta of `group` (ray ranges of `rays`, ≤ `MAX_FRUSTA` of them) through the BVH; their
/// hits into `hits`, which holds misses on entry.
fn trace_block<T: FrustumTree, R: RayTests, S: Stats>(
    frame: &Frame<'_, T>,
    group: &[Range<usize>],
    rays: Rays<'_>,
    hits: &mut [Hit],
    scratch: &mut Scratch,
    stats: &mut S,
) {
    let Frame {
        bvh,
        tree,
        grid,
        margins,
        scene_far,
        leaf_rays,
    } = *frame;
    let Scratch {
        frusta,
        rays: simd,
        far,
        stack,
        ..
    } = scratch;
    frusta.len = group.len();
    for (f, packet) in group.iter().enumerate() {
        let mut rect = [
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::INFINITY,
            f32::NEG_INFINITY,
        ];
        for &pixel in &rays.pixel[packet.clone()] {
            let (x, y) = grid.pixel_xy(pixel);
            let (x, y) = (x as f32 + 0.5, y as f32 + 0.5);
            rect = [
                rect[0].min(x),
                rect[1].max(x),
                rect[2].min(y),
                rect[3].max(y),
            ];
        }
        frusta.rect[f] = rect;
        far[f] = scene_far;
        aim(frusta, f, grid, scene_far);
    }
    let all = if group.len() == 64 {
        u64::MAX
    } else {
        (1u64 << group.len()) - 1
    };
    frusta.derive(all, Some(margins));

    // Children are visited nearer first along the first frustum's middle direction.
    let [x0, x1, y0, y1] = frusta.rect[0];
    let towards = grid.through(0.5 * (x0 + x1), 0.5 * (y0 + y1));
    // Frusta whose rays exist: made at the first leaf that needs them.
    let mut generated = 0u64;
    start_at_root::<T, S>(bvh, all, frusta, margins, stack, stats);
    while let Some((leaf, mask)) = next_leaf(tree, !0, frusta, margins, towards, stack, stats) {
        // A leaf: per triangle, cull for all frusta, then the remaining frusta's rays.
        if S::ENABLED {
            stats.event(Event::LeavesVisited, 1);
            let leaf_rays: usize = bits(mask).map(|f| group[f].len()).sum();
            stats.event(Event::LeafActiveRays, leaf_rays as u64);
        }
        let mut hit_frusta = 0u64;
        // `leaf_rays`: frusta whose rays were tested against the leaf's box, and those none of
        // whose rays meets it within its closest hit so far, which skip the leaf.
        let (mut box_tested, mut box_missed) = (0u64, 0u64);
        for t in leaf.first as usize..(leaf.first + leaf.count) as usize {
            let candidates = mask & !box_missed;
            if candidates == 0 {
                break;
            }
            let tri = &bvh.triangles[t];
            let keep = keep_counted(frusta, tri, candidates, false, stats);
            let prim = bvh.prim_ids[t];
            for f in bits(keep) {
                stats.charge_ray(f);
                let pixels = &rays.pixel[group[f].clone()];
                // The frustum's rays, one SIMD ray, count as one ray here (`relabelled`).
                let frustum_rays = Owners::Repeat {
                    ray: f as u32,
                    n: pixels.len() as u32,
                };
                if generated & 1 << f == 0 {
                    generated |= 1 << f;
                    generate(grid, pixels, &mut simd[f], stats);
                }
                if leaf_rays && box_tested & 1 << f == 0 {
                    box_tested |= 1 << f;
                    if S::ENABLED {
                        stats.aabb_tests(leaf.depth, frustum_rays, FRUSTUM_RAYS as u32);
                    }
                    let (lo, hi) = (leaf.bounds.min.to_array(), leaf.bounds.max.to_array());
                    if !simd[f].hits_box::<R>(lo, hi) {
                        box_missed |= 1 << f;
                        continue;
                    }
                }
                if S::ENABLED {
                    stats.triangle_tests(leaf.depth, frustum_rays, FRUSTUM_RAYS as u32);
                }
                if simd[f].intersect::<R, false>(tri, prim) > 0 {
                    hit_frusta |= 1 << f;
                }
            }
        }
        // App. A: pull in the far distance of the frusta all of whose rays now have a hit.
        let mut aimed = 0u64;
        for f in bits(hit_frusta) {
            let farthest = simd[f].max_tmax() * (1.0 + FAR_SLACK);
            if farthest < far[f] {
                far[f] = farthest;
                aim(frusta, f, grid, farthest);
                aimed |= 1 << f;
            }
        }
        frusta.derive(aimed, Some(margins));
    }

    for f in bits(generated) {
        let out = &mut hits[group[f].clone()];
        for (l, hit) in out.iter_mut().enumerate() {
            *hit = simd[f].hit(l);
        }
    }
}

/// Makes the rays of a frustum's pixels into its SIMD ray, pixel `l` in lane `l` (unused lanes
/// are padding).
#[inline(always)]
pub(super) fn generate<S: Stats>(
    grid: &CameraGrid,
    pixels: &[u32],
    simd: &mut SimdRay<FRUSTUM_RAYS>,
    stats: &mut S,
) {
    for l in 0..FRUSTUM_RAYS {
        let ray = pixels.get(l).map(|&pixel| grid.pixel_ray(pixel));
        simd.set_lane(l, ray.as_ref());
    }
    simd.set_common_axes();
    if S::ENABLED {
        stats.event(Event::RaysOnDemand, pixels.len() as u64);
    }
}
