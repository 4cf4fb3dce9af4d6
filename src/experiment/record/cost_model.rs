//! What a tracer's unit operations cost on the machine that ran it, fitted over the run's own rows
//! (the cost model of issue 44): a regression, not a calibrated kernel.
//!
//! Per tracer configuration (tracer, parameters, structure and threads) and ray kind (whole
//! rendered frames are the kind `frame`), every row's fastest pass is modelled as the sum, over
//! the operations the row counts, of count × unit cost: rays, ray–box tests, ray–triangle tests,
//! frustum–box tests, grid cells visited, grid slices stepped, shading points. The unit costs are
//! the non-negative least-squares fit of the rows' relative errors, so a short batch weighs as
//! much as a long one. A unit cost is the operation's whole average price in its traversal,
//! memory traffic included: a BVH's node fetches and stack work fall on its box tests
//! (`nodes_visited` is priced only where no box test is counted, a grid's cells). The ray kind is
//! part of the group because an operation costs more on incoherent rays: fitted per configuration
//! alone, the committed runs' rows were missed by more. The traced batches of the kinds that have
//! too few rows apart (one frame of a few workloads) are fitted together, per configuration.
//! `cost_fit_error`, the rms relative residual, says how well the sum explains each row's time.
//!
//! A priced row gains, per operation its model has, `ns_per_<op>` and `<op>_seconds` (count ×
//! unit cost: the part of the row's time the model gives the operation), and `cost_fit_error`.

use super::selection::{field_value, Row};

/// A counted operation the model prices.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Operation {
    /// The runs.csv count.
    pub count: &'static str,
    /// In the derived column names: `ns_per_<name>`, `<name>_seconds`.
    pub name: &'static str,
    /// For a reader.
    pub label: &'static str,
}

const fn op(count: &'static str, name: &'static str, label: &'static str) -> Operation {
    Operation { count, name, label }
}

pub const OPERATIONS: [Operation; 7] = [
    op("rays", "ray", "ray"),
    op("aabb_tests", "box_test", "box test"),
    op("triangle_tests", "triangle_test", "triangle test"),
    op("frustum_box_tests", "frustum_test", "frustum–box test"),
    op("nodes_visited", "cell_visit", "grid cell visit"),
    op("slices_stepped", "slice", "grid slice"),
    op("shade_lanes_active", "shading_point", "shading point"),
];

/// The rms relative residual of a row's group's fit.
pub const FIT_ERROR: &str = "cost_fit_error";

/// The columns a priced row may gain.
pub fn columns() -> Vec<String> {
    let per_op = OPERATIONS
        .iter()
        .flat_map(|o| [format!("ns_per_{}", o.name), format!("{}_seconds", o.name)]);
    per_op.chain([FIT_ERROR.to_string()]).collect()
}

/// The rows one model is fitted over.
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub struct Group {
    pub tracer: String,
    pub parameters: String,
    pub structure: String,
    pub threads: String,
    /// The ray kinds fitted together: one, or a configuration's traced batches whose kinds have
    /// too few rows apart (`frame`: whole rendered frames, shading and assembly included, is
    /// always alone).
    pub ray_kinds: Vec<String>,
}

impl Group {
    fn of(row: &Row) -> Group {
        Group {
            tracer: field_value(row, "tracer"),
            parameters: field_value(row, "parameters"),
            structure: field_value(row, "structure"),
            threads: field_value(row, "threads"),
            ray_kinds: vec![field_value(row, "ray_kind")],
        }
    }

    fn same_configuration(&self, other: &Group) -> bool {
        (
            &self.tracer,
            &self.parameters,
            &self.structure,
            &self.threads,
        ) == (
            &other.tracer,
            &other.parameters,
            &other.structure,
            &other.threads,
        )
    }

    fn holds(&self, row: &Row) -> bool {
        let of_row = Group::of(row);
        self.same_configuration(&of_row) && self.ray_kinds.contains(&of_row.ray_kinds[0])
    }
}

/// One group's fitted unit costs.
#[derive(Clone, Debug, PartialEq)]
pub struct Fit {
    pub group: Group,
    /// The rows fitted over.
    pub rows: usize,
    /// (operation, seconds per operation), in `OPERATIONS` order; an operation the fit priced at
    /// zero is listed with 0.
    pub costs: Vec<(Operation, f64)>,
    /// rms of (model − measured) / measured over the rows.
    pub error: f64,
}

