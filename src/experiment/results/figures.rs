//! Line figures, drawn: each `[[figures]]` of an experiment (declared and checked in
//! `plan::figure_spec`) over the rows of its data file, into the results directory.

use std::path::Path;

use plotters::prelude::*;

use crate::error::Result;
use crate::experiment::plan::figure_spec::{FigureSpec, Line};
use crate::experiment::record::selection::{distinct, Filter, Measure, Row};

use super::plots::{draw_legend, plot_error, register_font, significant, PlotResult, FONT};

impl FigureSpec {
    /// The lines to draw over the rows of its data file; x values that are not numbers are skipped.
    pub fn lines(&self, rows: &[Row]) -> Vec<Line> {
        let series: Vec<Option<String>> = match &self.series {
            Some(field) => distinct(rows, &self.filter, field)
                .into_iter()
                .map(Some)
                .collect(),
            None => vec![None],
        };
        let metrics = self.y.list();
        let mut lines = Vec::new();
        for value in &series {
            let filter = match (&self.series, value) {
                (Some(field), Some(v)) => self
                    .filter
                    .and(&Filter([(field.clone(), vec![v.clone()])].into())),
                _ => self.filter.clone(),
            };
            for metric in &metrics {
                let measure = Measure {
                    metric: metric.to_string(),
                    within_frame: self.within_frame,
                    frames: self.frames,
                    scale: self.scale,
                };
                let mut points: Vec<(f64, f64)> = distinct(rows, &filter, &self.x)
                    .iter()
                    .filter_map(|x| {
                        let at_x = filter.and(&Filter([(self.x.clone(), vec![x.clone()])].into()));
                        let y = measure.of(rows, &at_x)?;
                        let y = if self.reciprocal { 1.0 / y } else { y };
                        Some((x.parse::<f64>().ok()?, y))
                    })
                    .collect();
                points.sort_by(|a, b| a.0.total_cmp(&b.0));
                if self.normalise {
                    let best = points.iter().map(|p| p.1).fold(0.0, f64::max);
                    if best > 0.0 {
                        points.iter_mut().for_each(|p| p.1 /= best);
                    }
                }
                let label = match (value, metrics.len()) {
                    (Some(v), 1) => series_label(self.series.as_deref(), v),
                    (Some(v), _) => {
                        format!("{metric}, {}", series_label(self.series.as_deref(), v))
                    }
                    (None, _) => metric.to_string(),
                };
                if !points.is_empty() {
                    lines.push((label, points));
                }
            }
        }
        lines
    }

    /// Draws the figure into `dir`.
    pub fn draw(&self, dir: &Path, rows: &[Row]) -> Result<()> {
        register_font()?;
        let path = dir.join(&self.file);
        self.draw_lines(&path, &self.lines(rows))
            .map_err(|e| plot_error(&path, e))
    }

    fn draw_lines(&self, path: &Path, lines: &[Line]) -> PlotResult {
        let axis = |v: f64, log: bool| if log { v.max(1e-12).log10() } else { v };
        let points = || lines.iter().flat_map(|l| l.1.iter());
        let range = |values: Vec<f64>, log: bool| {
            let lo = values.iter().copied().fold(f64::INFINITY, f64::min);
            let hi = values.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            match (lo.is_finite(), log) {
                (false, _) => 0.0..1.0,
                (true, true) => lo - 0.1..hi + 0.1,
                (true, false) => lo.min(0.0)..(hi * 1.1).max(lo + 1e-9),
            }
        };
        let xs = range(
            points().map(|p| axis(p.0, self.log_x)).collect(),
            self.log_x,
        );
        let ys = range(
            points().map(|p| axis(p.1, self.log_y)).collect(),
            self.log_y,
        );
        let root = BitMapBackend::new(path, (1000, 650)).into_drawing_area();
        root.fill(&WHITE)?;
        let mut chart = ChartBuilder::on(&root)
            .caption(&self.title, (FONT, 20))
            .margin(12)
            .x_label_area_size(45)
            .y_label_area_size(75)
            .build_cartesian_2d(xs, ys)?;
        // Log axes are drawn in log10 units: label them with the value itself.
        let tick = |v: &f64, log: bool| significant(if log { 10f64.powf(*v) } else { *v }, true);
        chart
            .configure_mesh()
            .x_desc(self.x_label.clone().unwrap_or(self.x.clone()))
            .y_desc(self.y_label.clone().unwrap_or(self.y.list().join(", ")))
            .x_label_formatter(&|v| tick(v, self.log_x))
            .y_label_formatter(&|v| tick(v, self.log_y))
            .label_style((FONT, 14))
            .axis_desc_style((FONT, 15))
            .draw()?;
        for (i, (label, line)) in lines.iter().enumerate() {
            let colour = Palette99::pick(i).to_rgba();
            let at = |p: &(f64, f64)| (axis(p.0, self.log_x), axis(p.1, self.log_y));
            chart
                .draw_series(LineSeries::new(line.iter().map(at), colour.stroke_width(2)))?
                .label(label.clone())
                .legend(move |(x, y)| {
                    PathElement::new([(x, y), (x + 16, y)], colour.stroke_width(2))
                });
            chart.draw_series(line.iter().map(|p| Circle::new(at(p), 4, colour.filled())))?;
        }
        draw_legend(&mut chart)?;
        root.present()?;
        Ok(())
    }
}

fn series_label(field: Option<&str>, value: &str) -> String {
    match field.and_then(|f| f.strip_prefix("param:")) {
        Some(key) => format!("{key}={value}"),
        None => value.to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::experiment::plan::figure_spec::{DataFile, Metrics};

    fn figure(text: &str) -> FigureSpec {
        toml::from_str(text).unwrap()
    }

    #[test]
    fn histogram_figures_read_histograms_csv_columns() {
        let spec = figure(
            "data = \"histograms\"\nfile = \"f.png\"\ntitle = \"t\"\nx = \"depth\"\n\
             y = \"aabb_tests\"\nseries = \"param:traversal\"\nwhere = { ray_kind = \"primary\" }\n",
        );
        assert_eq!(spec.data.file_name(), "histograms.csv");
        spec.check().unwrap();
        // Rows as histograms.csv writes them: two traversals, depths 0 and 1, and a reflection
        // row the filter drops.
        let rows: Vec<Row> = [
            ("ranged", "primary", "0", "10"),
            ("ranged", "primary", "1", "30"),
            ("partition", "primary", "0", "20"),
            ("partition", "primary", "1", "5"),
            ("partition", "reflection", "0", "99"),
        ]
        .iter()
        .map(|(traversal, kind, depth, aabb)| {
            [
                ("scene", "s"),
                ("frame", "0"),
                ("parameters", &format!("packet=16;traversal={traversal}")),
                ("ray_kind", kind),
                ("depth", depth),
                ("aabb_tests", aabb),
            ]
            .iter()
            .map(|(k, v)| (k.to_string(), v.to_string()))
            .collect()
        })
        .collect();
        assert_eq!(
            spec.lines(&rows),
            vec![
                (
                    "traversal=ranged".to_string(),
                    vec![(0.0, 10.0), (1.0, 30.0)]
                ),
                (
                    "traversal=partition".to_string(),
                    vec![(0.0, 20.0), (1.0, 5.0)]
                ),
            ]
        );
        // A runs.csv column is not a histograms.csv column, and the other way round.
        let mut bad = spec.clone();
        bad.y = Metrics::One("seconds_min".into());
        assert!(bad.check().is_err());
        let mut runs = spec;
        runs.data = DataFile::Runs;
        assert!(runs.check().is_err());
    }
}
