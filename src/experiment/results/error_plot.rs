//! `error_vs_time.png`: distribution ray tracing's or path tracing's image error against its run
//! time, log-log, one line per tracer through its sample counts (each point labelled with its
//! spp). Lower left is better: less error for the time spent.
//!
//! In an experiment run (`write_error_plots`), each group of distribution (or path) workloads that
//! differ only in `spp` (at least two sample counts; for interleaved soft shadows also in filter
//! and retrace, each refinement its own line) gives one plot and its `.csv` per scene, from frame
//! 0's `frame` rows at the widest thread count: time = the fastest frame, trace time = the sum of
//! the fastest passes of its batches, error = the runs.csv `rmse`.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use plotters::prelude::*;

use crate::accel::AccelKind;
use crate::error::Result;
use crate::experiment::record::RunRow;
use crate::render::convergence::{write_error_csv, ErrorPoint};

use crate::experiment::plan::config::{Experiment, RenderWorkload};
use crate::experiment::plan::Plan;
use crate::experiment::results::plots::{
    draw_legend, plot_error, register_font, scene_stem, significant, PlotResult, FONT,
};

/// Tableau colours, one per tracer in name order.
const PALETTE: [RGBColor; 6] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
];

/// Writes `error_vs_time.png` and `.csv` into `dir` for every scene and group of distribution
/// workloads that differ only in their sample count (named `error_vs_time_<scene>_<n>` when
/// there are several). Returns the files written.
pub fn write_error_plots(
    dir: &Path,
    exp: &Experiment,
    plan: &Plan,
    rows: &[RunRow],
) -> Result<Vec<PathBuf>> {
    let threads = exp.threads.iter().copied().max().unwrap_or(1);
    let groups = spp_groups(exp);
    let mut plots = Vec::new();
    for scene in 0..plan.scenes.len() {
        for (g, group) in groups.iter().enumerate() {
            let points = error_points(exp, plan, rows, scene, group, threads);
            plots.push((scene, g, points));
        }
    }
    let mut written = Vec::new();
    let several = plots.len() > 1;
    for (scene, g, points) in plots {
        let stem = match several {
            true => format!("error_vs_time_{}_{}", scene_stem(plan, scene), g + 1),
            false => "error_vs_time".to_string(),
        };
        let title = format!(
            "{}: RMSE vs time per frame ({threads} threads)",
            plan.scenes[scene].name
        );
        let png = dir.join(format!("{stem}.png"));
        plot_error_vs_time(&png, &title, &points)?;
        let csv = dir.join(format!("{stem}.csv"));
        write_error_csv(&csv, &points)?;
        written.extend([png, csv]);
    }
    Ok(written)
}

/// Indices of the distribution workloads, grouped by everything but `spp` (and the refinements of
/// interleaved soft shadows); only groups with at least two sample counts.
fn spp_groups(exp: &Experiment) -> Vec<Vec<usize>> {
    let mut groups: Vec<Vec<usize>> = Vec::new();
    for (r, workload) in exp.renders.iter().enumerate() {
        let RenderWorkload::Distribution(w) = workload else {
            continue;
        };
        if !w.rmse {
            continue;
        }
        let same = |&&i: &&usize| matches!(&exp.renders[i], RenderWorkload::Distribution(v) if v.same_but_spp(w));
        match groups
            .iter_mut()
            .find(|g| g.first().is_some_and(|i| same(&i)))
        {
            Some(group) => group.push(r),
            None => groups.push(vec![r]),
        }
    }
    let spp = |i: &usize| match &exp.renders[*i] {
        RenderWorkload::Distribution(w) => w.settings.spp,
        RenderWorkload::Whitted(_) => 0,
    };
    groups.retain(|g| g.iter().any(|i| spp(i) != spp(&g[0])));
    groups
}

/// One point per tracer instance and workload of `group` on frame 0 of `scene`; the Embree
/// instances are one line, "Embree best": at each sample count the fastest of them (every ratio is
/// against Embree at its best, and twenty configurations would bury the plot).
fn error_points(
    exp: &Experiment,
    plan: &Plan,
    rows: &[RunRow],
    scene: usize,
    group: &[usize],
    threads: usize,
) -> Vec<ErrorPoint> {
    let render_of = |row: &RunRow| {
        let label = row.render.as_deref()?;
        plan.renders.iter().position(|r| r == label)
    };
    // Frame 0 of `scene`, at the widest thread count.
    let here = |row: &&RunRow| {
        row.frame == 0
            && row.threads == threads
            && plan.scene_of(&row.scene, Some(row.triangles)) == Some(scene)
    };
    let mut points = Vec::new();
    for frame in rows.iter().filter(here).filter(|r| r.ray_kind == "frame") {
        let (Some(render), Some(rmse)) = (render_of(frame), frame.rmse) else {
            continue;
        };
        let Some(instance) = plan.instance_of(&frame.tracer, &frame.parameters) else {
            continue;
        };
        let RenderWorkload::Distribution(w) = &exp.renders[render] else {
            continue;
        };
        if !group.contains(&render) {
            continue;
        }
        let trace_seconds = rows
            .iter()
            .filter(here)
            .filter(|r| {
                r.ray_kind != "frame"
                    && render_of(r) == Some(render)
                    && plan.instance_of(&r.tracer, &r.parameters) == Some(instance)
            })
            .map(|r| r.seconds_min)
            .sum();
        // Interleaved soft shadows' refinements are lines of their own ("packet filtered").
        let refinement = w
            .settings
            .soft_shadows
            .map_or(String::new(), |m| m.refinement());
        let instance = &plan.instances[instance];
        let embree = instance.structure.kind == AccelKind::Embree;
        let point = ErrorPoint {
            tracer: match embree {
                true => format!("{EMBREE_BEST_LINE}{refinement}"),
                false => format!("{}{refinement}", instance.label),
            },
            spp: w.settings.spp,
            seconds: frame.seconds_min,
            trace_seconds,
            rays: frame.rays as u64,
            rmse,
        };
        let slower_embree = points
            .iter()
            .position(|p: &ErrorPoint| embree && p.tracer == point.tracer && p.spp == point.spp);
        match slower_embree {
            Some(i) if points[i].seconds <= point.seconds => {}
            Some(i) => points[i] = point,
            None => points.push(point),
        }
    }
    points
}