/// The fit of every group of `rows` that counts its operations and has at least two rows more
/// than its model has costs (distinct rows: frames repeating one row add nothing), in first-seen
/// order: each configuration's ray kinds apart, then, together, the traced batches of the kinds
/// that could not be fitted apart.
pub fn fits(rows: &[Row]) -> Vec<Fit> {
    let apart: Vec<Fit> = grouped(rows.iter(), Group::of)
        .into_iter()
        .filter_map(|(group, members)| fit(group, &members))
        .collect();
    let left = rows.iter().filter(|r| {
        !apart.iter().any(|f| f.group.holds(r)) && field_value(r, "ray_kind") != "frame"
    });
    let pooled = grouped(left, |r| Group {
        ray_kinds: Vec::new(),
        ..Group::of(r)
    });
    let together = pooled.into_iter().filter_map(|(mut group, members)| {
        for row in &members {
            let kind = field_value(row, "ray_kind");
            if !group.ray_kinds.contains(&kind) {
                group.ray_kinds.push(kind);
            }
        }
        fit(group, &members)
    });
    apart
        .into_iter()
        .chain(together.collect::<Vec<_>>())
        .collect()
}

/// `rows` by `key`, in first-seen order.
fn grouped<'a>(
    rows: impl Iterator<Item = &'a Row>,
    key: impl Fn(&Row) -> Group,
) -> Vec<(Group, Vec<&'a Row>)> {
    let mut groups: Vec<(Group, Vec<&Row>)> = Vec::new();
    for row in rows {
        let group = key(row);
        match groups.iter_mut().find(|(g, _)| *g == group) {
            Some((_, members)) => members.push(row),
            None => groups.push((group, vec![row])),
        }
    }
    groups
}

fn number(row: &Row, field: &str) -> Option<f64> {
    field_value(row, field)
        .parse::<f64>()
        .ok()
        .filter(|x| x.is_finite())
}

fn fit(group: Group, members: &[&Row]) -> Option<Fit> {
    let has_boxes = members
        .iter()
        .any(|r| number(r, "aabb_tests").is_some_and(|n| n > 0.0));
    let ops: Vec<Operation> = OPERATIONS
        .into_iter()
        .filter(|o| !(o.count == "nodes_visited" && has_boxes))
        .filter(|o| {
            members
                .iter()
                .any(|r| number(r, o.count).is_some_and(|n| n > 0.0))
        })
        .collect();
    // Rows with a time and every count: (counts, seconds).
    let mut data: Vec<(Vec<f64>, f64)> = members
        .iter()
        .filter_map(|r| {
            let seconds = number(r, "seconds_min").filter(|s| *s > 0.0)?;
            let counts: Option<Vec<f64>> = ops.iter().map(|o| number(r, o.count)).collect();
            Some((counts?, seconds))
        })
        .collect();
    let distinct = {
        let mut counts: Vec<&Vec<f64>> = data.iter().map(|(c, _)| c).collect();
        counts.sort_by(|a, b| a.partial_cmp(b).unwrap_or(std::cmp::Ordering::Equal));
        counts.dedup();
        counts.len()
    };
    if ops.is_empty() || !ops.iter().any(|o| o.count != "rays") || distinct < ops.len() + 2 {
        return None;
    }
    // Relative errors: divide each row by its time.
    for (counts, seconds) in &mut data {
        counts.iter_mut().for_each(|c| *c /= *seconds);
        *seconds = 1.0;
    }
    let costs = non_negative_least_squares(&data, ops.len())?;
    let residual = |(counts, one): &(Vec<f64>, f64)| {
        counts.iter().zip(&costs).map(|(c, x)| c * x).sum::<f64>() - one
    };
    let error = (data.iter().map(|d| residual(d).powi(2)).sum::<f64>() / data.len() as f64).sqrt();
    Some(Fit {
        group,
        rows: data.len(),
        costs: ops.into_iter().zip(costs).collect(),
        error,
    })
}

/// The x ≥ 0 minimising Σ (a·x − b)² over `data` = [(a, b)]: the unconstrained least-squares
/// solution of the support with the smallest residual among those whose solution is
/// non-negative (the Karush–Kuhn–Tucker point; with at most 7 unknowns, every support is tried).
/// `None` when every support is singular.
fn non_negative_least_squares(data: &[(Vec<f64>, f64)], n: usize) -> Option<Vec<f64>> {
    let mut best: Option<(f64, Vec<f64>)> = None;
    for support in 1u32..(1 << n) {
        let columns: Vec<usize> = (0..n).filter(|j| support >> j & 1 == 1).collect();
        let Some(solution) = least_squares(data, &columns) else {
            continue;
        };
        if solution.iter().any(|x| *x < 0.0) {
            continue;
        }
        let mut x = vec![0.0; n];
        columns.iter().zip(&solution).for_each(|(&j, &v)| x[j] = v);
        let residual: f64 = data
            .iter()
            .map(|(a, b)| (a.iter().zip(&x).map(|(a, x)| a * x).sum::<f64>() - b).powi(2))
            .sum();
        if best.as_ref().is_none_or(|(r, _)| residual < *r) {
            best = Some((residual, x));
        }
    }
    best.map(|(_, x)| x)
}

