//! Heat-map PNGs (issue 33): `CostMap`s in false colour (viridis, the perceptually uniform map of
//! matplotlib) side by side with the shaded frame, on one scale with one colour bar labelled in
//! tests per ray, so several tracers' maps compare; a run's figures per scene × ray kind × cost.

use std::path::Path;

use plotters::prelude::*;

use crate::error::{Error, Result};
use crate::render::cost_map::CostMap;
use crate::render::image::Image;

use crate::experiment::record::heatmap_set::{panel_shrink, HeatmapPanel, HeatmapSet};
use crate::geometry::RayKind;
use crate::render::cost_map::Cost;

use super::plots::{file_stem, register_font, FONT};

/// Viridis at 0, 0.1, …, 1 (matplotlib's `viridis` sampled at 11 points); colours in between
/// are interpolated linearly.
const VIRIDIS: [[u8; 3]; 11] = [
    [0x44, 0x01, 0x54],
    [0x48, 0x24, 0x75],
    [0x41, 0x44, 0x87],
    [0x35, 0x5f, 0x8d],
    [0x2a, 0x78, 0x8e],
    [0x21, 0x91, 0x8c],
    [0x22, 0xa8, 0x84],
    [0x44, 0xbf, 0x70],
    [0x7a, 0xd1, 0x51],
    [0xbd, 0xdf, 0x26],
    [0xfd, 0xe7, 0x25],
];

/// The colour of `x` in `[0, 1]` (clamped; NaN is 0).
pub fn viridis(x: f64) -> RGBColor {
    let x = if x.is_nan() { 0.0 } else { x.clamp(0.0, 1.0) };
    let at = x * (VIRIDIS.len() - 1) as f64;
    let i = (at.floor() as usize).min(VIRIDIS.len() - 2);
    let f = at - i as f64;
    let [a, b] = [VIRIDIS[i], VIRIDIS[i + 1]];
    let mix = |c: usize| (a[c] as f64 + (b[c] as f64 - a[c] as f64) * f).round() as u8;
    RGBColor(mix(0), mix(1), mix(2))
}

/// Width of the colour bar and its labels beside the panels.
const BAR_PANEL: u32 = 150;
/// Panels are magnified (whole pixels repeated) to at least this wide, room for their captions
/// (and shrunk to at most `heatmap_set::PANEL_SIDE` a side).
const PANEL_MIN: u32 = 192;
/// Panels per row.
const COLUMNS: usize = 4;
/// Room under each panel for its two caption lines, and between panels.
const CAPTION: u32 = 34;
const GAP: u32 = 8;
/// Shortest image: room for the bar's labels.
const MIN_HEIGHT: u32 = 200;

