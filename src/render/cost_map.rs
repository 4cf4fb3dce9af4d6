//! Per-pixel traversal cost (issue 33): one counting pass over a wavefront with every count
//! charged to its ray (`stats::RayCosts`), the rays' costs summed into the pixels they descend
//! from. A pixel's value is its cost per ray (box tests, triangle tests or nodes visited, ÷ the
//! rays of the wavefront from that pixel), so maps of different ray kinds read alike; or, for
//! `lanes`, the share of SIMD lanes active in the operations its rays took part in.

use std::str::FromStr;

use crate::error::{Error, Result};
use crate::geometry::RayBatch;
use crate::render::area_light::{LightSampleSets, SoftShadowWork};
use crate::render::distribution::{DrtSettings, Integrator};
use crate::render::path::path_bounce_rays;
use crate::render::rays::{diffuse_rays, primary_rays, shadow_rays};
use crate::render::wavefront::{answer, Answers, Tracing, Work};
use crate::scene::{Frame, Scene};
use crate::stats::{Counters, RayCosts};
use crate::tracers::chunked::{query_rays, trace_hits};
use crate::tracers::Tracer;

/// The ray kinds `wavefront` makes: each ray descends from one pixel.
pub const RAY_KINDS: [&str; 5] = ["primary", "shadow", "diffuse", "soft-shadow", "bounce-N"];

/// A wavefront whose work descends from pixels.
pub enum Wavefront {
    Rays(RayBatch),
    /// The soft-shadow query and its shadow rays (`chunked::query_rays`).
    SoftShadow {
        work: SoftShadowWork,
        rays: RayBatch,
    },
}

impl Wavefront {
    /// What `tracer` is handed, with the pixel of each ray or shading point.
    pub fn work_for(&self, tracer: &dyn Tracer) -> (Work<'_>, Vec<u32>) {
        match self {
            Wavefront::Rays(batch) => (Work::of_batch(batch), batch.pixel.clone()),
            Wavefront::SoftShadow { work, rays } => soft_shadow_work(tracer, work, rays),
        }
    }
}

/// The `width × height` wavefront of `kind` (`RAY_KINDS`) of `frame`: its camera rays, or the
/// shadow rays (one per hit and light) or diffuse bounces (seed 0) of their hits through
/// `tracer`, or their soft-shadow query (`samples` jittered samples per point on the scene's
/// quad light, seed 0), or the `N`-th bounce of a path-traced frame (`bounce-N`, N ≥ 1: one
/// path per pixel, `path::path_bounce_rays`); each ray and point carries its pixel.
pub fn wavefront(
    scene: &Scene,
    frame: &Frame,
    tracer: &dyn Tracer,
    (kind, samples): (&str, u32),
    (width, height): (u32, u32),
) -> Result<Wavefront> {
    let primary = primary_rays(&frame.camera, width, height);
    let hits = || trace_hits(tracer, &primary);
    let rays = match kind {
        "primary" => primary,
        "shadow" => shadow_rays(scene, &frame.mesh, &primary, &hits(), 0),
        "diffuse" => diffuse_rays(&frame.mesh, &primary, &hits(), 0),
        "soft-shadow" => {
            let sets = LightSampleSets::default();
            let hits = hits();
            let work = SoftShadowWork::of_hits(
                scene,
                &frame.mesh,
                (&primary, &hits),
                width,
                (samples, sets),
                0,
            )?
            .ok_or_else(|| {
                Error::usage(format!(
                    "soft-shadow rays need a quad light, and scene {} has none \
                     (the *-area-light scenes have one)",
                    scene.name
                ))
            })?;
            let mut rays = RayBatch::default();
            query_rays(work.query(), &mut rays);
            return Ok(Wavefront::SoftShadow { work, rays });
        }
        other if other.starts_with("bounce-") => {
            let depth = other["bounce-".len()..]
                .parse::<u32>()
                .ok()
                .filter(|&d| d >= 1)
                .ok_or_else(|| {
                    Error::usage(format!(
                        "heat-map rays {other:?}: bounce-N takes a whole number N ≥ 1"
                    ))
                })?;
            let settings = DrtSettings {
                integrator: Integrator::Path,
                width,
                height,
                spp: 1,
                ..DrtSettings::default()
            };
            path_bounce_rays(scene, frame, tracer, &settings, depth, Tracing::Timed)?.0
        }
        other => {
            return Err(Error::usage(format!(
                "unknown heat-map rays {other:?}: one of {}",
                RAY_KINDS.join(", ")
            )))
        }
    };
    Ok(Wavefront::Rays(rays))
}

