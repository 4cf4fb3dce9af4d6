//! What a run with `heatmaps = [...]` hands from measuring to writing: per scene its shaded
//! image, and per scene × ray kind × tracer the cost maps of the first frame (`render::cost_map`).

use crate::geometry::RayKind;
use crate::render::cost_map::CostMap;
use crate::render::image::Image;

/// One tracer's maps of one scene's ray kind.
pub struct HeatmapPanel {
    pub scene: String,
    pub kind: RayKind,
    /// The tracer instance's label in the plan.
    pub tracer: String,
    /// Every cost's map; `None` for a production baseline, which reports no counts.
    pub maps: Option<Vec<CostMap>>,
}

/// Every panel of a run, with each scene's shaded first frame (ray casting, `render::raycast`).
#[derive(Default)]
pub struct HeatmapSet {
    pub shaded: Vec<(String, Image)>,
    pub panels: Vec<HeatmapPanel>,
}
