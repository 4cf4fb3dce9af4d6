//! PNG plots of a run: throughput per scene (horizontal bars of Mrays/s, grouped by tracer
//! instance, one colour per ray kind, one panel per thread count), and, per scene and counting
//! tracer, the AABB and triangle tests per ray at each BVH depth, one row of panels per ray kind.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use plotters::coord::ranged1d::SegmentValue;
use plotters::prelude::*;
use plotters::style::FontStyle;

use crate::error::{Error, Result};
use crate::geometry::RayKind;

use crate::experiment::plan::Plan;
use crate::experiment::record::run_row::mrays_per_s;
use crate::experiment::record::{HistogramRow, RunRow};

const FONT_PATH: &str = "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf";
pub const FONT: &str = "sans-serif";

pub(super) type PlotResult = std::result::Result<(), Box<dyn std::error::Error>>;

/// The legend every plot of a run draws: upper right, on a white box.
pub(super) fn draw_legend<'a, DB, CT>(chart: &mut ChartContext<'a, DB, CT>) -> PlotResult
where
    DB: DrawingBackend + 'a,
    DB::ErrorType: 'static,
    CT: CoordTranslate,
{
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .label_font((FONT, 14))
        .background_style(WHITE.mix(0.9))
        .border_style(BLACK)
        .draw()?;
    Ok(())
}

/// plotters draws text only with a registered font (its `ab_glyph` backend has none built in):
/// DejaVu Sans, read once per process and kept for its lifetime.
pub fn register_font() -> Result<()> {
    static REGISTERED: OnceLock<std::result::Result<(), String>> = OnceLock::new();
    REGISTERED
        .get_or_init(|| {
            let bytes = std::fs::read(FONT_PATH).map_err(|e| {
                format!("cannot read the plot font {FONT_PATH} ({e}); install the Debian package fonts-dejavu-core")
            })?;
            plotters::style::register_font(FONT, FontStyle::Normal, Box::leak(bytes.into_boxed_slice()))
                .map_err(|_| format!("{FONT_PATH} is not a usable TrueType font"))
        })
        .clone()
        .map_err(Error::runtime)
}

/// Tableau colours, one per ray kind.
fn kind_colour(kind: RayKind) -> RGBColor {
    match kind {
        RayKind::Primary => RGBColor(31, 119, 180),
        RayKind::Shadow => RGBColor(255, 127, 14),
        RayKind::Diffuse => RGBColor(44, 160, 44),
        RayKind::Reflection => RGBColor(214, 39, 40),
        RayKind::Refraction => RGBColor(148, 103, 189),
        RayKind::SoftShadow => RGBColor(140, 86, 75),
    }
}

/// Letters, digits, `-`, `_` and `.` pass; everything else becomes `_`.
pub(super) fn file_stem(label: &str) -> String {
    label
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || "-_.".contains(c) {
                c
            } else {
                '_'
            }
        })
        .collect()
}

pub(super) fn scene_stem(plan: &Plan, scene: usize) -> String {
    let s = &plan.scenes[scene];
    match s.size {
        Some(size) => file_stem(&format!("{}-{size}", s.name)),
        None => file_stem(&s.name),
    }
}

/// Draws every plot of the run into `dir`; returns the files written.
pub fn write_plots(
    dir: &Path,
    plan: &Plan,
    rows: &[RunRow],
    histograms: &[HistogramRow],
) -> Result<Vec<PathBuf>> {
    register_font()?;
    let mut written = Vec::new();
    // Plots of the ray batches; a scene with render workloads only has none.
    for scene in (0..plan.scenes.len()).filter(|&s| !plan.scenes[s].ray_kinds.is_empty()) {
        let path = dir.join(format!("throughput_{}.png", scene_stem(plan, scene)));
        throughput(&path, plan, scene, rows).map_err(|e| plot_error(&path, e))?;
        written.push(path);
        for (i, instance) in plan
            .instances
            .iter()
            .enumerate()
            .filter(|(_, inst)| inst.counts_internals)
        {
            let path = dir.join(format!(
                "depths_{}_{}.png",
                scene_stem(plan, scene),
                file_stem(&instance.label)
            ));
            depth_histograms(&path, plan, scene, i, rows, histograms)
                .map_err(|e| plot_error(&path, e))?;
            written.push(path);
        }
    }
    Ok(written)
}

/// The error of a plot that could not be drawn.
pub(super) fn plot_error(path: &Path, e: Box<dyn std::error::Error>) -> Error {
    Error::runtime(format!("cannot draw {}: {e}", path.display()))
}

/// `v` to 3 significant digits for an axis label (not the f64 round-off of the tick value);
/// `trim` drops trailing zeros (`0.4` rather than `0.400`). Magnitudes below 1e-12 are treated
/// as 1e-12, so zero gets a label instead of an overflowing digit count.
pub(super) fn significant(v: f64, trim: bool) -> String {
    let decimals = (2 - v.abs().max(1e-12).log10().floor() as i32).max(0) as usize;
    let text = format!("{v:.decimals$}");
    match trim && text.contains('.') {
        true => text.trim_end_matches('0').trim_end_matches('.').to_string(),
        false => text,
    }
}

