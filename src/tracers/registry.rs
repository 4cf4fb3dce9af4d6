//! The list of tracers by name, as data: which structure each traverses, which parameters it
//! reads, how to make one from a built structure, whether it traces moving geometry, and how many
//! rays it wants per work chunk. Adding a tracer is one entry here.

use crate::accel::{Accel, AccelKind};
use crate::error::{Error, Result};
use crate::geometry::{Hit, Rays};
use crate::scene::{Frame, Mesh};
use crate::stats::Counters;
use crate::tracers::batch::CHUNK_RAYS;
use crate::tracers::cgt::{CgtConfig, CgtTracer};
use crate::tracers::embree::{
    Coherence, EmbreeTracer, Packets16, Packets4, Packets8, Single, Stream, Submission,
};
use crate::tracers::mft::{MftConfig, MftTracer};
use crate::tracers::packet::{PacketConfig, PacketTracer};
use crate::tracers::stream::{StreamConfig, StreamTracer};
use crate::tracers::{
    dda::GridDdaTracer, obvhs::ObvhsTracer, reference::ReferenceTracer, Params, Tracer,
    VisibilityQuery,
};

/// Makes a tracer from its parameters and a structure of its `AccelKind`.
type Make = fn(&Params, &Accel) -> Result<Box<dyn Tracer>>;

pub struct TracerInfo {
    pub name: &'static str,
    pub accel: AccelKind,
    /// Parameters the tracer itself reads (the structure's own are in `AccelKind::params`).
    pub params: &'static [&'static str],
    pub about: &'static str,
    pub make: Make,
    /// Whether it traces moving geometry at each ray's time (motion blur); a moving structure
    /// handed to any other tracer is refused rather than answered for the wrong instant.
    pub motion_blur: bool,
    /// Rays per work chunk (`tracers::batch`): a multiple of 1024, so no aligned n×n block of
    /// camera rays (n ≤ 32) straddles two chunks. A stream tracer wants far more than a packet
    /// tracer.
    pub chunk_rays: usize,
}

fn embree<M: Submission + 'static>(params: &Params, accel: &Accel) -> Result<Box<dyn Tracer>> {
    Ok(Box::new(EmbreeTracer::<M>::from_params(
        accel.embree()?,
        params,
    )?))
}

