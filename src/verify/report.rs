//! Per-ray-kind verification results: disagreement counts by class, distance-error percentiles,
//! the tolerance they are judged against, and their CSV form.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;

use crate::error::{Error, Result};
use crate::geometry::{Hit, RayBatch, RayKind};
use crate::verify::compare::{at_range_end, Agreement, Mismatch, Tie};

/// Pass/fail rule of `raylab verify`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tolerance {
    /// Unexplained disagreements allowed per ray kind.
    pub max_unexplained: u64,
    /// Largest allowed 99th percentile of |t − t_embree| / t_embree over rays hitting the same triangle.
    pub max_distance_error_p99: f64,
}

impl Default for Tolerance {
    fn default() -> Self {
        Tolerance {
            max_unexplained: 0,
            max_distance_error_p99: 1e-4,
        }
    }
}

/// One disagreement, for `disagreements.csv`.
#[derive(Clone, Debug)]
pub struct Disagreement {
    pub index: usize,
    pub pixel: u32,
    pub agreement: Agreement,
    pub tested: Hit,
    pub reference: Hit,
}

#[derive(Clone, Debug)]
pub struct KindReport {
    pub kind: RayKind,
    pub rays: usize,
    pub mismatches: BTreeMap<Mismatch, u64>,
    pub ties: BTreeMap<Tie, u64>,
    pub unexplained: u64,
    /// Relative distance error percentiles (50, 90, 99, 99.9, 100) over same-triangle hits,
    /// except those Embree finds at an end of the ray's interval: a ray starting on the triangle
    /// hit at t = 0 there and 1e-7 here has a relative error of 1e31 that measures nothing.
    pub distance_error: [f64; 5],
    pub disagreements: Vec<Disagreement>,
}

pub const PERCENTILES: [f64; 5] = [50.0, 90.0, 99.0, 99.9, 100.0];

impl KindReport {
    pub fn from_agreements(
        kind: RayKind,
        batch: &RayBatch,
        agreements: &[Agreement],
        tested: &[Hit],
        reference: &[Hit],
    ) -> Self {
        let mut report = KindReport {
            kind,
            rays: batch.len(),
            mismatches: BTreeMap::new(),
            ties: BTreeMap::new(),
            unexplained: 0,
            distance_error: [0.0; 5],
            disagreements: vec![],
        };
        for (i, a) in agreements.iter().enumerate() {
            let mismatch = match *a {
                Agreement::Agree => continue,
                Agreement::Tie(m, tie) => {
                    *report.ties.entry(tie).or_default() += 1;
                    m
                }
                Agreement::Unexplained(m) => {
                    report.unexplained += 1;
                    m
                }
            };
            *report.mismatches.entry(mismatch).or_default() += 1;
            report.disagreements.push(Disagreement {
                index: i,
                pixel: batch.pixel[i],
                agreement: *a,
                tested: tested[i],
                reference: reference[i],
            });
        }
        let mut errors: Vec<f64> = (0..tested.len())
            .filter(|&i| {
                let (a, b) = (&tested[i], &reference[i]);
                a.is_hit() && a.prim == b.prim && !at_range_end(&batch.ray(i), b)
            })
            .map(|i| {
                let (a, b) = (&tested[i], &reference[i]);
                ((a.t - b.t).abs() / b.t.abs().max(f32::MIN_POSITIVE)) as f64
            })
            .collect();
        errors.sort_by(f64::total_cmp);
        if !errors.is_empty() {
            for (slot, p) in report.distance_error.iter_mut().zip(PERCENTILES) {
                let k = ((p / 100.0) * (errors.len() - 1) as f64).round() as usize;
                *slot = errors[k];
            }
        }
        report
    }

    pub fn mismatch(&self, m: Mismatch) -> u64 {
        self.mismatches.get(&m).copied().unwrap_or(0)
    }

    pub fn tie(&self, t: Tie) -> u64 {
        self.ties.get(&t).copied().unwrap_or(0)
    }

    pub fn passes(&self, tol: &Tolerance) -> bool {
        self.unexplained <= tol.max_unexplained
            && self.distance_error[2] <= tol.max_distance_error_p99
    }
}

fn mismatch_name(m: Mismatch) -> &'static str {
    match m {
        Mismatch::HitMiss => "hit_miss",
        Mismatch::Primitive => "primitive",
        Mismatch::Occlusion => "occlusion",
    }
}

fn agreement_name(a: &Agreement) -> String {
    match a {
        Agreement::Agree => "agree".into(),
        Agreement::Tie(m, t) => format!("{}:tie:{}", mismatch_name(*m), t.name()),
        Agreement::Unexplained(m) => format!("{}:unexplained", mismatch_name(*m)),
    }
}