/// Whether `row` measured instance `instance` of `plan` on a batch of `kind` of scene `scene`
/// (not a batch of a rendered frame).
fn is_batch(plan: &Plan, row: &RunRow, scene: usize, instance: usize, kind: RayKind) -> bool {
    row.render.is_none()
        && row.ray_kind == kind.name()
        && plan.scene_of(&row.scene, Some(row.triangles)) == Some(scene)
        && plan.instance_of(&row.tracer, &row.parameters) == Some(instance)
}

/// Mrays/s over all frames (total rays / total fastest-pass seconds) of one instance, ray kind
/// and thread count.
fn throughput_over_frames(
    plan: &Plan,
    rows: &[RunRow],
    scene: usize,
    instance: usize,
    kind: RayKind,
    threads: usize,
) -> Option<f64> {
    let (rays, seconds) = rows
        .iter()
        .filter(|r| r.threads == threads && is_batch(plan, r, scene, instance, kind))
        .fold((0, 0.0), |(n, s), r| (n + r.rays, s + r.seconds_min));
    mrays_per_s(rays, seconds)
}

fn throughput(path: &Path, plan: &Plan, scene: usize, runs: &[RunRow]) -> PlotResult {
    let kinds = &plan.scenes[scene].ray_kinds;
    let group = kinds.len() + 1; // bars of one instance, then a blank row
    let rows = (plan.instances.len() * group - 1) as i32;
    // Row 0 (the first instance's first kind) at the top, as the plan lists them.
    let y_of = |row: usize| rows - 1 - row as i32;
    let row_px = 22;
    let panel_height = 90 + rows as u32 * row_px;
    let label_px = plan
        .instances
        .iter()
        .map(|i| i.label.len())
        .max()
        .unwrap_or(0) as u32
        * 8
        + 16;
    let root = BitMapBackend::new(path, (1000, panel_height * plan.threads.len() as u32))
        .into_drawing_area();
    root.fill(&WHITE)?;
    let s = &plan.scenes[scene];
    for (panel, &threads) in root
        .split_evenly((plan.threads.len(), 1))
        .iter()
        .zip(&plan.threads)
    {
        let values: Vec<(i32, RayKind, f64)> = (0..plan.instances.len())
            .flat_map(|i| {
                kinds.iter().enumerate().map(move |(k, &kind)| {
                    let mrays =
                        throughput_over_frames(plan, runs, scene, i, kind, threads).unwrap_or(0.0);
                    (y_of(i * group + k), kind, mrays)
                })
            })
            .collect();
        let max = values.iter().map(|v| v.2).fold(0.0, f64::max).max(1e-3);
        let mut chart = ChartBuilder::on(panel)
            .caption(
                format!(
                    "{} ({} triangles): throughput, {threads} thread(s)",
                    s.name, s.triangles
                ),
                (FONT, 20),
            )
            .margin(10)
            .x_label_area_size(40)
            .y_label_area_size(label_px)
            // Room on the right for the value labels and the legend.
            .build_cartesian_2d(0.0..max * 1.4, (0..rows).into_segmented())?;
        let labels: Vec<&str> = plan.instances.iter().map(|i| i.label.as_str()).collect();
        let middle = (kinds.len() - 1) / 2;
        chart
            .configure_mesh()
            .disable_y_mesh()
            .y_labels(rows as usize + 1)
            .y_label_formatter(&|v| match v {
                // The instance name beside the middle bar of its group.
                SegmentValue::CenterOf(y) if (0..rows).contains(y) => {
                    let row = (rows - 1 - y) as usize;
                    match row % group == middle {
                        true => labels[row / group].to_string(),
                        false => String::new(),
                    }
                }
                _ => String::new(),
            })
            .x_desc("Mrays/s (fastest pass, all frames)")
            .label_style((FONT, 14))
            .draw()?;
        for &kind in kinds {
            let colour = kind_colour(kind);
            chart
                .draw_series(
                    values
                        .iter()
                        .filter(|v| v.1 == kind)
                        .map(|&(row, _, mrays)| {
                            let mut bar = Rectangle::new(
                                [
                                    (0.0, SegmentValue::Exact(row)),
                                    (mrays, SegmentValue::Exact(row + 1)),
                                ],
                                colour.filled(),
                            );
                            bar.set_margin(2, 2, 0, 0);
                            bar
                        }),
                )?
                .label(kind.name())
                .legend(move |(x, y)| {
                    Rectangle::new([(x, y - 6), (x + 12, y + 6)], colour.filled())
                });
            chart.draw_series(
                values
                    .iter()
                    .filter(|v| v.1 == kind)
                    .map(|&(row, _, mrays)| {
                        Text::new(
                            format!(" {mrays:.2}"),
                            (mrays, SegmentValue::CenterOf(row)),
                            (FONT, 13).into_font(),
                        )
                    }),
            )?;
        }
        draw_legend(&mut chart)?;
    }
    root.present()?;
    Ok(())
}

