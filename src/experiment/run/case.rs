//! A case: one tracer instance on one workload of one frame of one scene, as the runner measured
//! it (its counting pass and its timing at every thread count), and the rows it becomes. The
//! runner's own intermediate: everything after the run reads the rows (`record`).

use crate::experiment::plan::Plan;
use crate::experiment::record::{CheckRow, HistogramRow, Records, RunRow};
use crate::geometry::RayKind;
use crate::render::assembly::BatchKind;
use crate::stats::Event;

use super::passes::{Counted, Timing};
use super::sampled_check::Checked;

/// What a case measured.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Traced {
    /// A batch of one ray kind, traced on its own.
    Batch(RayKind),
    /// One batch of a rendered frame of render workload `render` (an index into `Plan::renders`).
    Render {
        render: usize,
        batch: BatchKind,
        depth: u32,
    },
    /// A whole rendered frame: all its batches plus sampling, shading and packet assembly.
    Frame { render: usize },
    /// The rays of ray file `Plan::ray_files[i]`, closest hit.
    File(usize),
}

impl Traced {
    /// runs.csv's `ray_kind`: the kind, batch or `frame`, or `file:<name>` for a ray file.
    pub fn kind_name(self, plan: &Plan) -> String {
        match self {
            Traced::Batch(kind) => kind.name().to_string(),
            Traced::Render { batch, .. } => batch.name().to_string(),
            Traced::Frame { .. } => "frame".to_string(),
            Traced::File(i) => format!("file:{}", plan.ray_files[i].name),
        }
    }

    /// Bounce depth: camera rays 0, rays leaving their hits 1; none for a whole frame or a ray
    /// file.
    pub fn depth(self) -> Option<u32> {
        match self {
            Traced::Batch(RayKind::Primary) => Some(0),
            Traced::Batch(_) => Some(1),
            Traced::Render { depth, .. } => Some(depth),
            Traced::Frame { .. } | Traced::File(_) => None,
        }
    }

    pub fn render(self) -> Option<usize> {
        match self {
            Traced::Batch(_) | Traced::File(_) => None,
            Traced::Render { render, .. } | Traced::Frame { render } => Some(render),
        }
    }
}

/// One tracer instance on one ray kind (or one batch of a rendered frame, or a whole frame) of one
/// frame of one scene: its counts and its timing at every thread count. One row of runs.csv per
/// timing.
#[derive(Clone, Debug)]
pub struct Case {
    /// Index into `Plan::scenes`.
    pub scene: usize,
    pub triangles: usize,
    pub frame: usize,
    /// Index into `Plan::instances`.
    pub instance: usize,
    pub traced: Traced,
    pub rays: usize,
    /// From the one counting pass (the same at every thread count).
    pub counted: Counted,
    /// False for tracers that count rays only: their box and triangle counts are not measured.
    pub counts_internals: bool,
    /// Seconds to build the instance's structure for this frame; 0 when reused.
    pub build_seconds: f64,
    /// Whether the structure was built this frame (false: reused from frame 0 of a static scene).
    pub built: bool,
    /// The SAH cost of the instance's structure, when it is our BVH.
    pub sah_cost: Option<f64>,
    pub timings: Vec<Timing>,
    /// The generation of the rays the tracer was handed, where the runner generated them once
    /// for every tracer (the soft-shadow query's shadow rays), at every thread count; empty
    /// otherwise.
    pub generation: Vec<Timing>,
    /// A distribution frame's RMSE against its reference image (frame rows only).
    pub rmse: Option<f64>,
    /// An interleaved-soft-shadow frame's share of pixels retraced (frame rows, with retrace).
    pub retraced_share: Option<f64>,
    /// The sampled check against the oracle (ray batches and ray files only).
    pub checked: Option<Checked>,
}

