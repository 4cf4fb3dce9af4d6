//! The Embree baselines as a `Kernel`: one tracer type over a committed `EmbreeScene`, generic
//! over the Embree version (`EmbreeApi`: 3 or 4) and over how rays are handed to it
//! (`Submission`: one at a time, packets of 4/8/16, Embree 3's streams).

use std::fmt;
use std::marker::PhantomData;
use std::str::FromStr;
use std::sync::Arc;

use super::denormals::FlushDenormals;
use crate::accel::embree::{EmbreeApi, EmbreeScene};
use crate::error::Result;
use crate::geometry::{Hit, RayKind, Rays};
use crate::params::Params;
use crate::stats::Stats;
use crate::tracers::Kernel;

/// One way of calling Embree `A`'s intersect/occluded functions on a chunk of rays.
pub trait Submission<A: EmbreeApi>: 'static {
    fn intersect(scene: &EmbreeScene<A>, args: &mut A::Arguments, rays: Rays<'_>, hits: &mut [Hit]);
    fn occluded(
        scene: &EmbreeScene<A>,
        args: &mut A::Arguments,
        rays: Rays<'_>,
        occluded: &mut [bool],
    );
}

/// The intersect context's hint (tracer parameter `context`): whether the rays of a call are
/// coherent (Embree 3's intersect context flag, Embree 4's ray query flag in the intersect and
/// occluded arguments). Embree's own default (`rtcInitIntersectContext`) is incoherent, and its
/// documentation prescribes the coherent traversal for coherent rays such as primary camera rays;
/// so `auto` (our default) gives each batch the hint its kind calls for (`for_kind`), and
/// `coherent` / `incoherent` force one.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Coherence {
    #[default]
    Auto,
    Coherent,
    Incoherent,
}

impl Coherence {
    pub const PARAMS: &'static [&'static str] = &["context"];

    pub fn from_params(p: &Params) -> Result<Self> {
        p.get_or("context", Coherence::default())
    }

    /// The hint a batch of `kind` gets: `auto` is coherent for camera rays and for point-light
    /// shadow rays (which converge on the light), incoherent for bounces, reflection, refraction
    /// and soft shadows (rays to scattered points of an area light).
    pub fn for_kind(self, kind: RayKind) -> Coherence {
        match (self, kind) {
            (Coherence::Auto, RayKind::Primary | RayKind::Shadow) => Coherence::Coherent,
            (Coherence::Auto, _) => Coherence::Incoherent,
            (forced, _) => forced,
        }
    }

    /// Whether a resolved hint is coherent (`Auto` before resolution is Embree's default,
    /// incoherent).
    fn is_coherent(self) -> bool {
        self == Coherence::Coherent
    }
}

impl FromStr for Coherence {
    type Err = ();
    fn from_str(s: &str) -> std::result::Result<Self, ()> {
        match s {
            "auto" => Ok(Coherence::Auto),
            "coherent" => Ok(Coherence::Coherent),
            "incoherent" => Ok(Coherence::Incoherent),
            _ => Err(()),
        }
    }
}

impl fmt::Display for Coherence {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Coherence::Auto => "auto",
            Coherence::Coherent => "coherent",
            Coherence::Incoherent => "incoherent",
        })
    }
}

pub struct EmbreeTracer<A: EmbreeApi, M: Submission<A>> {
    scene: Arc<EmbreeScene<A>>,
    coherence: Coherence,
    submission: PhantomData<fn() -> M>,
}

impl<A: EmbreeApi, M: Submission<A>> EmbreeTracer<A, M> {
    pub fn new(scene: Arc<EmbreeScene<A>>, coherence: Coherence) -> Self {
        EmbreeTracer {
            scene,
            coherence,
            submission: PhantomData,
        }
    }

    /// Runs one Embree call sequence on rays of `kind` the way Embree asks: FTZ/DAZ on for its
    /// duration only, and fresh arguments (intersect context) with the kind's coherence hint.
    #[inline]
    fn call<R>(&self, kind: RayKind, f: impl FnOnce(&EmbreeScene<A>, &mut A::Arguments) -> R) -> R {
        let _denormals = FlushDenormals::new();
        let mut args = A::arguments(self.coherence.for_kind(kind).is_coherent());
        f(&self.scene, &mut args)
    }
}

/// Embree's internals are opaque: only rays are counted.
#[inline(always)]
fn count_rays<S: Stats>(n: usize, stats: &mut S) {
    if S::ENABLED {
        for _ in 0..n {
            stats.ray();
        }
    }
}

impl<A: EmbreeApi, M: Submission<A>> Kernel for EmbreeTracer<A, M> {
    const COUNTS_INTERNALS: bool = false;

    fn intersect_with<S: Stats>(&self, rays: Rays<'_>, hits: &mut [Hit], stats: &mut S) {
        let rays = rays.slice(0..hits.len());
        count_rays(hits.len(), stats);
        self.call(rays.kind, |scene, args| {
            M::intersect(scene, args, rays, hits)
        });
    }

    fn occluded_with<S: Stats>(&self, rays: Rays<'_>, occluded: &mut [bool], stats: &mut S) {
        let rays = rays.slice(0..occluded.len());
        count_rays(occluded.len(), stats);
        self.call(rays.kind, |scene, args| {
            M::occluded(scene, args, rays, occluded)
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn auto_hints_coherence_by_ray_kind_and_a_parameter_forces_it() {
        let auto = Coherence::from_params(&Params::new()).unwrap();
        assert_eq!(auto, Coherence::Auto);
        let hinted: Vec<Coherence> = RayKind::ALL.iter().map(|&k| auto.for_kind(k)).collect();
        use Coherence::{Coherent as C, Incoherent as I};
        // Primary, shadow (point light), diffuse, reflection, refraction, soft shadow.
        assert_eq!(hinted, [C, C, I, I, I, I]);
        for forced in [C, I] {
            let p = Params::new().with("context", forced);
            let c = Coherence::from_params(&p).unwrap();
            assert!(RayKind::ALL.iter().all(|&k| c.for_kind(k) == forced));
        }
        assert!(Coherence::from_params(&Params::new().with("context", "fast")).is_err());
    }
}
