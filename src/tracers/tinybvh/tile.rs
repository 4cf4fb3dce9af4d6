//! `tinybvh-256`: tinybvh's packet kernel, `BVH::Intersect256Rays`, on 16×16 blocks of camera rays.
//! Its source says it follows Overbeck et al. 2008 — the paper our `packet` tracer reproduces —
//! with a first-hit test on the packet's first active ray, a frustum of four planes through the
//! corner rays, and a first/last active-ray range narrowed at each box. It is a second,
//! independent implementation of the ranged traversal, over tinybvh's binary `BVH`.
//!
//! The call takes 256 rays sharing an origin, with the corners of the block at 0, 51, 204 and
//! 255: the block as 4×4 sub-blocks of 4×4 rays, each row-major (`order`). A pinhole camera's
//! batch (`Rays::camera`) comes in 32×32 Morton-ordered tiles, so each aligned run of 256 of its
//! rays is a 16×16 block: those go to the packet kernel, reordered. Anything else — a partial
//! block at an image edge, rays of a thin-lens camera, secondary rays — goes by single rays
//! (`BVH::Intersect`); occlusion always does, tinybvh having no packet occlusion query.
//!
//! The parameter `sse` (default true) picks `Intersect256RaysSSE`, tinybvh's SSE version of the
//! same traversal, over the scalar `Intersect256Rays`.

use std::ops::Range;
use std::sync::Arc;

use super::tiny_rays::{hit_of, tiny_ray, TinyRays};
use super::{count_rays, stage_occlusion_single};
use crate::accel::tinybvh::ffi::TinyRay;
use crate::accel::TinyBvh;
use crate::error::{Error, Result};
use crate::geometry::{CameraGrid, Hit, Rays};
use crate::params::Params;
use crate::stats::Stats;
use crate::tracers::kernel::Kernel;
use crate::tracers::staged::{staged_by, StagedRays};

/// The rays of one packet: a 16×16 block.
pub const PACKET: usize = 256;

/// `tinybvh-256`'s parameters.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TileConfig {
    /// `Intersect256RaysSSE` rather than `Intersect256Rays`.
    pub sse: bool,
}

impl TileConfig {
    pub const PARAMS: &'static [&'static str] = &["sse"];

    pub fn from_params(p: &Params) -> Result<Self> {
        Ok(TileConfig {
            sse: p.get_or("sse", true)?,
        })
    }
}

/// Where ray `(dx, dy)` of a 16×16 block goes in the packet `Intersect256Rays` takes: 4×4
/// sub-blocks of 4×4 rays, both row-major, so that the corners are rays 0, 51, 204 and 255.
#[inline(always)]
pub fn order(dx: u32, dy: u32) -> usize {
    ((dx & 3) | (dy & 3) << 2 | (dx >> 2) << 4 | (dy >> 2) << 6) as usize
}

/// Whether a block goes to `Intersect256Rays` mirrored left to right. It builds its frustum's
/// planes from the corner rays assuming `forward × up` points left (the left plane's normal is
/// `top-left × (top-left − bottom-left)`, taken to point out of the frustum); for a camera whose
/// `forward × up` points right, as raylab's do, those normals point in and the frustum culls
/// what it should keep. Handing the block over mirrored makes them point out; the rays are the
/// same.
pub fn mirrored(camera: &CameraGrid) -> bool {
    camera.forward.cross(camera.up).dot(camera.right) > 0.0
}

/// The packet slot of each of `pixels` when they are exactly the pixels of one 16×16 block of
/// `camera`'s image, in any order; `None` otherwise. Columns are mirrored when `mirrored`.
pub fn block_slots(camera: &CameraGrid, pixels: &[u32]) -> Option<[u8; PACKET]> {
    let mirror = mirrored(camera);
    if pixels.len() != PACKET {
        return None;
    }
    let x0 = pixels.iter().map(|&p| camera.pixel_xy(p).0).min()?;
    let y0 = pixels.iter().map(|&p| camera.pixel_xy(p).1).min()?;
    let mut slots = [0u8; PACKET];
    let mut seen = [false; PACKET];
    for (slot, &pixel) in slots.iter_mut().zip(pixels) {
        let (x, y) = camera.pixel_xy(pixel);
        let (dx, dy) = (x - x0, y - y0);
        if dx >= 16 || dy >= 16 {
            return None;
        }
        let k = order(if mirror { 15 - dx } else { dx }, dy);
        if seen[k] {
            return None;
        }
        seen[k] = true;
        *slot = k as u8;
    }
    Some(slots)
}

pub struct TileTracer {
    bvh: Arc<TinyBvh>,
    config: TileConfig,
}