/// Human-readable table, one line per ray kind.
pub fn format_table(reports: &[KindReport], tol: &Tolerance) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "{:<10} {:>9} {:>9} {:>9} {:>9} {:>6} {:>11} {:>10} {:>10}  verdict",
        "kind", "rays", "hit/miss", "prim", "occl", "ties", "unexplained", "err p50", "err p99",
    );
    for r in reports {
        let _ = writeln!(
            s,
            "{:<10} {:>9} {:>9} {:>9} {:>9} {:>6} {:>11} {:>10.2e} {:>10.2e}  {}",
            r.kind.name(),
            r.rays,
            r.mismatch(Mismatch::HitMiss),
            r.mismatch(Mismatch::Primitive),
            r.mismatch(Mismatch::Occlusion),
            r.ties.values().sum::<u64>(),
            r.unexplained,
            r.distance_error[0],
            r.distance_error[2],
            if r.passes(tol) { "ok" } else { "FAIL" }
        );
    }
    s
}

/// Writes `summary.csv` and `disagreements.csv` into `dir`.
pub fn write_csv(dir: &Path, scene: &str, tracer: &str, reports: &[KindReport]) -> Result<()> {
    let fail = |path: &Path, e: csv::Error| Error::runtime(format!("{}: {e}", path.display()));
    let path = dir.join("summary.csv");
    let mut w = csv::Writer::from_path(&path).map_err(|e| fail(&path, e))?;
    let mut header: Vec<String> = [
        "scene",
        "tracer",
        "ray_kind",
        "rays",
        "hit_miss",
        "primitive",
        "occlusion",
    ]
    .map(String::from)
    .to_vec();
    header.extend(Tie::ALL.iter().map(|t| format!("tie_{}", t.name())));
    header.push("unexplained".into());
    header.extend(PERCENTILES.iter().map(|p| format!("distance_error_p{p}")));
    w.write_record(&header).map_err(|e| fail(&path, e))?;
    for r in reports {
        let mut row = vec![
            scene.to_string(),
            tracer.to_string(),
            r.kind.name().to_string(),
            r.rays.to_string(),
            r.mismatch(Mismatch::HitMiss).to_string(),
            r.mismatch(Mismatch::Primitive).to_string(),
            r.mismatch(Mismatch::Occlusion).to_string(),
        ];
        row.extend(Tie::ALL.iter().map(|t| r.tie(*t).to_string()));
        row.push(r.unexplained.to_string());
        row.extend(r.distance_error.iter().map(|e| format!("{e:e}")));
        w.write_record(&row).map_err(|e| fail(&path, e))?;
    }
    w.flush()
        .map_err(|e| Error::runtime(format!("{}: {e}", path.display())))?;

    let path = dir.join("disagreements.csv");
    let mut w = csv::Writer::from_path(&path).map_err(|e| fail(&path, e))?;
    w.write_record([
        "ray_kind",
        "ray",
        "pixel",
        "class",
        "t",
        "prim",
        "t_embree",
        "prim_embree",
    ])
    .map_err(|e| fail(&path, e))?;
    let prim = |h: &Hit| {
        if h.is_hit() {
            h.prim.to_string()
        } else {
            "miss".into()
        }
    };
    for r in reports {
        for d in &r.disagreements {
            w.write_record([
                r.kind.name().to_string(),
                d.index.to_string(),
                d.pixel.to_string(),
                agreement_name(&d.agreement),
                d.tested.t.to_string(),
                prim(&d.tested),
                d.reference.t.to_string(),
                prim(&d.reference),
            ])
            .map_err(|e| fail(&path, e))?;
        }
    }
    w.flush()
        .map_err(|e| Error::runtime(format!("{}: {e}", path.display())))
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;
    use crate::geometry::Ray;

    fn hit(t: f32) -> Hit {
        Hit {
            t,
            prim: 0,
            u: 0.25,
            v: 0.25,
        }
    }

    #[test]
    fn distances_at_the_start_of_the_interval_are_not_relative_errors() {
        // Found with a camera on the room's ceiling: rays leaving it that Embree hits at t = 0
        // (or −0) and a tracer at 1e-7 made the p99 error 4.9e30 and failed every tracer.
        let mut batch = RayBatch::new(RayKind::Diffuse);
        for _ in 0..3 {
            batch.push(Ray::new(Vec3::ZERO, Vec3::Z, 0.0, f32::INFINITY), 0);
        }
        let tested = [hit(1e-7), hit(2.0), hit(1e-7)];
        let reference = [hit(0.0), hit(2.5), hit(-0.0)];
        let report = KindReport::from_agreements(
            RayKind::Diffuse,
            &batch,
            &[Agreement::Agree; 3],
            &tested,
            &reference,
        );
        // Only the middle ray's error counts.
        assert_eq!(report.distance_error, [(0.5f32 / 2.5) as f64; 5]);
        let starts = KindReport::from_agreements(
            RayKind::Diffuse,
            &batch,
            &[Agreement::Agree; 3],
            &[hit(1e-7); 3],
            &[hit(0.0), hit(-0.0), hit(0.0)],
        );
        assert_eq!(starts.distance_error, [0.0; 5]);
        assert!(starts.passes(&Tolerance::default()));
    }
}
