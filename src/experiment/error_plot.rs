//! `error_vs_time.png`: distribution ray tracing's image error against its run time, log-log, one
//! line per tracer through its sample counts (each point labelled with its spp). Lower left is
//! better: less error for the time spent.

use std::collections::BTreeMap;
use std::path::Path;

use plotters::prelude::*;

use crate::error::{Error, Result};
use crate::render::convergence::ErrorPoint;

use super::plots::register_font;

const FONT: &str = "sans-serif";

/// Tableau colours, one per tracer in name order.
const PALETTE: [RGBColor; 6] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
];

/// Draws RMSE against wall-clock seconds per frame for `points` into `path`.
pub fn plot_error_vs_time(path: &Path, title: &str, points: &[ErrorPoint]) -> Result<()> {
    register_font()?;
    draw(path, title, points)
        .map_err(|e| Error::runtime(format!("cannot draw {}: {e}", path.display())))
}

fn draw(
    path: &Path,
    title: &str,
    points: &[ErrorPoint],
) -> std::result::Result<(), Box<dyn std::error::Error>> {
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
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .label_font((FONT, 14))
        .background_style(WHITE.mix(0.9))
        .border_style(BLACK)
        .draw()?;
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