pub const TRACERS: &[TracerInfo] = &[
    TracerInfo {
        name: "reference",
        accel: AccelKind::Bvh,
        params: &[],
        about:
            "single rays, binary SAH BVH, nearer child first; watertight triangles, robust slabs",
        make: |_, accel| Ok(Box::new(ReferenceTracer::new(accel.bvh()?.clone()))),
        motion_blur: true,
        chunk_rays: CHUNK_RAYS,
    },
    TracerInfo {
        name: "embree1",
        accel: AccelKind::Embree,
        params: Coherence::PARAMS,
        about: "Embree 3 baseline: rtcIntersect1 / rtcOccluded1 per ray",
        make: embree::<Single>,
        motion_blur: true,
        chunk_rays: CHUNK_RAYS,
    },
    TracerInfo {
        name: "embree4",
        accel: AccelKind::Embree,
        params: Coherence::PARAMS,
        about: "Embree 3 baseline: rtcIntersect4 / rtcOccluded4 on groups of 4 consecutive rays",
        make: embree::<Packets4>,
        motion_blur: true,
        chunk_rays: CHUNK_RAYS,
    },
    TracerInfo {
        name: "embree8",
        accel: AccelKind::Embree,
        params: Coherence::PARAMS,
        about: "Embree 3 baseline: rtcIntersect8 / rtcOccluded8 on groups of 8 consecutive rays",
        make: embree::<Packets8>,
        motion_blur: true,
        chunk_rays: CHUNK_RAYS,
    },
    TracerInfo {
        name: "embree16",
        accel: AccelKind::Embree,
        params: Coherence::PARAMS,
        about: "Embree 3 baseline: rtcIntersect16 / rtcOccluded16 on groups of 16 consecutive rays",
        make: embree::<Packets16>,
        motion_blur: true,
        chunk_rays: CHUNK_RAYS,
    },
    TracerInfo {
        name: "embree-stream",
        accel: AccelKind::Embree,
        params: Coherence::PARAMS,
        about: "Embree 3 baseline: AoS ray streams, rtcIntersect1M / rtcOccluded1M",
        make: embree::<Stream>,
        motion_blur: true,
        chunk_rays: CHUNK_RAYS,
    },
    TracerInfo {
        name: "obvhs",
        accel: AccelKind::Obvhs,
        params: &[],
        about: "single rays, obvhs 0.4 compressed 8-wide BVH and its own traversal; watertight triangles",
        make: |_, accel| Ok(Box::new(ObvhsTracer::new(accel.obvhs()?.clone()))),
        motion_blur: false,
        chunk_rays: CHUNK_RAYS,
    },
    TracerInfo {
        name: "grid-dda",
        accel: AccelKind::Grid,
        params: &[],
        about: "single rays, uniform grid by 3D-DDA (Amanatides & Woo 1987), empty macrocells skipped; watertight triangles",
        make: |_, accel| Ok(Box::new(GridDdaTracer::new(accel.grid()?.clone()))),
        motion_blur: false,
        chunk_rays: CHUNK_RAYS,
    },
    TracerInfo {
        name: "cgt",
        accel: AccelKind::Grid,
        params: CgtConfig::PARAMS,
        about: "coherent grid traversal (Wald et al. 2006): n×n packets walk the uniform grid slice by slice in their frustum; per-packet mailboxing, SIMD frustum culling, macrocells",
        make: |params, accel| Ok(Box::new(CgtTracer::from_params(accel.grid()?.clone(), params)?)),
        motion_blur: false,
        chunk_rays: CHUNK_RAYS,
    },
    TracerInfo {
        name: "packet",
        accel: AccelKind::Bvh,
        params: PacketConfig::PARAMS,
        about: "large ray packets (Overbeck et al. 2008): n×n packets (packet ∈ 2,4,8,16,32) of L-lane SIMD rays (lanes ∈ 4,8,16) through the SAH BVH by masked, ranged, partition or ia (Wald et al. 2007 first hit + interval arithmetic) traversal, front to back by direction signs; frustum culling of boxes and triangles (shared-origin, shared-end-point or general frustum, from the data); exact closest hits (watertight, robust slabs per lane)",
        make: |params, accel| Ok(Box::new(PacketTracer::from_params(accel.bvh()?.clone(), params)?)),
        motion_blur: true,
        chunk_rays: CHUNK_RAYS,
    },
    TracerInfo {
        name: "mft",
        accel: AccelKind::Bvh,
        params: MftConfig::PARAMS,
        about: "multi-frusta tracing (Benthin & Wald 2009): light-visibility queries as blocks of shadow frusta (block points, ≤ 64) through the SAH BVH together, rays generated on demand at leaves, box culling for all frusta at once, plane and corner-ray triangle culling, occlusion bits, corner-ray recomputation (cr), frustum shrinking (fs) and leaf ray–box tests (leaf_rays); ordinary ray batches by 4×4 packets; exact answers (watertight)",
        make: |params, accel| Ok(Box::new(MftTracer::from_params(accel.bvh()?.clone(), params)?)),
        motion_blur: false,
        chunk_rays: CHUNK_RAYS,
    },
    TracerInfo {
        name: "stream",
        accel: AccelKind::Bvh,
        params: StreamConfig::PARAMS,
        about: "stream filtering (Gribble & Ramani 2008): streams of S rays (stream = S or frame) through the SAH BVH; at each node a box filter tests N rays at a time (width ∈ 4,8,12,16,32,64) and partitions the stream in place, the rays that meet the box going on to the leaf or to both children, front to back; exact closest hits (watertight, robust slabs per lane)",
        make: |params, accel| Ok(Box::new(StreamTracer::from_params(accel.bvh()?.clone(), params)?)),
        motion_blur: false,
        chunk_rays: 16 * CHUNK_RAYS,
    },
];