/// Least squares over the `columns` of `data`'s rows, by the normal equations on columns scaled
/// to unit length (Gauss–Jordan with partial pivoting); `None` when they are (nearly) dependent.
fn least_squares(data: &[(Vec<f64>, f64)], columns: &[usize]) -> Option<Vec<f64>> {
    let k = columns.len();
    let norm: Vec<f64> = columns
        .iter()
        .map(|&j| data.iter().map(|(a, _)| a[j] * a[j]).sum::<f64>().sqrt())
        .collect();
    if norm.contains(&0.0) {
        return None;
    }
    let scaled = |a: &[f64], i: usize| a[columns[i]] / norm[i];
    let mut m: Vec<Vec<f64>> = (0..k)
        .map(|r| {
            let mut line: Vec<f64> = (0..k)
                .map(|c| data.iter().map(|(a, _)| scaled(a, r) * scaled(a, c)).sum())
                .collect();
            line.push(data.iter().map(|(a, b)| scaled(a, r) * b).sum());
            line
        })
        .collect();
    for c in 0..k {
        let pivot = (c..k).max_by(|&a, &b| m[a][c].abs().total_cmp(&m[b][c].abs()))?;
        m.swap(c, pivot);
        if m[c][c].abs() < 1e-10 {
            return None;
        }
        let pivot_line = m[c].clone();
        for (_, line) in m.iter_mut().enumerate().filter(|(r, _)| *r != c) {
            let f = line[c] / pivot_line[c];
            line.iter_mut()
                .zip(&pivot_line)
                .skip(c)
                .for_each(|(x, p)| *x -= f * p);
        }
    }
    Some((0..k).map(|i| m[i][k] / m[i][i] / norm[i]).collect())
}