/// What `tracer` is handed for the soft-shadow workload `work` — the query itself when it
/// answers natively (mft), else its shadow rays `rays` — with the pixel of each point or ray.
pub fn soft_shadow_work<'a>(
    tracer: &dyn Tracer,
    work: &'a SoftShadowWork,
    rays: &'a RayBatch,
) -> (Work<'a>, Vec<u32>) {
    match tracer.answers_visibility_natively() {
        true => (Work::LightVisibility(work.query()), work.pixels.clone()),
        // A shadow ray's `pixel` is its shading point.
        false => (
            Work::Occlusion(rays),
            rays.pixel
                .iter()
                .map(|&p| work.pixels[p as usize])
                .collect(),
        ),
    }
}

/// What a map shows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Cost {
    /// Ray–box tests.
    Box,
    /// Ray–triangle tests.
    Triangle,
    /// BVH nodes or grid cells visited (a visit shared by a packet goes to its rays in turn).
    Nodes,
    /// Active lanes ÷ lanes of the SIMD operations over rays that a pixel's rays took part in
    /// (`stats::RayCosts`): a share, 1 = every lane busy. Single-ray tracers have none.
    Lanes,
}

impl Cost {
    pub const ALL: [Cost; 4] = [Cost::Box, Cost::Triangle, Cost::Nodes, Cost::Lanes];

    pub fn name(self) -> &'static str {
        match self {
            Cost::Box => "box",
            Cost::Triangle => "triangle",
            Cost::Nodes => "nodes",
            Cost::Lanes => "lanes",
        }
    }

    /// The colour bar's unit.
    pub fn unit(self) -> &'static str {
        match self {
            Cost::Box => "box tests per ray",
            Cost::Triangle => "triangle tests per ray",
            Cost::Nodes => "nodes visited per ray",
            Cost::Lanes => "share of lanes active",
        }
    }

    /// A map's caption line: its mean.
    pub fn caption(self, mean: f64) -> String {
        match self {
            Cost::Lanes => format!("mean share {mean:.2}"),
            _ => format!("mean {mean:.2} per ray"),
        }
    }

    /// The top of the colour scale of `maps` drawn together: a share's is 1, a count's the
    /// largest pixel of them (at least 1).
    pub fn scale<'a>(self, maps: impl IntoIterator<Item = &'a CostMap>) -> f64 {
        match self {
            Cost::Lanes => 1.0,
            _ => maps.into_iter().map(CostMap::max).fold(1.0, f64::max),
        }
    }

    /// `costs`' column of this cost and what it is divided by: the ray counts `rays_of`, or
    /// for lanes the lanes of the operations.
    fn of<'a>(self, costs: &'a RayCosts, rays_of: &'a [u64]) -> (&'a [u64], &'a [u64]) {
        match self {
            Cost::Box => (&costs.boxes, rays_of),
            Cost::Triangle => (&costs.triangles, rays_of),
            Cost::Nodes => (&costs.nodes, rays_of),
            Cost::Lanes => (&costs.lanes_active, &costs.lanes),
        }
    }
}

impl FromStr for Cost {
    type Err = Error;
    fn from_str(name: &str) -> Result<Cost> {
        Cost::ALL
            .into_iter()
            .find(|c| c.name() == name)
            .ok_or_else(|| {
                Error::usage(format!(
                    "unknown heat map {name:?}: one of box, triangle, nodes, lanes"
                ))
            })
    }
}

