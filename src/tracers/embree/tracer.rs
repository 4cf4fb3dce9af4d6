//! The Embree baseline as a `Kernel`: one tracer type over a committed `EmbreeScene`, generic
//! over how rays are handed to Embree (`Submission`: one at a time, packets of 4/8/16, streams).

use std::fmt;
use std::marker::PhantomData;
use std::str::FromStr;
use std::sync::Arc;

use super::denormals::FlushDenormals;
use crate::accel::embree::ffi::{self, RTCIntersectContext, RTCIntersectContextFlags};
use crate::accel::embree::EmbreeScene;
use crate::error::Result;
use crate::geometry::{Hit, Rays};
use crate::params::Params;
use crate::stats::Stats;
use crate::tracers::Kernel;

/// One way of calling Embree's intersect/occluded functions on a chunk of rays.
pub trait Submission: 'static {
    fn intersect(
        scene: &EmbreeScene,
        context: &mut RTCIntersectContext,
        rays: Rays<'_>,
        hits: &mut [Hit],
    );
    fn occluded(
        scene: &EmbreeScene,
        context: &mut RTCIntersectContext,
        rays: Rays<'_>,
        occluded: &mut [bool],
    );
}

/// The intersect context's hint (tracer parameter `context`): whether the rays of a call are
/// coherent. Embree's default (`rtcInitIntersectContext`) is incoherent.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Coherence {
    Coherent,
    #[default]
    Incoherent,
}

impl Coherence {
    pub const PARAMS: &'static [&'static str] = &["context"];

    pub fn from_params(p: &Params) -> Result<Self> {
        p.get_or("context", Coherence::default())
    }

    fn flags(self) -> RTCIntersectContextFlags {
        match self {
            Coherence::Coherent => RTCIntersectContextFlags::RTC_INTERSECT_CONTEXT_FLAG_COHERENT,
            Coherence::Incoherent => {
                RTCIntersectContextFlags::RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT
            }
        }
    }
}

impl FromStr for Coherence {
    type Err = ();
    fn from_str(s: &str) -> std::result::Result<Self, ()> {
        match s {
            "coherent" => Ok(Coherence::Coherent),
            "incoherent" => Ok(Coherence::Incoherent),
            _ => Err(()),
        }
    }
}

impl fmt::Display for Coherence {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Coherence::Coherent => "coherent",
            Coherence::Incoherent => "incoherent",
        })
    }
}

pub struct EmbreeTracer<M: Submission> {
    scene: Arc<EmbreeScene>,
    coherence: Coherence,
    submission: PhantomData<fn() -> M>,
}

impl<M: Submission> EmbreeTracer<M> {
    pub fn new(scene: Arc<EmbreeScene>, coherence: Coherence) -> Self {
        EmbreeTracer {
            scene,
            coherence,
            submission: PhantomData,
        }
    }

    /// A tracer over `scene` reading the tracer parameter `context`.
    pub fn from_params(scene: &Arc<EmbreeScene>, params: &Params) -> Result<Self> {
        Ok(Self::new(scene.clone(), Coherence::from_params(params)?))
    }

    /// Runs one Embree call sequence the way Embree asks: FTZ/DAZ on for its duration only, and a
    /// fresh intersect context.
    #[inline]
    fn call<R>(&self, f: impl FnOnce(&EmbreeScene, &mut RTCIntersectContext) -> R) -> R {
        let _denormals = FlushDenormals::new();
        let mut context = ffi::intersect_context(self.coherence.flags());
        f(&self.scene, &mut context)
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

impl<M: Submission> Kernel for EmbreeTracer<M> {
    const COUNTS_INTERNALS: bool = false;

    fn intersect_with<S: Stats>(&self, rays: Rays<'_>, hits: &mut [Hit], stats: &mut S) {
        let rays = rays.slice(0..hits.len());
        count_rays(hits.len(), stats);
        self.call(|scene, context| M::intersect(scene, context, rays, hits));
    }

    fn occluded_with<S: Stats>(&self, rays: Rays<'_>, occluded: &mut [bool], stats: &mut S) {
        let rays = rays.slice(0..occluded.len());
        count_rays(occluded.len(), stats);
        self.call(|scene, context| M::occluded(scene, context, rays, occluded));
    }
}
