//! What a run with `heatmaps = [...]` hands from measuring to writing: per scene its shaded
//! image, and per scene × ray kind × tracer the cost maps of the first frame (`render::cost_map`).

use crate::geometry::RayKind;
use crate::render::cost_map::{Cost, CostMap};
use crate::render::image::Image;

/// A figure's panels are at most this many pixels a side: larger images and maps are shrunk by
/// `panel_shrink`, in whole blocks of pixels.
pub const PANEL_SIDE: u32 = 256;

/// Source pixels per panel pixel, along each axis, for a `width × height` image (≥ 1).
pub fn panel_shrink(width: u32, height: u32) -> u32 {
    width.max(height).div_ceil(PANEL_SIDE).max(1)
}

/// One tracer's maps of one scene's ray kind.
pub struct HeatmapPanel {
    pub scene: String,
    pub kind: RayKind,
    /// The tracer instance's label in the plan.
    pub tracer: String,
    /// The map of every cost drawn, shrunk to the figure's panel (`for_figure`); `None` for a
    /// production baseline, which reports no counts.
    pub maps: Option<Vec<CostMap>>,
}

/// `maps` as a figure draws them: only the `costs` asked for, each shrunk to the panel
/// (`CostMap::shrunk` by `panel_shrink`: block sums, so each panel pixel and the mean are what
/// the full map gives). A run holds every panel until its figures are written: at 1024² a full
/// map is 16 MB and a tracer's four of them 64 MB, which a sweep of 40 counting tracers over 6
/// scenes and 2 ray kinds cannot hold in 24 GB; shrunk, a map is 1 MB.
pub fn for_figure(maps: Vec<CostMap>, costs: &[Cost]) -> Vec<CostMap> {
    maps.into_iter()
        .filter(|m| costs.contains(&m.cost))
        .map(|m| {
            let by = panel_shrink(m.width, m.height);
            m.shrunk(by)
        })
        .collect()
}

/// Every panel of a run, with each scene's shaded first frame (ray casting, `render::raycast`).
#[derive(Default)]
pub struct HeatmapSet {
    pub shaded: Vec<(String, Image)>,
    pub panels: Vec<HeatmapPanel>,
}
