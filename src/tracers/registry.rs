//! The list of tracers by name: which structure each traverses, which parameters it reads, and how
//! to make one from a built structure. Adding a tracer is one entry here.

use crate::accel::{Accel, AccelKind};
use crate::error::{Error, Result};
use crate::tracers::{obvhs::ObvhsTracer, reference::ReferenceTracer, Params, Tracer};

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
        about: "single rays, binary SAH BVH, nearer child first; watertight triangles, robust slabs",
    },
    TracerInfo {
        name: "obvhs",
        accel: AccelKind::Obvhs,
        params: &[],
        about: "single rays, obvhs 0.4 compressed 8-wide BVH and its own traversal; watertight triangles",
    },
];

impl TracerInfo {
    pub fn find(name: &str) -> Result<&'static TracerInfo> {
        TRACERS.iter().find(|t| t.name == name).ok_or_else(|| {
            let known: Vec<&str> = TRACERS.iter().map(|t| t.name).collect();
            Error::usage(format!("unknown tracer {name:?} (known: {})", known.join(", ")))
        })
    }

    /// Every parameter this tracer accepts: its own and its structure's.
    pub fn accepts(&self) -> Vec<&'static str> {
        self.params.iter().chain(self.accel.params()).copied().collect()
    }
}

/// A tracer over `accel`, which must be of the tracer's `AccelKind` built with its parameters.
pub fn build_tracer(info: &TracerInfo, params: &Params, accel: &Accel) -> Result<Box<dyn Tracer>> {
    params.check_known(info.name, &info.accepts())?;
    match (info.name, accel) {
        ("reference", Accel::Bvh(bvh)) => Ok(Box::new(ReferenceTracer::new(bvh.clone()))),
        ("obvhs", Accel::Obvhs(bvh)) => Ok(Box::new(ObvhsTracer::new(bvh.clone()))),
        (name, _) => Err(Error::runtime(format!("tracer {name} was given the wrong structure"))),
    }
}