impl TracerInfo {
    pub fn find(name: &str) -> Result<&'static TracerInfo> {
        TRACERS.iter().find(|t| t.name == name).ok_or_else(|| {
            let known: Vec<&str> = TRACERS.iter().map(|t| t.name).collect();
            Error::usage(format!(
                "unknown tracer {name:?} (known: {})",
                known.join(", ")
            ))
        })
    }

    /// Every parameter this tracer accepts: its own and its structure's.
    pub fn accepts(&self) -> Vec<&'static str> {
        self.params
            .iter()
            .chain(self.accel.params())
            .copied()
            .collect()
    }
}

/// A tracer over `accel`, which must be of the tracer's `AccelKind` built with its parameters.
pub fn build_tracer(info: &TracerInfo, params: &Params, accel: &Accel) -> Result<Box<dyn Tracer>> {
    params.check_known(info.name, &info.accepts())?;
    if accel.is_moving() && !info.motion_blur {
        let movers: Vec<&str> = TRACERS
            .iter()
            .filter(|t| t.motion_blur)
            .map(|t| t.name)
            .collect();
        return Err(Error::usage(format!(
            "tracer {} has no motion blur (moving geometry needs one of {})",
            info.name,
            movers.join(", ")
        )));
    }
    Ok(Box::new(Registered {
        tracer: (info.make)(params, accel)?,
        chunk_rays: info.chunk_rays,
    }))
}

/// Builds tracer `name` with `params` over `mesh` (its own structure, built here).
pub fn tracer_for_mesh(name: &str, params: &Params, mesh: &Mesh) -> Result<Box<dyn Tracer>> {
    let info = TracerInfo::find(name)?;
    let accel = info
        .accel
        .build(mesh, &params.subset(info.accel.params()))?;
    build_tracer(info, params, &accel)
}

/// Builds tracer `name` with `params` over `frame`'s geometry (its own structure, built here).
pub fn tracer_for_frame(name: &str, params: &Params, frame: &Frame) -> Result<Box<dyn Tracer>> {
    tracer_for_mesh(name, params, &frame.mesh)
}

/// The oracle verification compares against: Embree's single-ray call on a robust,
/// high-quality scene.
pub const ORACLE: &str = "embree1";

pub fn oracle_params() -> Params {
    Params::new().with("robust", "true").with("quality", "high")
}

/// A tracer as its registry entry made it: the algorithm, and the chunk size the entry asks for.
struct Registered {
    tracer: Box<dyn Tracer>,
    chunk_rays: usize,
}

impl Tracer for Registered {
    fn counts_internals(&self) -> bool {
        self.tracer.counts_internals()
    }
    fn chunk_rays(&self) -> usize {
        self.chunk_rays
    }
    fn intersect(&self, rays: Rays<'_>, hits: &mut [Hit]) {
        self.tracer.intersect(rays, hits)
    }
    fn occluded(&self, rays: Rays<'_>, occluded: &mut [bool]) {
        self.tracer.occluded(rays, occluded)
    }
    fn intersect_counted(&self, rays: Rays<'_>, hits: &mut [Hit], counters: &mut Counters) {
        self.tracer.intersect_counted(rays, hits, counters)
    }
    fn occluded_counted(&self, rays: Rays<'_>, occluded: &mut [bool], counters: &mut Counters) {
        self.tracer.occluded_counted(rays, occluded, counters)
    }
    fn light_visibility(&self, query: VisibilityQuery<'_>, occluded: &mut [u64]) {
        self.tracer.light_visibility(query, occluded)
    }
    fn light_visibility_counted(
        &self,
        query: VisibilityQuery<'_>,
        occluded: &mut [u64],
        counters: &mut Counters,
    ) {
        self.tracer
            .light_visibility_counted(query, occluded, counters)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_unique_and_chunks_hold_whole_blocks() {
        for (i, t) in TRACERS.iter().enumerate() {
            assert!(TRACERS[..i].iter().all(|u| u.name != t.name), "{}", t.name);
            assert!(t.chunk_rays > 0 && t.chunk_rays % 1024 == 0, "{}", t.name);
        }
    }
}