/// The label of the Embree line.
const EMBREE_BEST_LINE: &str = "Embree best";

/// Draws RMSE against wall-clock seconds per frame for `points` into `path`.
pub fn plot_error_vs_time(path: &Path, title: &str, points: &[ErrorPoint]) -> Result<()> {
    register_font()?;
    draw(path, title, points).map_err(|e| plot_error(path, e))
}

fn draw(path: &Path, title: &str, points: &[ErrorPoint]) -> PlotResult {
    let usable: Vec<&ErrorPoint> = points
        .iter()
        .filter(|p| p.seconds > 0.0 && p.rmse > 0.0)
        .collect();
    if usable.is_empty() {
        return Err("no point with positive time and error to plot".into());
    }
    let range = |f: fn(&ErrorPoint) -> f64| {
        let lo = usable.iter().map(|p| f(p)).fold(f64::INFINITY, f64::min);
        let hi = usable.iter().map(|p| f(p)).fold(0.0, f64::max);
        // Half a decade of room each side for the labels.
        lo / 2.0..hi * 2.0
    };
    let root = BitMapBackend::new(path, (900, 600)).into_drawing_area();
    root.fill(&WHITE)?;
    let mut chart = ChartBuilder::on(&root)
        .caption(title, (FONT, 20))
        .margin(10)
        .x_label_area_size(45)
        .y_label_area_size(70)
        .build_cartesian_2d(
            range(|p| p.seconds).log_scale(),
            range(|p| p.rmse).log_scale(),
        )?;
    chart
        .configure_mesh()
        .x_desc("seconds per frame (wall clock)")
        .y_desc("RMSE against the reference image")
        .label_style((FONT, 14))
        .x_label_formatter(&|x| significant(*x, false))
        .y_label_formatter(&|y| significant(*y, false))
        .draw()?;
    let mut by_tracer: BTreeMap<&str, Vec<&ErrorPoint>> = BTreeMap::new();
    for p in &usable {
        by_tracer.entry(p.tracer.as_str()).or_default().push(p);
    }
    for (i, (tracer, mut line)) in by_tracer.into_iter().enumerate() {
        line.sort_by_key(|p| p.spp);
        let colour = PALETTE[i % PALETTE.len()];
        chart
            .draw_series(LineSeries::new(
                line.iter().map(|p| (p.seconds, p.rmse)),
                colour.stroke_width(2),
            ))?
            .label(tracer)
            .legend(move |(x, y)| PathElement::new([(x, y), (x + 18, y)], colour.stroke_width(2)));
        chart.draw_series(
            line.iter()
                .map(|p| Circle::new((p.seconds, p.rmse), 4, colour.filled())),
        )?;
        chart.draw_series(line.iter().map(|p| {
            Text::new(
                format!(" {} spp", p.spp),
                (p.seconds, p.rmse),
                (FONT, 13).into_font(),
            )
        }))?;
    }
    draw_legend(&mut chart)?;
    root.present()?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn draws_a_png_and_refuses_an_empty_plot() {
        let path = std::env::temp_dir().join(format!("raylab-error-{}.png", std::process::id()));
        let point = |tracer: &str, spp, seconds, rmse| ErrorPoint {
            tracer: tracer.into(),
            spp,
            seconds,
            trace_seconds: seconds / 2.0,
            rays: 0,
            rmse,
        };
        let points = [
            point("reference", 1, 0.01, 0.1),
            point("reference", 16, 0.16, 0.025),
            point("embree8", 1, 0.005, 0.1),
            point("embree8", 16, 0.07, 0.025),
        ];
        plot_error_vs_time(&path, "room", &points).unwrap();
        let png = std::fs::read(&path).unwrap();
        let _ = std::fs::remove_file(&path);
        assert_eq!(&png[1..4], b"PNG");
        assert!(plot_error_vs_time(&path, "room", &[point("x", 1, 0.0, 0.1)]).is_err());
    }
}
