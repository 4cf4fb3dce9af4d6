//! Adding a tracer is one registry entry and no test edit: the suites that check every tracer —
//! agreement with Embree, the light-visibility bits, the fast tests and the stability suite —
//! iterate `TRACERS` and name no tracer, and every entry declares the configurations they check it
//! in (`TracerInfo::test_configs`), its defaults first.

use std::path::Path;

use raylab::tracers::registry::{ALIASES, EMBREE4_TRACERS, TINYBVH_TRACERS};
use raylab::tracers::TRACERS;

/// The suites the registry drives.
const REGISTRY_DRIVEN: &[&str] = &[
    "embree_agreement.rs",
    "visibility.rs",
    "fast_tests.rs",
    "stability.rs",
];

/// Every string literal of `text` outside `//` comments (no escapes inside: none of these files
/// has a tracer name with one).
fn string_literals(text: &str) -> Vec<(usize, String)> {
    let mut found = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let code = line.split("//").next().unwrap_or("");
        let parts: Vec<&str> = code.split('"').collect();
        for literal in parts.iter().skip(1).step_by(2) {
            found.push((i + 1, literal.to_string()));
        }
    }
    found
}

/// Every name a tracer is known by, in this build or another.
fn tracer_names() -> Vec<&'static str> {
    let mut names: Vec<&str> = TRACERS.iter().map(|t| t.name).collect();
    names.extend(ALIASES.iter().map(|(alias, _)| *alias));
    names.extend(EMBREE4_TRACERS.iter().chain(TINYBVH_TRACERS));
    names
}

/// Where the suites in `files` (under tests/suite) name a tracer.
fn named_tracers(files: &[&str]) -> Vec<String> {
    let suite = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/suite");
    let names = tracer_names();
    let mut found = Vec::new();
    for file in files {
        let text = std::fs::read_to_string(suite.join(file)).unwrap();
        for (line, literal) in string_literals(&text) {
            if names.contains(&literal.as_str()) {
                found.push(format!("{file}:{line}: \"{literal}\""));
            }
        }
    }
    found
}

#[test]
fn the_cross_tracer_suites_name_no_tracer() {
    let found = named_tracers(REGISTRY_DRIVEN);
    assert!(
        found.is_empty(),
        "a suite the registry drives names a tracer:\n{}",
        found.join("\n")
    );
    // The check can fail: the family suites name their tracers.
    assert!(!named_tracers(&["packet.rs", "mft.rs", "tinybvh.rs"]).is_empty());
}

#[test]
fn every_entry_declares_test_configurations_that_parse_defaults_first() {
    for info in TRACERS {
        let configs = info.test_params();
        assert!(
            !configs.is_empty(),
            "{} declares no test configuration",
            info.name
        );
        assert!(configs[0].0.is_empty(), "{}: defaults first", info.name);
        for params in &configs {
            assert!(info.config(params).is_ok(), "{} {params}", info.name);
        }
        let distinct: std::collections::BTreeSet<String> =
            configs.iter().map(|p| p.to_string()).collect();
        assert_eq!(
            distinct.len(),
            configs.len(),
            "{}: a repeated configuration",
            info.name
        );
    }
}
