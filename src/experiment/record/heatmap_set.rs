//! What a run with `heatmaps = [...]` hands from measuring to writing: per scene its shaded
//! image, and per scene × ray kind × tracer the cost maps of the first frame (`render::cost_map`).
//! A shard of a sweep writes it to disk (`heatmap_file`) for `raylab merge` to join.

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
#[derive(Clone, Debug, PartialEq)]
pub struct HeatmapPanel {
    /// The scene's index in the plan.
    pub scene: usize,
    pub kind: RayKind,
    /// The tracer instance's index in the plan, and its label there.
    pub instance: usize,
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

/// A scene's shaded first frame, the figures' first panel.
#[derive(Clone, Debug, PartialEq)]
pub struct ShadedFrame {
    /// The scene's index in the plan, and its name in figure captions and file names
    /// (`<name>[-<size>]`).
    pub scene: usize,
    pub name: String,
    pub image: Image,
}

/// Every panel of a run, with each scene's shaded first frame (ray casting, `render::raycast`).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct HeatmapSet {
    pub shaded: Vec<ShadedFrame>,
    pub panels: Vec<HeatmapPanel>,
}

impl HeatmapSet {
    /// The sets of a sweep's shards as one, in the order an unsharded run makes it: scenes in
    /// plan order, each scene's panels by tracer instance, each instance's ray kinds in the
    /// order measured. Every shard measuring a scene shades it; one frame is kept.
    pub fn joined(sets: Vec<HeatmapSet>) -> HeatmapSet {
        let mut joined = HeatmapSet::default();
        for set in sets {
            joined.shaded.extend(set.shaded);
            joined.panels.extend(set.panels);
        }
        joined.shaded.sort_by_key(|s| s.scene);
        joined.shaded.dedup_by_key(|s| s.scene);
        // Stable: an instance's kinds keep their order.
        joined.panels.sort_by_key(|p| (p.scene, p.instance));
        joined
    }
}
