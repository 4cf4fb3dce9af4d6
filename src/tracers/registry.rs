//! The list of tracers by name, as data: which structure each traverses, which parameters it
//! reads, how to make one from a built structure, whether it traces moving geometry, and how many
//! rays it wants per work chunk. Adding a tracer is one entry here.

#[cfg(embree4)]
use crate::accel::embree::Embree4;
use crate::accel::embree::{Embree3, EMBREE4_BUILT, EMBREE4_HINT};
use crate::accel::{Accel, AccelKind};
use crate::error::{Error, Result};
use crate::geometry::{Hit, Rays};
use crate::scene::{Frame, Mesh};
use crate::stats::Counters;
use crate::tracers::batch::CHUNK_RAYS;
use crate::tracers::coherent_grid::{CgtConfig, CgtTracer};
use crate::tracers::embree::{
    Coherence, EmbreeTracer, Packets16, Packets4, Packets8, Single, Stream, Submission,
};
use crate::tracers::multi_frusta::{MftConfig, MftTracer};
use crate::tracers::packet::{PacketConfig, PacketTracer};
use crate::tracers::stream::{StreamConfig, StreamTracer};
use crate::tracers::{
    grid_dda::GridDdaTracer, obvhs::ObvhsTracer, reference::ReferenceTracer, wide_single, Params,
    Tracer, VisibilityQuery,
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

fn embree3<M: Submission<Embree3>>(params: &Params, accel: &Accel) -> Result<Box<dyn Tracer>> {
    Ok(Box::new(EmbreeTracer::<Embree3, M>::from_params(
        accel.embree()?,
        params,
    )?))
}

#[cfg(embree4)]
fn embree4<M: Submission<Embree4>>(params: &Params, accel: &Accel) -> Result<Box<dyn Tracer>> {
    Ok(Box::new(EmbreeTracer::<Embree4, M>::from_params(
        accel.embree4()?,
        params,
    )?))
}

/// An Embree tracer's entry: every one reads the coherence hint (`context`) and traces moving
/// geometry.
const fn embree_entry(
    name: &'static str,
    accel: AccelKind,
    about: &'static str,
    make: Make,
) -> TracerInfo {
    TracerInfo {
        name,
        accel,
        params: Coherence::PARAMS,
        about,
        make,
        motion_blur: true,
        chunk_rays: CHUNK_RAYS,
    }
}

/// The names the Embree 3 tracers had before Embree 4 came (`embree4` was rtcIntersect4!), kept
/// as aliases so existing experiment files still run; rows carry the new names.
pub const ALIASES: &[(&str, &str)] = &[
    ("embree1", "embree3-1"),
    ("embree4", "embree3-4"),
    ("embree8", "embree3-8"),
    ("embree16", "embree3-16"),
    ("embree-stream", "embree3-stream"),
];

/// The name rows carry for a tracer called `name`: the new name of an alias, else `name`.
pub fn canonical_name(name: &str) -> &str {
    ALIASES
        .iter()
        .find(|(alias, _)| *alias == name)
        .map_or(name, |(_, canonical)| canonical)
}

/// Whether `name` is a tracer this build lacks but another build has: Embree 4's, when
/// `build.rs` did not find Embree 4.
pub fn not_built(name: &str) -> bool {
    !EMBREE4_BUILT && EMBREE4_TRACERS.contains(&name)
}

/// The Embree 4 tracers, which a build without Embree 4 lacks (`accel::embree::EMBREE4_HINT`).
const EMBREE4_TRACERS: &[&str] = &["embree4-1", "embree4-4", "embree4-8", "embree4-16"];

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
        name: "wide-single",
        accel: AccelKind::Bvh,
        params: wide_single::PARAMS,
        about: "single rays, the SAH BVH collapsed to 4 or 8 children per node (width, default 8): one SIMD slab test of all children, nearest first; the reference's watertight triangles and hits",
        make: |params, accel| wide_single::from_params(accel.bvh()?.clone(), params),
        motion_blur: true,
        chunk_rays: CHUNK_RAYS,
    },
    embree_entry(
        "embree3-1",
        AccelKind::Embree,
        "Embree 3 baseline: rtcIntersect1 / rtcOccluded1 per ray (alias embree1)",
        embree3::<Single>,
    ),
    embree_entry(
        "embree3-4",
        AccelKind::Embree,
        "Embree 3 baseline: rtcIntersect4 / rtcOccluded4 on groups of 4 consecutive rays (alias embree4)",
        embree3::<Packets4>,
    ),
    embree_entry(
        "embree3-8",
        AccelKind::Embree,
        "Embree 3 baseline: rtcIntersect8 / rtcOccluded8 on groups of 8 consecutive rays (alias embree8)",
        embree3::<Packets8>,
    ),
    embree_entry(
        "embree3-16",
        AccelKind::Embree,
        "Embree 3 baseline: rtcIntersect16 / rtcOccluded16 on groups of 16 consecutive rays (alias embree16)",
        embree3::<Packets16>,
    ),
    embree_entry(
        "embree3-stream",
        AccelKind::Embree,
        "Embree 3 baseline: AoS ray streams, rtcIntersect1M / rtcOccluded1M (alias embree-stream)",
        embree3::<Stream>,
    ),
    #[cfg(embree4)]
    embree_entry(
        "embree4-1",
        AccelKind::Embree4,
        "Embree 4 baseline: rtcIntersect1 / rtcOccluded1 per ray",
        embree4::<Single>,
    ),
    #[cfg(embree4)]
    embree_entry(
        "embree4-4",
        AccelKind::Embree4,
        "Embree 4 baseline: rtcIntersect4 / rtcOccluded4 on groups of 4 consecutive rays",
        embree4::<Packets4>,
    ),
    #[cfg(embree4)]
    embree_entry(
        "embree4-8",
        AccelKind::Embree4,
        "Embree 4 baseline: rtcIntersect8 / rtcOccluded8 on groups of 8 consecutive rays",
        embree4::<Packets8>,
    ),
    #[cfg(embree4)]
    embree_entry(
        "embree4-16",
        AccelKind::Embree4,
        "Embree 4 baseline: rtcIntersect16 / rtcOccluded16 on groups of 16 consecutive rays",
        embree4::<Packets16>,
    ),
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
        about: "multi-frusta tracing (Benthin & Wald 2009): light-visibility queries as blocks of shadow frusta (block points, ≤ 64) through the SAH BVH together, rays generated on demand at leaves, box culling for all frusta at once, plane and corner-ray triangle culling, occlusion bits, corner-ray recomputation (cr), frustum shrinking (fs) and leaf ray–box tests (leaf_rays); with primary = frusta, pinhole camera batches as blocks of 4×4-pixel primary frusta, their rays made on demand from the camera grid; other ray batches (and camera rays by default) by 4×4 packets; exact answers (watertight)",
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
    /// The tracer `name` names, directly or through one of its `ALIASES`.
    pub fn find(name: &str) -> Result<&'static TracerInfo> {
        let canonical = canonical_name(name);
        if let Some(info) = TRACERS.iter().find(|t| t.name == canonical) {
            return Ok(info);
        }
        if not_built(name) {
            return Err(Error::usage(format!("tracer {name:?}: {EMBREE4_HINT}")));
        }
        let known: Vec<&str> = TRACERS.iter().map(|t| t.name).collect();
        Err(Error::usage(format!(
            "unknown tracer {name:?} (known: {})",
            known.join(", ")
        )))
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
pub const ORACLE: &str = "embree3-1";

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
    fn aliases_resolve_to_the_embree_3_tracers() {
        for (alias, canonical) in ALIASES {
            assert_eq!(TracerInfo::find(alias).unwrap().name, *canonical);
            assert_eq!(
                TracerInfo::find(canonical).unwrap().accel,
                AccelKind::Embree
            );
            assert!(
                TRACERS.iter().all(|t| t.name != *alias),
                "{alias} is only an alias"
            );
        }
        // `embree4` is Embree 3's rtcIntersect4, not Embree 4.
        assert_eq!(TracerInfo::find("embree4").unwrap().name, "embree3-4");
    }

    #[test]
    fn embree_4_tracers_exist_exactly_when_it_was_built() {
        for name in EMBREE4_TRACERS {
            let found = TracerInfo::find(name);
            assert_eq!(found.is_ok(), EMBREE4_BUILT, "{name}");
            assert_eq!(not_built(name), !EMBREE4_BUILT, "{name}");
            match found {
                Ok(info) => assert_eq!((info.name, info.accel.is_embree()), (*name, true)),
                Err(err) => {
                    assert!(matches!(err, Error::Usage(_)), "{err}");
                    assert!(err.to_string().contains(".ci/fetch-embree4"), "{err}");
                }
            }
        }
        assert!(!not_built("embree3-16") && !not_built("no-such-tracer"));
    }

    #[test]
    fn names_are_unique_and_chunks_hold_whole_blocks() {
        for (i, t) in TRACERS.iter().enumerate() {
            assert!(TRACERS[..i].iter().all(|u| u.name != t.name), "{}", t.name);
            assert!(t.chunk_rays > 0 && t.chunk_rays % 1024 == 0, "{}", t.name);
        }
    }
}
