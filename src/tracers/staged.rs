//! Rays already in a tracer's own layout. A library's user holds rays in the library's layout
//! before calling it (Embree: `RTCRayHitN` packets, `RTCRay` records), so a baseline is timed on
//! rays converted beforehand: `Kernel::stage_closest` / `stage_occlusion` convert a batch outside
//! the timed region, and the timed pass only makes the calls (`StagedRays::trace`).

use std::ops::Range;

use rayon::prelude::*;

/// A batch in a tracer's own layout, cut into the chunks `chunked` cuts it into (`Chunks`).
pub trait StagedRays<T>: Send {
    /// Traces every staged ray once, answer `i` into `out[i]`, chunks spread over the current
    /// rayon pool. The rays are consumed (a call may overwrite them, as Embree's do): stage again
    /// for another pass.
    fn trace(&mut self, out: &mut [T]);
}

/// Per-chunk staged data beside the chunk's range of the batch.
struct Chunks<C> {
    chunks: Vec<(Range<usize>, C)>,
}

impl<C: Send> Chunks<C> {
    /// `stage` of every range, in the current pool.
    fn stage(ranges: Vec<Range<usize>>, stage: impl Fn(Range<usize>) -> C + Sync) -> Self {
        Chunks {
            chunks: ranges
                .into_par_iter()
                .map(|range| (range.clone(), stage(range)))
                .collect(),
        }
    }

    /// `trace` of every chunk with its part of `out`, in the current pool.
    fn trace<T: Send>(&mut self, out: &mut [T], trace: impl Fn(&mut C, &mut [T]) + Sync) {
        let mut rest = out;
        let mut parts = Vec::with_capacity(self.chunks.len());
        for (range, chunk) in &mut self.chunks {
            let (part, tail) = std::mem::take(&mut rest).split_at_mut(range.len());
            rest = tail;
            parts.push((chunk, part));
        }
        parts
            .into_par_iter()
            .for_each(|(chunk, part)| trace(chunk, part));
    }
}

/// A batch staged by a closure per chunk and traced by another: a tracer whose staged data is
/// one value per chunk needs nothing more.
struct StagedBy<C, F> {
    chunks: Chunks<C>,
    trace: F,
}

impl<C: Send, T: Send, F: Fn(&mut C, &mut [T]) + Send + Sync> StagedRays<T> for StagedBy<C, F> {
    fn trace(&mut self, out: &mut [T]) {
        self.chunks.trace(out, &self.trace);
    }
}

/// `ranges` staged by `stage` (in the current pool), each chunk traced by `trace`.
pub fn staged_by<'t, C: Send + 't, T: Send + 't>(
    ranges: Vec<Range<usize>>,
    stage: impl Fn(Range<usize>) -> C + Sync,
    trace: impl Fn(&mut C, &mut [T]) + Send + Sync + 't,
) -> Box<dyn StagedRays<T> + 't> {
    Box::new(StagedBy {
        chunks: Chunks::stage(ranges, stage),
        trace,
    })
}
