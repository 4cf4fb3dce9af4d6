//! Heat-map PNGs (issue 33): a `CostMap` in false colour (viridis, the perceptually uniform map
//! of matplotlib) beside a colour bar labelled in tests per ray, on a scale the caller picks so
//! several tracers' maps compare.

use std::path::Path;

use plotters::prelude::*;

use crate::error::{Error, Result};
use crate::render::cost_map::CostMap;

use super::plots::{register_font, FONT};

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

/// Width of the colour bar and its labels beside the map.
const BAR_PANEL: u32 = 110;
/// Shortest image: room for the bar's five labels.
const MIN_HEIGHT: u32 = 160;

/// Writes `map` to `path` as a PNG, its per-ray costs from 0 (dark) to `scale_max` (bright;
/// larger values saturate), with a colour bar and `caption` above it.
pub fn save_png(map: &CostMap, scale_max: f64, caption: &str, path: &Path) -> Result<()> {
    if !(scale_max.is_finite() && scale_max > 0.0) {
        return Err(Error::usage(format!(
            "heat map scale maximum must be a number > 0, not {scale_max}"
        )));
    }
    register_font()?;
    let (width, height) = (map.width + BAR_PANEL, map.height.max(MIN_HEIGHT));
    let mut buffer = vec![255u8; width as usize * height as usize * 3];
    draw(map, scale_max, caption, &mut buffer, (width, height))
        .map_err(|e| Error::runtime(format!("{}: cannot draw heat map: {e}", path.display())))?;
    image::save_buffer(path, &buffer, width, height, image::ColorType::Rgb8)
        .map_err(|e| Error::runtime(format!("{}: cannot write PNG: {e}", path.display())))
}

fn draw(
    map: &CostMap,
    scale_max: f64,
    caption: &str,
    buffer: &mut [u8],
    size: (u32, u32),
) -> std::result::Result<(), Box<dyn std::error::Error>> {
    let root = BitMapBackend::with_buffer(buffer, size).into_drawing_area();
    for y in 0..map.height {
        for x in 0..map.width {
            let i = (y * map.width + x) as usize;
            let colour = match map.rays[i] {
                // No ray from this pixel (a shadow map's background): grey, not "zero cost".
                0 => RGBColor(128, 128, 128),
                _ => viridis(map.per_ray(i) / scale_max),
            };
            root.draw_pixel((x as i32, y as i32), &colour)?;
        }
    }
    // The bar: bottom (0) to top (scale_max), with five labels.
    let (left, top, bar_height) = (map.width as i32 + 12, 24, size.1 as i32 - 40);
    for row in 0..bar_height {
        let colour = viridis(1.0 - row as f64 / (bar_height - 1).max(1) as f64);
        root.draw(&Rectangle::new(
            [(left, top + row), (left + 16, top + row + 1)],
            colour.filled(),
        ))?;
    }
    let style = TextStyle::from((FONT, 12).into_font()).color(&BLACK);
    for k in 0..=4 {
        let value = scale_max * k as f64 / 4.0;
        let y = top + ((bar_height - 1) as f64 * (1.0 - k as f64 / 4.0)) as i32 - 6;
        root.draw(&Text::new(
            format!("{value:.1}"),
            (left + 20, y),
            style.clone(),
        ))?;
    }
    root.draw(&Text::new(
        caption.to_string(),
        (left - 8, 4),
        style.clone(),
    ))?;
    root.draw(&Text::new(
        map.cost.unit().to_string(),
        (left - 8, size.1 as i32 - 14),
        style,
    ))?;
    root.present()?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

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