/// `rows` with the columns of their group's fit (rows of a group without a fit unchanged).
pub fn priced(rows: &[Row], fits: &[Fit]) -> Vec<Row> {
    rows.iter()
        .map(|row| {
            let mut row = row.clone();
            if let Some(fit) = fits.iter().find(|f| f.group.holds(&row)) {
                for (o, cost) in &fit.costs {
                    let count = number(&row, o.count).unwrap_or(0.0);
                    row.insert(format!("ns_per_{}", o.name), (cost * 1e9).to_string());
                    row.insert(format!("{}_seconds", o.name), (count * cost).to_string());
                }
                row.insert(FIT_ERROR.to_string(), fit.error.to_string());
            }
            row
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::experiment::record::selection::row;

    /// A batch row of `tracer` with its counts and time.
    fn batch(tracer: &str, rays: f64, boxes: f64, triangles: f64, seconds: f64) -> Row {
        let (rays, boxes, triangles, seconds) = (
            rays.to_string(),
            boxes.to_string(),
            triangles.to_string(),
            seconds.to_string(),
        );
        row(&[
            ("tracer", tracer),
            ("parameters", "packet=4"),
            ("threads", "1"),
            ("ray_kind", "primary"),
            ("rays", &rays),
            ("aabb_tests", &boxes),
            ("triangle_tests", &triangles),
            ("seconds_min", &seconds),
        ])
    }

    /// Times made from known costs (10 ns a ray, 1 ns a box test, 4 ns a triangle test).
    fn exact_rows() -> Vec<Row> {
        [
            (1e6, 3e7, 4e6),
            (1e6, 5e7, 2e6),
            (2e6, 4e7, 9e6),
            (4e6, 9e7, 1e7),
            (3e6, 2e7, 5e6),
        ]
        .iter()
        .map(|&(r, b, t)| batch("packet", r, b, t, (10.0 * r + b + 4.0 * t) * 1e-9))
        .collect()
    }

    #[test]
    fn costs_made_exactly_are_found_and_price_every_row() {
        let rows = exact_rows();
        let fits = fits(&rows);
        assert_eq!(fits.len(), 1);
        let ns: Vec<(&str, f64)> = fits[0]
            .costs
            .iter()
            .map(|(o, c)| (o.name, c * 1e9))
            .collect();
        let expected = [("ray", 10.0), ("box_test", 1.0), ("triangle_test", 4.0)];
        for ((name, got), (want_name, want)) in ns.iter().zip(expected) {
            assert_eq!(*name, want_name);
            assert!((got - want).abs() < 1e-6, "{name}: {got} ns, not {want}");
        }
        assert!(fits[0].error < 1e-9);
        let priced = priced(&rows, &fits);
        // Row 0: 3e7 box tests at 1 ns = 0.03 s of its 0.056 s.
        let boxes: f64 = priced[0]["box_test_seconds"].parse().unwrap();
        assert!((boxes - 0.03).abs() < 1e-9, "{boxes}");
        let parts: f64 = ["ray_seconds", "box_test_seconds", "triangle_test_seconds"]
            .iter()
            .map(|c| priced[0][*c].parse::<f64>().unwrap())
            .sum();
        let total: f64 = priced[0]["seconds_min"].parse().unwrap();
        assert!((parts - total).abs() < 1e-12);
    }

    #[test]
    fn a_cost_the_data_would_make_negative_is_zero_and_the_rest_refit() {
        // Time = 2 ns a box test less 5 ns a ray, made non-negative only by dropping the rays.
        let rows: Vec<Row> = [(1e6, 3e7), (2e6, 5e7), (1e6, 6e7), (3e6, 7e7), (2e6, 2e7)]
            .iter()
            .map(|&(r, b)| batch("packet", r, b, 0.0, (2.0 * b - 5.0 * r) * 1e-9))
            .collect();
        let fit = &fits(&rows)[0];
        let ray = fit.costs.iter().find(|(o, _)| o.name == "ray").unwrap().1;
        let boxes = fit
            .costs
            .iter()
            .find(|(o, _)| o.name == "box_test")
            .unwrap()
            .1;
        assert_eq!(ray, 0.0);
        assert!(boxes > 0.0 && fit.error > 0.0);
        assert!(fit.costs.iter().all(|(o, _)| o.name != "triangle_test"));
    }

    #[test]
    fn groups_without_counts_or_with_too_few_distinct_rows_get_no_fit() {
        let mut rows = exact_rows();
        rows.truncate(4);
        // Four rows for three costs: one row of residual is too little to judge the model by.
        assert!(fits(&rows).is_empty());
        // A row repeated (a static scene's frames) counts once.
        let mut repeated = exact_rows();
        repeated[1] = repeated[0].clone();
        assert!(fits(&repeated).is_empty());
        // Embree counts nothing.
        let embree: Vec<Row> = (1..6)
            .map(|i| {
                row(&[
                    ("tracer", "embree4-8"),
                    ("rays", &i.to_string()),
                    ("seconds_min", "0.1"),
                ])
            })
            .collect();
        assert!(fits(&embree).is_empty());
        assert_eq!(priced(&embree, &[])[0], embree[0]);
    }

    #[test]
    fn kinds_with_too_few_rows_apart_are_fitted_together() {
        // Five primary rows fit alone; three shadow and two reflection rows only together.
        let mut rows = exact_rows();
        let mut other = |kind: &str, r: f64, b: f64, t: f64| {
            let mut row = batch("packet", r, b, t, (10.0 * r + b + 4.0 * t) * 1e-9);
            row.insert("ray_kind".into(), kind.into());
            rows.push(row);
        };
        other("shadow", 1e6, 2e7, 1e6);
        other("shadow", 2e6, 7e7, 3e6);
        other("shadow", 4e6, 5e7, 2e6);
        other("reflection", 3e6, 3e7, 8e6);
        other("reflection", 1e6, 6e7, 2e6);
        let fits = fits(&rows);
        let kinds: Vec<&[String]> = fits.iter().map(|f| &f.group.ray_kinds[..]).collect();
        assert_eq!(
            kinds,
            [
                &["primary".to_string()][..],
                &["shadow".into(), "reflection".into()]
            ]
        );
        assert!(fits[1].error < 1e-9);
        let priced = priced(&rows, &fits);
        assert!(priced.iter().all(|r| r.contains_key(FIT_ERROR)));
    }

    #[test]
    fn grids_price_their_cell_visits_and_frames_fit_apart_from_batches() {
        let grid = |r: f64, cells: f64, t: f64, kind: &str| {
            let s = ((5.0 * r + 3.0 * cells + 2.0 * t) * 1e-9).to_string();
            let (r, cells, t) = (r.to_string(), cells.to_string(), t.to_string());
            row(&[
                ("tracer", "grid-dda"),
                ("ray_kind", kind),
                ("rays", &r),
                ("nodes_visited", &cells),
                ("triangle_tests", &t),
                ("seconds_min", &s),
            ])
        };
        let mut rows: Vec<Row> = [
            (1e6, 8e6, 3e6),
            (1e6, 2e7, 2e6),
            (3e6, 9e6, 9e6),
            (2e6, 3e7, 1e6),
            (4e6, 1e7, 2e6),
        ]
        .iter()
        .map(|&(r, c, t)| grid(r, c, t, "primary"))
        .collect();
        rows.push(grid(1e6, 1e6, 1e6, "frame"));
        let fits = fits(&rows);
        assert_eq!(fits.len(), 1, "five batch rows fit; one frame row does not");
        let cell = fits[0]
            .costs
            .iter()
            .find(|(o, _)| o.name == "cell_visit")
            .unwrap()
            .1;
        assert!((cell * 1e9 - 3.0).abs() < 1e-6);
        assert!(!priced(&rows, &fits)[5].contains_key(FIT_ERROR));
    }
}