/// Per-depth AABB and triangle tests per ray of one instance and ray kind, over all frames.
fn tests_per_ray_by_depth(
    plan: &Plan,
    (rows, histograms): (&[RunRow], &[HistogramRow]),
    scene: usize,
    instance: usize,
    kind: RayKind,
) -> (Vec<f64>, Vec<f64>) {
    // The counting pass ran once per batch: its rays are on each thread count's row.
    let rays: u64 = rows
        .iter()
        .filter(|r| r.threads == plan.threads[0] && is_batch(plan, r, scene, instance, kind))
        .map(|r| r.counted_rays)
        .sum();
    let mut sums: BTreeMap<bool, Vec<u64>> = BTreeMap::new();
    for h in histograms.iter().filter(|h| {
        h.ray_kind == kind.name()
            && plan.scene_of(&h.scene, None) == Some(scene)
            && plan.instance_of(&h.tracer, &h.parameters) == Some(instance)
    }) {
        for (is_aabb, count) in [(true, h.aabb_tests), (false, h.triangle_tests)] {
            let sum = sums.entry(is_aabb).or_default();
            if sum.len() <= h.depth {
                sum.resize(h.depth + 1, 0);
            }
            sum[h.depth] += count;
        }
    }
    let per_ray = |v: Option<&Vec<u64>>| -> Vec<f64> {
        v.map_or(Vec::new(), |v| {
            v.iter()
                .map(|&n| {
                    if rays > 0 {
                        n as f64 / rays as f64
                    } else {
                        0.0
                    }
                })
                .collect()
        })
    };
    (per_ray(sums.get(&true)), per_ray(sums.get(&false)))
}

fn depth_histograms(
    path: &Path,
    plan: &Plan,
    scene: usize,
    instance: usize,
    rows: &[RunRow],
    histograms: &[HistogramRow],
) -> PlotResult {
    let kinds = &plan.scenes[scene].ray_kinds;
    let root = BitMapBackend::new(path, (1100, 300 * kinds.len() as u32)).into_drawing_area();
    root.fill(&WHITE)?;
    let s = &plan.scenes[scene];
    let label = &plan.instances[instance].label;
    let panels = root.split_evenly((kinds.len(), 2));
    let per_kind: Vec<(Vec<f64>, Vec<f64>)> = kinds
        .iter()
        .map(|&kind| tests_per_ray_by_depth(plan, (rows, histograms), scene, instance, kind))
        .collect();
    // One depth axis for every panel, so the panels line up.
    let depths = per_kind
        .iter()
        .map(|(a, t)| a.len().max(t.len()))
        .max()
        .unwrap_or(0)
        .max(1) as u32;
    for (k, (&kind, (aabb, triangles))) in kinds.iter().zip(&per_kind).enumerate() {
        for (col, (what, values)) in [("AABB tests", aabb), ("triangle tests", triangles)]
            .into_iter()
            .enumerate()
        {
            let max = values.iter().copied().fold(0.0, f64::max).max(1e-3);
            let mut chart = ChartBuilder::on(&panels[k * 2 + col])
                .caption(
                    format!("{label} on {}: {} rays, {what}", s.name, kind.name()),
                    (FONT, 16),
                )
                .margin(8)
                .x_label_area_size(36)
                .y_label_area_size(72)
                .build_cartesian_2d((0..depths).into_segmented(), 0.0..max * 1.1)?;
            chart
                .configure_mesh()
                .disable_x_mesh()
                .x_desc("BVH depth")
                .y_desc("tests per ray")
                .x_label_formatter(&|v| match v {
                    SegmentValue::CenterOf(d) | SegmentValue::Exact(d) => d.to_string(),
                    SegmentValue::Last => String::new(),
                })
                .label_style((FONT, 13))
                .axis_desc_style((FONT, 14))
                .draw()?;
            chart.draw_series(
                Histogram::vertical(&chart)
                    .style(kind_colour(kind).filled())
                    .margin(1)
                    .data(values.iter().enumerate().map(|(d, &v)| (d as u32, v))),
            )?;
        }
    }
    root.present()?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn axis_labels_have_three_significant_digits() {
        assert_eq!(significant(0.0100000000001, false), "0.0100");
        assert_eq!(significant(0.4, false), "0.400");
        assert_eq!(significant(3.0, false), "3.00");
        assert_eq!(significant(250.0, false), "250");
        assert_eq!(significant(12345.6, false), "12346");
        assert_eq!(significant(0.4, true), "0.4");
        assert_eq!(significant(3.0, true), "3");
        assert_eq!(significant(250.0, true), "250");
        assert_eq!(significant(0.012345, true), "0.0123");
    }
}
