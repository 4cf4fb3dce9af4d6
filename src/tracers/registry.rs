//! The list of tracers by name: which structure each traverses, which parameters it reads, and how
//! to make one from a built structure. Adding a tracer is one entry here.

use crate::accel::{Accel, AccelKind};
use crate::error::{Error, Result};
use crate::tracers::cgt::{CgtConfig, CgtTracer};
use crate::tracers::embree::{
    Coherence, EmbreeTracer, Packets16, Packets4, Packets8, Single, Stream,
};
use crate::tracers::packet::{PacketConfig, PacketTracer};
use crate::tracers::{
    dda::GridDdaTracer, obvhs::ObvhsTracer, reference::ReferenceTracer, Params, Tracer,
};

pub struct TracerInfo {
    pub name: &'static str,
    pub accel: AccelKind,
    /// Parameters the tracer itself reads (the structure's own are in `AccelKind::params`).
    pub params: &'static [&'static str],
    pub about: &'static str,
}

pub const TRACERS: &[TracerInfo] = &[
    TracerInfo {
        name: "reference",
        accel: AccelKind::Bvh,
        params: &[],
        about:
            "single rays, binary SAH BVH, nearer child first; watertight triangles, robust slabs",
    },
    TracerInfo {
        name: "embree1",
        accel: AccelKind::Embree,
        params: Coherence::PARAMS,
        about: "Embree 3 baseline: rtcIntersect1 / rtcOccluded1 per ray",
    },
    TracerInfo {
        name: "embree4",
        accel: AccelKind::Embree,
        params: Coherence::PARAMS,
        about: "Embree 3 baseline: rtcIntersect4 / rtcOccluded4 on groups of 4 consecutive rays",
    },
    TracerInfo {
        name: "embree8",
        accel: AccelKind::Embree,
        params: Coherence::PARAMS,
        about: "Embree 3 baseline: rtcIntersect8 / rtcOccluded8 on groups of 8 consecutive rays",
    },
    TracerInfo {
        name: "embree16",
        accel: AccelKind::Embree,
        params: Coherence::PARAMS,
        about: "Embree 3 baseline: rtcIntersect16 / rtcOccluded16 on groups of 16 consecutive rays",
    },
    TracerInfo {
        name: "embree-stream",
        accel: AccelKind::Embree,
        params: Coherence::PARAMS,
        about: "Embree 3 baseline: AoS ray streams, rtcIntersect1M / rtcOccluded1M",
    },
    TracerInfo {
        name: "obvhs",
        accel: AccelKind::Obvhs,
        params: &[],
        about: "single rays, obvhs 0.4 compressed 8-wide BVH and its own traversal; watertight triangles"
    },
    TracerInfo {
        name: "grid-dda",
        accel: AccelKind::Grid,
        params: &[],
        about: "single rays, uniform grid by 3D-DDA (Amanatides & Woo 1987), empty macrocells skipped; watertight triangles",
    },
    TracerInfo {
        name: "cgt",
        accel: AccelKind::Grid,
        params: CgtConfig::PARAMS,
        about: "coherent grid traversal (Wald et al. 2006): n×n packets walk the uniform grid slice by slice in their frustum; per-packet mailboxing, SIMD frustum culling, macrocells",
    },
    TracerInfo {
        name: "packet",
        accel: AccelKind::Bvh,
        params: PacketConfig::PARAMS,
        about: "large ray packets (Overbeck et al. 2008): n×n packets (packet ∈ 2,4,8,16,32) of L-lane SIMD rays (lanes ∈ 4,8,16) through the SAH BVH by masked, ranged, partition or ia (Wald et al. 2007 first hit + interval arithmetic) traversal, front to back by direction signs; frustum culling of boxes and triangles (shared-origin, shared-end-point or general frustum, from the data); exact closest hits (watertight, robust slabs per lane)",
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

/// The tracers over our BVH that test moving triangles at each ray's time (motion blur); any
/// other tracer handed a moving BVH is refused rather than answering for the wrong instant.
const BVH_MOTION_TRACERS: [&str; 2] = ["reference", "packet"];

/// A tracer over `accel`, which must be of the tracer's `AccelKind` built with its parameters.
pub fn build_tracer(info: &TracerInfo, params: &Params, accel: &Accel) -> Result<Box<dyn Tracer>> {
    params.check_known(info.name, &info.accepts())?;
    if let Accel::Bvh(bvh) = accel {
        if bvh.motion_end.is_some() && !BVH_MOTION_TRACERS.contains(&info.name) {
            return Err(Error::usage(format!(
                "tracer {} has no motion blur (moving geometry needs one of {} or embree)",
                info.name,
                BVH_MOTION_TRACERS.join(", ")
            )));
        }
    }
    match (info.name, accel) {
        ("reference", Accel::Bvh(bvh)) => Ok(Box::new(ReferenceTracer::new(bvh.clone()))),
        ("embree1", Accel::Embree(s)) => {
            Ok(Box::new(EmbreeTracer::<Single>::from_params(s, params)?))
        }
        ("embree4", Accel::Embree(s)) => {
            Ok(Box::new(EmbreeTracer::<Packets4>::from_params(s, params)?))
        }
        ("embree8", Accel::Embree(s)) => {
            Ok(Box::new(EmbreeTracer::<Packets8>::from_params(s, params)?))
        }
        ("embree16", Accel::Embree(s)) => {
            Ok(Box::new(EmbreeTracer::<Packets16>::from_params(s, params)?))
        }
        ("embree-stream", Accel::Embree(s)) => {
            Ok(Box::new(EmbreeTracer::<Stream>::from_params(s, params)?))
        }
        ("obvhs", Accel::Obvhs(bvh)) => Ok(Box::new(ObvhsTracer::new(bvh.clone()))),
        ("packet", Accel::Bvh(bvh)) => {
            Ok(Box::new(PacketTracer::from_params(bvh.clone(), params)?))
        }
        ("grid-dda", Accel::Grid(grid)) => Ok(Box::new(GridDdaTracer::new(grid.clone()))),
        ("cgt", Accel::Grid(grid)) => Ok(Box::new(CgtTracer::from_params(grid.clone(), params)?)),
        (name, _) => Err(Error::runtime(format!(
            "tracer {name} was given the wrong structure"
        ))),
    }
}