impl TileTracer {
    /// Over tinybvh's binary `BVH`, the only layout with the packet kernel.
    pub fn new(bvh: Arc<TinyBvh>, config: TileConfig) -> Result<Self> {
        if bvh.layout != crate::accel::TinyLayout::Binary {
            return Err(Error::runtime(format!(
                "Intersect256Rays needs tinybvh's BVH, not {}",
                bvh.layout.class()
            )));
        }
        Ok(TileTracer { bvh, config })
    }

    /// The 256 rays of `rays` laid out in `packet`, and each ray's slot; `None` when they are
    /// not a 16×16 block of camera rays from one origin with tmin = 0.
    fn packet(&self, rays: &Rays<'_>, packet: &mut [TinyRay; PACKET]) -> Option<[u8; PACKET]> {
        let slots = block_slots(rays.camera?, rays.pixel)?;
        for (i, &slot) in slots.iter().enumerate() {
            match tiny_ray(&self.bvh, rays, i) {
                Some((ray, 0.0)) => packet[slot as usize] = ray,
                _ => return None,
            }
        }
        Some(slots)
    }
}

/// One block of a staged batch: a 16×16 tile in `Intersect256Rays`' order with each ray's slot,
/// or rays that go by single rays.
enum Block {
    Packet(Box<[TinyRay; PACKET]>, [u8; PACKET]),
    Single(TinyRays),
}

impl TileTracer {
    /// `rays` cut into blocks of `PACKET` rays, each staged as a packet when it is one.
    fn stage(&self, rays: &Rays<'_>) -> Vec<(Range<usize>, Block)> {
        (0..rays.len())
            .step_by(PACKET)
            .map(|start| {
                let range = start..rays.len().min(start + PACKET);
                let block = rays.slice(range.clone());
                let mut packet = Box::new([TinyRay::new([0.0; 3], [1.0, 0.0, 0.0], 0.0); PACKET]);
                let staged = match self.packet(&block, &mut packet) {
                    Some(slots) => Block::Packet(packet, slots),
                    None => Block::Single(TinyRays::stage(&self.bvh, &block)),
                };
                (range, staged)
            })
            .collect()
    }

    /// Closest hits of staged `blocks`, `hits[i]` for ray `i` of the batch they were staged from.
    fn intersect_staged(&self, blocks: &mut [(Range<usize>, Block)], hits: &mut [Hit]) {
        for (range, block) in blocks {
            let hits = &mut hits[range.clone()];
            match block {
                Block::Packet(packet, slots) => {
                    if !self.bvh.intersect256(packet, self.config.sse) {
                        // Not reached: `new` takes the binary layout only. The same rays, singly.
                        self.bvh.intersect(&mut packet[..]);
                    }
                    for (hit, &slot) in hits.iter_mut().zip(slots.iter()) {
                        *hit = hit_of(&self.bvh, &packet[slot as usize], 0.0);
                    }
                }
                Block::Single(rays) => rays.intersect(&self.bvh, hits),
            }
        }
    }
}

impl Kernel for TileTracer {
    const COUNTS_INTERNALS: bool = false;

    fn intersect_with<S: Stats>(&self, rays: Rays<'_>, hits: &mut [Hit], stats: &mut S) {
        count_rays(hits.len(), stats);
        self.intersect_staged(&mut self.stage(&rays), hits);
    }

    fn occluded_with<S: Stats>(&self, rays: Rays<'_>, occluded: &mut [bool], stats: &mut S) {
        count_rays(occluded.len(), stats);
        TinyRays::stage(&self.bvh, &rays).occluded(&self.bvh, occluded);
    }

    fn stage_closest(
        &self,
        rays: Rays<'_>,
        chunks: Vec<Range<usize>>,
    ) -> Option<Box<dyn StagedRays<Hit> + '_>> {
        Some(staged_by(
            chunks,
            |range| self.stage(&rays.slice(range)),
            move |blocks: &mut Vec<(Range<usize>, Block)>, out: &mut [Hit]| {
                self.intersect_staged(blocks, out)
            },
        ))
    }

    fn stage_occlusion(
        &self,
        rays: Rays<'_>,
        chunks: Vec<Range<usize>>,
    ) -> Option<Box<dyn StagedRays<bool> + '_>> {
        Some(stage_occlusion_single(&self.bvh, rays, chunks))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_corners_of_a_block_are_where_intersect256rays_reads_them() {
        // tiny_bh.h: "Corner rays are: 0, 51, 204 and 255" (top-left, top-right, bottom-left,
        // bottom-right).
        assert_eq!(
            [order(0, 0), order(15, 0), order(0, 15), order(15, 15)],
            [0, 51, 204, 255]
        );
        let mut all: Vec<usize> = (0..16)
            .flat_map(|y| (0..16).map(move |x| order(x, y)))
            .collect();
        all.sort_unstable();
        assert_eq!(all, (0..PACKET).collect::<Vec<_>>(), "a permutation");
    }
}
