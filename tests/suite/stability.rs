//! The numerical stability suite on every case kind, for the from-scratch tracers (each in
//! every configuration its registry entry declares for tests): no leak, no crash, no hang,
//! every ill-formed ray a miss, and no answer the f64 truth calls wrong — slivers and crowded
//! needle fans included: the watertight test redoes in f64 the edge functions that lost more than
//! 4 bits to cancellation (`geometry::triangle::needs_f64`; at 11 bits a handful of sliver rays
//! got their distance wrong, issue 30).

use std::time::Duration;

use raylab::tracers::TracerInfo;
use raylab::verify::stability::{generate, run, CaseKind, Contender, Status};

use crate::common;
use common::smaller_sweep;

/// Every tracer of ours in every configuration its registry entry declares for tests.
#[test]
fn from_scratch_tracers_pass_every_stiff_case() {
    let sweep = smaller_sweep();
    let cases = generate(&sweep);
    let contenders: Vec<Contender> = common::test_configurations(TracerInfo::is_ours)
        .into_iter()
        .map(|(info, p)| Contender::new(format!("{} {p}", info.name), info, p).unwrap())
        .collect();
    let outcomes = run(cases, &contenders, Duration::from_secs(120), &|_, _| {}).unwrap();
    assert!(!outcomes.is_empty());
    for o in &outcomes {
        assert_eq!(o.status, Status::Answered, "{o:?}");
        assert_eq!(o.leaks, 0, "{o:?}");
        assert_eq!((o.missed, o.false_hits), (0, 0), "{o:?}");
        if o.kind == CaseKind::Watertight && !o.variant.contains("crushed") {
            assert!(o.must_hit > 1000, "{o:?}");
        }
    }
    // Every case kind ran, the crowded needle fans among them.
    for kind in CaseKind::ALL {
        assert!(outcomes.iter().any(|o| o.kind == kind), "{kind}");
    }
}