/// One cost per pixel of a `width × height` image.
#[derive(Clone, Debug, PartialEq)]
pub struct CostMap {
    pub cost: Cost,
    pub width: u32,
    pub height: u32,
    /// The cost of the rays from each pixel (lanes: their active lanes), row by row.
    pub total: Vec<u64>,
    /// What `total` is divided by: the rays (a light-visibility query: sample rays) from each
    /// pixel, or for lanes the lanes of their operations. 0: no ray, or no lane, from here.
    pub per: Vec<u64>,
}

impl CostMap {
    /// `costs` (one entry per ray or shading point `i`, from pixel `pixel_of[i]`, standing for
    /// `rays_of[i]` rays) summed per pixel.
    pub fn of(
        costs: &RayCosts,
        cost: Cost,
        (pixel_of, rays_of): (&[u32], &[u64]),
        width: u32,
        height: u32,
    ) -> Self {
        let pixels = width as usize * height as usize;
        let mut map = CostMap {
            cost,
            width,
            height,
            total: vec![0; pixels],
            per: vec![0; pixels],
        };
        let (totals, pers) = cost.of(costs, rays_of);
        for ((&pixel, &per), &c) in pixel_of.iter().zip(pers).zip(totals) {
            map.total[pixel as usize] += c;
            map.per[pixel as usize] += per;
        }
        map
    }

    /// The map over blocks of `by × by` pixels (the last row and column of blocks may be
    /// partial): each block's `total` and `per` the sums of its pixels', so its value is its
    /// rays' cost per ray and the map's `mean` is unchanged.
    pub fn shrunk(self, by: u32) -> CostMap {
        if by <= 1 {
            return self;
        }
        let (width, height) = (self.width.div_ceil(by), self.height.div_ceil(by));
        let mut out = CostMap {
            cost: self.cost,
            width,
            height,
            total: vec![0; width as usize * height as usize],
            per: vec![0; width as usize * height as usize],
        };
        for y in 0..self.height {
            for x in 0..self.width {
                let (from, to) = (
                    (y * self.width + x) as usize,
                    ((y / by) * width + x / by) as usize,
                );
                out.total[to] += self.total[from];
                out.per[to] += self.per[from];
            }
        }
        out
    }

    /// Pixel `i`'s value: cost per ray, or share of lanes active (0 where `per` is 0).
    pub fn value(&self, i: usize) -> f64 {
        match self.per[i] {
            0 => 0.0,
            n => self.total[i] as f64 / n as f64,
        }
    }

    /// The map's value over all its pixels: Σ total ÷ Σ per.
    pub fn mean(&self) -> f64 {
        match self.per.iter().sum::<u64>() {
            0 => 0.0,
            n => self.total.iter().sum::<u64>() as f64 / n as f64,
        }
    }

    /// The largest value of any pixel.
    pub fn max(&self) -> f64 {
        (0..self.total.len())
            .map(|i| self.value(i))
            .fold(0.0, f64::max)
    }
}