/// What one panel shows.
pub enum Panel<'a> {
    /// The shaded frame the rays come from.
    Shaded(&'a Image),
    /// A tracer's cost map.
    Map(&'a CostMap),
    /// A tracer that reports no counts (a production baseline).
    NoCounts,
    /// A tracer that traces single rays, on a `lanes` figure: no ray lanes to share.
    SingleRays,
}

/// Writes `panels` (each with its caption) to `path` as one PNG, rows of `COLUMNS`, every map in
/// false colour from 0 (dark) to `scale_max` (bright; larger values saturate) of `cost`'s unit,
/// with one colour bar. Each map's caption line 2 is its mean per ray.
pub fn save_panels(
    path: &Path,
    panels: &[(String, Panel<'_>)],
    unit: &str,
    scale_max: f64,
) -> Result<()> {
    if !(scale_max.is_finite() && scale_max > 0.0) {
        return Err(Error::usage(format!(
            "heat map scale maximum must be a number > 0, not {scale_max}"
        )));
    }
    let Some((w, h)) = panels.iter().find_map(|(_, p)| match p {
        Panel::Shaded(image) => Some((image.width, image.height)),
        Panel::Map(map) => Some((map.width, map.height)),
        Panel::NoCounts | Panel::SingleRays => None,
    }) else {
        return Err(Error::usage(
            "a heat-map figure needs at least one map or image",
        ));
    };
    register_font()?;
    let shrink = panel_shrink(w, h);
    let zoom = PANEL_MIN.div_ceil(w).max(1);
    let layout = Layout {
        panel: (w * zoom / shrink, h * zoom / shrink),
        rows: panels.len().div_ceil(COLUMNS) as u32,
        columns: panels.len().min(COLUMNS) as u32,
    };
    let size = layout.size();
    let mut buffer = vec![255u8; size.0 as usize * size.1 as usize * 3];
    draw(&layout, panels, unit, scale_max, &mut buffer)
        .map_err(|e| Error::runtime(format!("{}: cannot draw heat map: {e}", path.display())))?;
    image::save_buffer(path, &buffer, size.0, size.1, image::ColorType::Rgb8)
        .map_err(|e| Error::runtime(format!("{}: cannot write PNG: {e}", path.display())))
}

/// Where the panels go.
struct Layout {
    /// Every panel's size in pixels: the first image's or map's, shrunk or magnified.
    panel: (u32, u32),
    rows: u32,
    columns: u32,
}

impl Layout {
    fn size(&self) -> (u32, u32) {
        let width = self.columns * (self.panel.0 + GAP) + BAR_PANEL;
        let height = (self.rows * (self.panel.1 + CAPTION + GAP)).max(MIN_HEIGHT);
        (width, height)
    }

    /// The top-left corner of panel `i`.
    fn corner(&self, i: usize) -> (i32, i32) {
        let (column, row) = ((i % COLUMNS) as u32, (i / COLUMNS) as u32);
        (
            (column * (self.panel.0 + GAP)) as i32,
            (row * (self.panel.1 + CAPTION + GAP)) as i32,
        )
    }
}

type Canvas<'b> = DrawingArea<BitMapBackend<'b>, plotters::coord::Shift>;

fn draw(
    layout: &Layout,
    panels: &[(String, Panel<'_>)],
    unit: &str,
    scale_max: f64,
    buffer: &mut [u8],
) -> std::result::Result<(), Box<dyn std::error::Error>> {
    let size = layout.size();
    let root = BitMapBackend::with_buffer(buffer, size).into_drawing_area();
    let style = TextStyle::from((FONT, 12).into_font()).color(&BLACK);
    for (i, (caption, panel)) in panels.iter().enumerate() {
        let (x0, y0) = layout.corner(i);
        let second = match panel {
            Panel::Shaded(image) => {
                draw_shaded(&root, layout, image, (x0, y0))?;
                "shaded".to_string()
            }
            Panel::Map(map) => {
                draw_map(&root, layout, map, scale_max, (x0, y0))?;
                map.cost.caption(map.mean())
            }
            Panel::NoCounts => "no counts: a library's own kernels".to_string(),
            Panel::SingleRays => "single rays: no lanes".to_string(),
        };
        let below = y0 + layout.panel.1 as i32;
        root.draw(&Text::new(caption.clone(), (x0, below + 3), style.clone()))?;
        root.draw(&Text::new(second, (x0, below + 17), style.clone()))?;
    }
    // The bar: bottom (0) to top (scale_max), with five labels.
    let left = (layout.columns * (layout.panel.0 + GAP)) as i32 + 8;
    let (top, bar_height) = (10, size.1 as i32 - 40);
    for row in 0..bar_height {
        let colour = viridis(1.0 - row as f64 / (bar_height - 1).max(1) as f64);
        root.draw(&Rectangle::new(
            [(left, top + row), (left + 16, top + row + 1)],
            colour.filled(),
        ))?;
    }
    for k in 0..=4 {
        let value = scale_max * k as f64 / 4.0;
        let y = top + ((bar_height - 1) as f64 * (1.0 - k as f64 / 4.0)) as i32 - 6;
        // Quarters of a share (0.25) need two decimals; counts of tens, one.
        let text = match scale_max <= 2.0 {
            true => format!("{value:.2}"),
            false => format!("{value:.1}"),
        };
        root.draw(&Text::new(text, (left + 20, y), style.clone()))?;
    }
    root.draw(&Text::new(
        unit.to_string(),
        (left - 4, size.1 as i32 - 22),
        style,
    ))?;
    root.present()?;
    Ok(())
}

/// The pixels, along an axis of a source `len` of them, that pixel `p` of a panel `side` wide
/// shows: a block of them when the source is larger, one pixel (repeated) when it is smaller. A
/// map shrunk for its figure (`heatmap_set::for_figure`) and the image it came from, shrunk here, show
/// the same blocks.
fn source(p: u32, side: u32, len: u32) -> std::ops::Range<u32> {
    if len == 0 || side == 0 {
        return 0..0;
    }
    let at = |p: u32| (p as u64 * len as u64 / side as u64) as u32;
    let start = at(p).min(len - 1);
    start..at(p + 1).clamp(start + 1, len)
}

/// `map` at `corner`, each panel pixel the value of its block of map pixels.
fn draw_map(
    root: &Canvas<'_>,
    layout: &Layout,
    map: &CostMap,
    scale_max: f64,
    corner: (i32, i32),
) -> std::result::Result<(), Box<dyn std::error::Error>> {
    for py in 0..layout.panel.1 {
        for px in 0..layout.panel.0 {
            let (mut total, mut per) = (0u64, 0u64);
            for y in source(py, layout.panel.1, map.height) {
                for x in source(px, layout.panel.0, map.width) {
                    let i = (y * map.width + x) as usize;
                    total += map.total[i];
                    per += map.per[i];
                }
            }
            let colour = match per {
                // No ray (a shadow map's background), or no lane, from here: grey, not zero.
                0 => RGBColor(128, 128, 128),
                _ => viridis(total as f64 / per as f64 / scale_max),
            };
            root.draw_pixel((corner.0 + px as i32, corner.1 + py as i32), &colour)?;
        }
    }
    Ok(())
}

/// `image` at `corner`, auto-exposed as `Image::save_png` does, one image pixel per block.
fn draw_shaded(
    root: &Canvas<'_>,
    layout: &Layout,
    image: &Image,
    corner: (i32, i32),
) -> std::result::Result<(), Box<dyn std::error::Error>> {
    let bytes = image.to_srgb8(image.auto_exposure());
    // One image pixel per block: its middle one.
    let middle = |p: u32, side: u32, len: u32| {
        let block = source(p, side, len);
        (block.start + block.end) / 2
    };
    for py in 0..layout.panel.1 {
        for px in 0..layout.panel.0 {
            let (x, y) = (
                middle(px, layout.panel.0, image.width),
                middle(py, layout.panel.1, image.height),
            );
            let i = 3 * (y * image.width + x) as usize;
            let colour = RGBColor(bytes[i], bytes[i + 1], bytes[i + 2]);
            root.draw_pixel((corner.0 + px as i32, corner.1 + py as i32), &colour)?;
        }
    }
    Ok(())
}

/// The run's figures (`heatmaps = [...]`): one per scene × ray kind × cost of `set`,
/// `heatmap-<scene>[-<size>]-<kind>-<cost>.png`, the shaded frame first, then every tracer that
/// counts in plan order, all on one scale (`Cost::scale`), then one panel for the baselines,
/// which report no counts. On a `lanes` figure a single-ray tracer's panel is blank.
pub fn write_figures(dir: &Path, costs: &[Cost], set: &HeatmapSet) -> Result<()> {
    for shaded in &set.shaded {
        let of_scene: Vec<&HeatmapPanel> = set
            .panels
            .iter()
            .filter(|p| p.scene == shaded.scene)
            .collect();
        let mut kinds: Vec<RayKind> = Vec::new();
        for p in &of_scene {
            if !kinds.contains(&p.kind) {
                kinds.push(p.kind);
            }
        }
        for kind in kinds {
            let tracers: Vec<&&HeatmapPanel> = of_scene.iter().filter(|p| p.kind == kind).collect();
            for &cost in costs {
                // `None` for a baseline; `Some(None)` for a counting tracer without this map.
                let maps: Vec<Option<Option<&CostMap>>> = tracers
                    .iter()
                    .map(|p| {
                        p.maps
                            .as_ref()
                            .map(|maps| maps.iter().find(|m| m.cost == cost))
                    })
                    .collect();
                let scale = cost.scale(maps.iter().flatten().flatten().copied());
                let mut panels = vec![(shaded.name.clone(), Panel::Shaded(&shaded.image))];
                panels.extend(tracers.iter().zip(&maps).filter_map(|(p, map)| {
                    let panel = match map.as_ref()? {
                        Some(map) => Panel::Map(map),
                        None => Panel::SingleRays,
                    };
                    Some((p.tracer.clone(), panel))
                }));
                // The baselines (embree-best alone is 18 of them) share one blank panel.
                let baselines = maps.iter().filter(|m| m.is_none()).count();
                if baselines > 0 {
                    panels.push((format!("{baselines} baseline(s)"), Panel::NoCounts));
                }
                let name = format!(
                    "heatmap-{}-{}-{}.png",
                    file_stem(&shaded.name),
                    kind.name(),
                    cost.name()
                );
                save_panels(&dir.join(name), &panels, cost.unit(), scale)?;
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn panel_pixels_show_blocks_of_a_larger_source_and_repeat_a_smaller_one() {
        // 1024 shrunk to 256: blocks of 4; a map already shrunk to 256: one pixel each.
        assert_eq!(source(3, 256, 1024), 12..16);
        assert_eq!(source(3, 256, 256), 3..4);
        // 64 magnified to 192: each pixel three times.
        assert_eq!(
            [0, 1, 2, 3].map(|p| source(p, 192, 64)),
            [0..1, 0..1, 0..1, 1..2]
        );
        // A source not a multiple of the panel: blocks cover it all, never past its end.
        assert_eq!(source(186, 187, 750), 745..750);
        assert_eq!(source(186, 187, 188), 186..188);
        // Nothing to show: an empty range, not a panic.
        assert_eq!(source(0, 192, 0), 0..0);
    }

    #[test]
    fn viridis_ends_and_middle() {
        assert_eq!(viridis(0.0), RGBColor(0x44, 0x01, 0x54));
        assert_eq!(viridis(1.0), RGBColor(0xfd, 0xe7, 0x25));
        assert_eq!(viridis(0.5), RGBColor(0x21, 0x91, 0x8c));
        assert_eq!(viridis(2.0), viridis(1.0));
        assert_eq!(viridis(f64::NAN), viridis(0.0));
        // Halfway between the first two stops.
        assert_eq!(viridis(0.05), RGBColor(0x46, 0x13, 0x65));
    }
}