impl Case {
    /// The case's runs.csv rows, one per thread count, without the Embree-best columns (the
    /// results fill them in from the whole run's rows).
    fn run_rows<'a>(&'a self, plan: &'a Plan) -> impl Iterator<Item = RunRow> + 'a {
        let instance = &plan.instances[self.instance];
        let c = &self.counted.counters;
        let internal = move |v: u64| self.counts_internals.then_some(v);
        self.timings.iter().map(move |timing| RunRow {
            experiment: plan.experiment.clone(),
            scene: plan.scenes[self.scene].name.clone(),
            triangles: self.triangles,
            frame: self.frame,
            tracer: instance.tracer.clone(),
            parameters: instance.params.to_string(),
            structure: instance.structure.to_string(),
            resolved: Some(instance.resolved()),
            render: self.traced.render().map(|r| plan.renders[r].to_string()),
            ray_kind: self.traced.kind_name(plan),
            bounce_depth: self.traced.depth(),
            threads: timing.threads,
            rays: self.rays,
            hits: self.counted.hits as u64,
            seconds_min: timing.seconds_min,
            seconds_median: timing.seconds_median,
            generation_seconds: self
                .generation
                .iter()
                .find(|g| g.threads == timing.threads)
                .map(|g| g.seconds_min),
            build_seconds: self.build_seconds,
            built: self.built,
            sah_cost: self.sah_cost,
            counted_rays: c.rays,
            nodes_visited: internal(c.nodes_visited),
            aabb_tests: internal(c.aabb_tests),
            triangle_tests: internal(c.triangle_tests),
            // The counting pass ran once, on the widest pool: the row at its thread count.
            counting_seconds: (timing.threads == self.counted.threads)
                .then_some(self.counted.seconds),
            rmse: self.rmse,
            retraced_share: self.retraced_share,
            events: Event::ALL.iter().map(|&e| internal(c.get(e))).collect(),
            embree_best: None,
            embree_best_build_plus_trace: None,
            baseline_best: None,
        })
    }

    /// Tests per BVH depth, for the tracers that count them, on ray batches and ray files.
    fn histogram_rows<'a>(&'a self, plan: &'a Plan) -> impl Iterator<Item = HistogramRow> + 'a {
        let counted =
            self.counts_internals && matches!(self.traced, Traced::Batch(_) | Traced::File(_));
        let c = &self.counted.counters;
        let depths = match counted {
            true => c.aabb_by_depth.len().max(c.triangle_by_depth.len()),
            false => 0,
        };
        let instance = &plan.instances[self.instance];
        (0..depths).map(move |depth| HistogramRow {
            experiment: plan.experiment.clone(),
            scene: plan.scenes[self.scene].name.clone(),
            frame: self.frame,
            tracer: instance.tracer.clone(),
            parameters: instance.params.to_string(),
            ray_kind: self.traced.kind_name(plan),
            depth,
            aabb_tests: c.aabb_by_depth.get(depth).copied().unwrap_or(0),
            triangle_tests: c.triangle_by_depth.get(depth).copied().unwrap_or(0),
        })
    }

    /// The sampled check's row, for the cases that ran one.
    fn check_row(&self, plan: &Plan) -> Option<CheckRow> {
        let checked = self.checked?;
        let instance = &plan.instances[self.instance];
        Some(CheckRow {
            scene: plan.scenes[self.scene].name.clone(),
            triangles: self.triangles,
            frame: self.frame,
            tracer: instance.tracer.clone(),
            parameters: instance.params.to_string(),
            ray_kind: self.traced.kind_name(plan),
            checked_rays: checked.rays,
            ties: checked.ties,
            unexplained: checked.unexplained,
            ours_right: checked.judged[0],
            ours_wrong: checked.judged[1],
            rounding: checked.judged[2],
            undecided: checked.judged[3],
        })
    }
}

/// The rows of `cases`, in their order.
pub fn records(plan: &Plan, cases: &[Case]) -> Records {
    Records {
        runs: cases.iter().flat_map(|c| c.run_rows(plan)).collect(),
        histograms: cases.iter().flat_map(|c| c.histogram_rows(plan)).collect(),
        checks: cases.iter().filter_map(|c| c.check_row(plan)).collect(),
    }
}