/// One counting pass of `tracer` over `work` in the current pool, each count charged to its ray:
/// the pass's counters and its map of each cost (no `lanes` map when the pass made no SIMD
/// operation over rays: a single-ray tracer's). `pixel_of[i]`: the pixel of ray `i` (a batch's
/// `pixel`) or of shading point `i` (a light-visibility query), in a `width × height` image.
pub fn count_per_pixel(
    tracer: &dyn Tracer,
    work: Work<'_>,
    pixel_of: &[u32],
    (width, height): (u32, u32),
) -> Result<(Counters, Vec<CostMap>)> {
    if !tracer.counts_internals() {
        return Err(Error::usage(
            "this tracer (a production baseline) does not report its box and triangle tests: \
             no heat map can be drawn for it",
        ));
    }
    // A shading point stands for its sample rays (those in front of its surface).
    let rays_of: Vec<u64> = match work {
        Work::Closest(batch) | Work::Occlusion(batch) => vec![1; batch.len()],
        Work::LightVisibility(query) => (0..query.len())
            .map(|i| {
                (0..query.samples.per_point())
                    .filter(|&s| query.ray(i, s).is_some())
                    .count() as u64
            })
            .collect(),
    };
    let owners = rays_of.len();
    assert_eq!(owners, pixel_of.len(), "one pixel per ray or shading point");
    if let Some(&pixel) = pixel_of
        .iter()
        .find(|&&p| p as u64 >= width as u64 * height as u64)
    {
        return Err(Error::usage(format!(
            "pixel {pixel} lies outside the {width}×{height} image"
        )));
    }
    let mut counters = Counters::attributing(owners);
    let mut answers = Answers::blank(&work);
    answer(tracer, work, &mut answers, Some(&mut counters));
    let costs = counters.per_ray.take().expect("an attributing pass");
    let maps = Cost::ALL
        .into_iter()
        .filter(|&cost| cost != Cost::Lanes || counters.simd_lanes > 0)
        .map(|cost| CostMap::of(&costs, cost, (pixel_of, &rays_of), width, height))
        .collect();
    Ok((counters, maps))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_shrunk_map_sums_blocks_and_keeps_its_mean() {
        // 5 × 3 pixels, pixel i: total i, per 1 (pixel 7: no ray); blocks of 2 × 2.
        let map = CostMap {
            cost: Cost::Box,
            width: 5,
            height: 3,
            total: (0..15).collect(),
            per: (0..15).map(|i| u64::from(i != 7)).collect(),
        };
        let mean = map.mean();
        let small = map.shrunk(2);
        assert_eq!((small.width, small.height), (3, 2));
        // Row 0: {0,1,5,6} {2,3,7,8} {4,9}; row 1: {10,11} {12,13} {14}.
        assert_eq!(small.total, vec![12, 20, 13, 21, 25, 14]);
        assert_eq!(small.per, vec![4, 3, 2, 2, 2, 1]);
        assert_eq!(small.mean(), mean);
        assert_eq!(small.clone().shrunk(1), small);
    }

    #[test]
    fn rays_sum_into_their_pixels() {
        let mut costs = RayCosts::new(4);
        costs.boxes = vec![3, 5, 1, 0];
        // Rays 0 and 1 from pixel 3, ray 2 from pixel 0, ray 3 from pixel 1; pixel 2 has none.
        // Ray 3 stands for 3 rays (a shading point's samples).
        let map = CostMap::of(&costs, Cost::Box, (&[3, 3, 0, 1], &[1, 1, 1, 3]), 2, 2);
        assert_eq!(map.total, vec![1, 0, 0, 8]);
        assert_eq!(map.per, vec![1, 3, 0, 2]);
        assert_eq!(map.value(3), 4.0);
        assert_eq!(map.value(2), 0.0);
        assert_eq!(map.mean(), 9.0 / 6.0);
        assert_eq!(map.max(), 4.0);
        assert_eq!(Cost::Box.scale([&map]), 4.0);
        assert_eq!("triangle".parse::<Cost>().unwrap(), Cost::Triangle);
        assert!("lane".parse::<Cost>().is_err());
    }

    #[test]
    fn lanes_are_active_over_issued_per_pixel() {
        let mut costs = RayCosts::new(3);
        costs.lanes_active = vec![2, 6, 0];
        costs.lanes = vec![4, 8, 0];
        // Rays 0 and 1 from pixel 0, ray 2 (in no SIMD operation) from pixel 1.
        let map = CostMap::of(&costs, Cost::Lanes, (&[0, 0, 1], &[1, 1, 1]), 2, 1);
        assert_eq!((&map.total[..], &map.per[..]), (&[8, 0][..], &[12, 0][..]));
        assert_eq!(map.value(0), 8.0 / 12.0);
        assert_eq!(Cost::Lanes.scale([&map]), 1.0, "a share, whatever the map");
        assert_eq!("lanes".parse::<Cost>().unwrap(), Cost::Lanes);
    }
}
