//! The Embree baselines as a `Kernel`: one tracer type over a committed `EmbreeScene`, generic
//! over the Embree version (`EmbreeApi`: 3 or 4) and over how rays are handed to it
//! (`Submission`: one at a time, packets of 4/8/16, Embree 3's streams).

use std::fmt;
use std::marker::PhantomData;
use std::ops::Range;
use std::str::FromStr;
use std::sync::Arc;

use super::denormals::FlushDenormals;
use crate::accel::embree::{EmbreeApi, EmbreeScene};
use crate::error::Result;
use crate::geometry::{Hit, RayKind, Rays};
use crate::params::Params;
use crate::stats::Stats;
use crate::tracers::kernel::Kernel;
use crate::tracers::staged::staged_by;
use crate::tracers::staged::StagedRays;

/// One way of calling Embree `A` on a chunk of rays: how the chunk is cut into calls, the record
/// each call takes (a ray, a packet of 4/8/16, a stream), made from our rays (`stage_*`), and the
/// calls on it. A timed pass of a baseline stages the whole batch first (`Kernel::stage_*`), so
/// it pays only for the calls, as a user holding rays in Embree's layout would.
pub trait Submission<A: EmbreeApi>: 'static {
    /// One closest-hit call's record.
    type Hits: Send;
    /// One occlusion call's record.
    type Shadows: Send;
    /// The calls of `rays`, in order: consecutive runs covering them.
    fn calls(rays: Rays<'_>) -> impl Iterator<Item = Range<usize>> + '_;
    fn stage_hits(rays: &Rays<'_>, call: Range<usize>) -> Self::Hits;
    fn stage_shadows(rays: &Rays<'_>, call: Range<usize>) -> Self::Shadows;
    /// Traces one call's record; `hits` has one entry per ray of its call.
    fn intersect(
        scene: &EmbreeScene<A>,
        args: &mut A::Arguments,
        record: &mut Self::Hits,
        hits: &mut [Hit],
    );
    fn occluded(
        scene: &EmbreeScene<A>,
        args: &mut A::Arguments,
        record: &mut Self::Shadows,
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

impl<A: EmbreeApi, M: Submission<A>> EmbreeTracer<A, M> {
    /// The records of the calls of `rays`, each with its run of the rays.
    fn stage<Q: Query<A, M>>(rays: Rays<'_>) -> Vec<(Range<usize>, Q::Record)> {
        M::calls(rays)
            .map(|call| (call.clone(), Q::stage(&rays, call)))
            .collect()
    }

    /// Every call of `staged` (records of rays of `kind`), answers into `out`.
    fn trace_staged<Q: Query<A, M>>(
        &self,
        kind: RayKind,
        staged: &mut [(Range<usize>, Q::Record)],
        out: &mut [Q::Answer],
    ) {
        self.call(kind, |scene, args| {
            for (call, record) in staged {
                Q::trace(scene, args, record, &mut out[call.clone()]);
            }
        })
    }

    /// `rays` converted call by call and traced: what a renderer's wavefront gets.
    fn convert_and_trace<Q: Query<A, M>, S: Stats>(
        &self,
        rays: Rays<'_>,
        out: &mut [Q::Answer],
        stats: &mut S,
    ) {
        let rays = rays.slice(0..out.len());
        count_rays(out.len(), stats);
        self.call(rays.kind, |scene, args| {
            for call in M::calls(rays) {
                let mut record = Q::stage(&rays, call.clone());
                Q::trace(scene, args, &mut record, &mut out[call]);
            }
        })
    }

    fn staged<Q: Query<A, M>>(
        &self,
        rays: Rays<'_>,
        chunks: Vec<Range<usize>>,
    ) -> Box<dyn StagedRays<Q::Answer> + '_> {
        let kind = rays.kind;
        staged_by(
            chunks,
            |range| Self::stage::<Q>(rays.slice(range)),
            move |calls: &mut Vec<(Range<usize>, Q::Record)>, out: &mut [Q::Answer]| {
                self.trace_staged::<Q>(kind, calls, out)
            },
        )
    }
}

impl<A: EmbreeApi, M: Submission<A>> Kernel for EmbreeTracer<A, M> {
    const COUNTS_INTERNALS: bool = false;

    fn intersect_with<S: Stats>(&self, rays: Rays<'_>, hits: &mut [Hit], stats: &mut S) {
        self.convert_and_trace::<Closest, S>(rays, hits, stats)
    }

    fn occluded_with<S: Stats>(&self, rays: Rays<'_>, occluded: &mut [bool], stats: &mut S) {
        self.convert_and_trace::<Occlusion, S>(rays, occluded, stats)
    }

    fn stage_closest(
        &self,
        rays: Rays<'_>,
        chunks: Vec<Range<usize>>,
    ) -> Option<Box<dyn StagedRays<Hit> + '_>> {
        Some(self.staged::<Closest>(rays, chunks))
    }

    fn stage_occlusion(
        &self,
        rays: Rays<'_>,
        chunks: Vec<Range<usize>>,
    ) -> Option<Box<dyn StagedRays<bool> + '_>> {
        Some(self.staged::<Occlusion>(rays, chunks))
    }
}

/// Closest hit or occlusion: the record a submission stages for it and the call that traces it,
/// so staging and tracing are written once for both queries.
trait Query<A: EmbreeApi, M: Submission<A>>: 'static {
    type Record: Send;
    type Answer: Send;
    fn stage(rays: &Rays<'_>, call: Range<usize>) -> Self::Record;
    fn trace(
        scene: &EmbreeScene<A>,
        args: &mut A::Arguments,
        record: &mut Self::Record,
        out: &mut [Self::Answer],
    );
}

struct Closest;
struct Occlusion;

impl<A: EmbreeApi, M: Submission<A>> Query<A, M> for Closest {
    type Record = M::Hits;
    type Answer = Hit;
    #[inline(always)]
    fn stage(rays: &Rays<'_>, call: Range<usize>) -> M::Hits {
        M::stage_hits(rays, call)
    }
    #[inline(always)]
    fn trace(
        scene: &EmbreeScene<A>,
        args: &mut A::Arguments,
        record: &mut M::Hits,
        out: &mut [Hit],
    ) {
        M::intersect(scene, args, record, out)
    }
}

impl<A: EmbreeApi, M: Submission<A>> Query<A, M> for Occlusion {
    type Record = M::Shadows;
    type Answer = bool;
    #[inline(always)]
    fn stage(rays: &Rays<'_>, call: Range<usize>) -> M::Shadows {
        M::stage_shadows(rays, call)
    }
    #[inline(always)]
    fn trace(
        scene: &EmbreeScene<A>,
        args: &mut A::Arguments,
        record: &mut M::Shadows,
        out: &mut [bool],
    ) {
        M::occluded(scene, args, record, out)
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
