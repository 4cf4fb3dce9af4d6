//! The README and the reference carry no hand-typed measurement (issue 16): every block of
//! measured numbers is generated — pasted between `<!-- generated: FILE -->` and
//! `<!-- end generated -->` markers from a committed file that is itself regenerated from its
//! run's files — and no other line states a timing, a speed or a ratio.

use std::path::{Path, PathBuf};

use raylab::experiment::results::summary::Summary;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn read(path: &Path) -> String {
    std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// The generated blocks of `text`: (source file, block text), and the text outside them.
fn split_generated(text: &str) -> (Vec<(String, String)>, String) {
    const OPEN: &str = "<!-- generated: ";
    const CLOSE: &str = "<!-- end generated -->";
    let (mut blocks, mut outside, mut rest) = (Vec::new(), String::new(), text);
    while let Some(at) = rest.find(OPEN) {
        outside.push_str(&rest[..at]);
        let after = &rest[at + OPEN.len()..];
        let (source, body) = after
            .split_once(" -->\n")
            .expect("a generated marker ends its line");
        let (block, tail) = body
            .split_once(CLOSE)
            .expect("every generated block is closed");
        blocks.push((source.to_string(), block.to_string()));
        rest = tail;
    }
    outside.push_str(rest);
    (blocks, outside)
}

/// `text` (a generated file in folder `from`) with its relative markdown links made relative to
/// the repository root, where the documents that paste it lie: `](x)` becomes `](from/x)`.
fn rebased(text: &str, from: &Path) -> String {
    let mut out = String::new();
    let mut rest = text;
    while let Some(at) = rest.find("](") {
        let (head, link) = rest.split_at(at + 2);
        out.push_str(head);
        let absolute = ["http:", "https:", "/", "#"]
            .iter()
            .any(|p| link.starts_with(p));
        if !absolute && !from.as_os_str().is_empty() {
            out.push_str(&format!("{}/", from.display()));
        }
        rest = link;
    }
    out.push_str(rest);
    out
}

/// A line stating a measurement: a decimal ratio (0.54×), a time in ms, a speed, a frame rate or
/// a run time. Dimensions (4×4, 1024²) and counts (864 triangles) are not measurements.
fn states_a_measurement(line: &str) -> bool {
    let bytes = line.as_bytes();
    let number_before = |at: usize| {
        let head = line[..at].trim_end();
        head.ends_with(|c: char| c.is_ascii_digit())
    };
    let decimal_before = |at: usize| {
        let head = line[..at].trim_end();
        let digits = head.trim_end_matches(|c: char| c.is_ascii_digit());
        digits.len() < head.len() && digits.ends_with('.')
    };
    let unit_at = |unit: &str, at: usize| {
        let end = at + unit.len();
        line[at..].starts_with(unit) && bytes.get(end).is_none_or(|b| !b.is_ascii_alphanumeric())
    };
    line.char_indices().any(|(at, c)| {
        (c == '×' && decimal_before(at))
            || (["ms", "Mrays/s", "fps"].iter().any(|u| unit_at(u, at)) && number_before(at))
    })
}

#[test]
fn the_measurement_detector_tells_measurements_from_dimensions() {
    for measured in [
        "| room | 0.54× |",
        "took 27.4 ms",
        "31.4 Mrays/s",
        "at 20 fps here",
        "8.8ms",
    ] {
        assert!(states_a_measurement(measured), "{measured}");
    }
    for not in [
        "4×4 packets",
        "1024² pixels",
        "| `room` | 864 (size 3) |",
        "16 × 16",
        "the ms column",
        "5 entry points × 2 contexts",
    ] {
        assert!(!states_a_measurement(not), "{not}");
    }
}

#[test]
fn generated_blocks_equal_their_files_and_nothing_else_is_measured() {
    for doc in ["README.md", "docs/REFERENCE.md"] {
        let text = read(&root().join(doc));
        let (blocks, outside) = split_generated(&text);
        for (source, block) in &blocks {
            let file = read(&root().join(source));
            let from = Path::new(source).parent().unwrap_or(Path::new(""));
            assert_eq!(
                block.trim(),
                rebased(&file, from).trim(),
                "{doc}: the block generated from {source} differs from it: paste it again"
            );
        }
        let measured: Vec<&str> = outside
            .lines()
            .filter(|l| states_a_measurement(l))
            .collect();
        assert!(
            measured.is_empty(),
            "{doc}: hand-typed measurements outside generated blocks: {measured:#?}"
        );
    }
    let readme = read(&root().join("README.md"));
    assert!(
        readme.contains("](results/quick/summary.md)")
            && root().join("results/quick/summary.md").is_file(),
        "the README links the default experiment's summary"
    );
}

/// The README stays an overview (issue 46): at most 200 lines, the details in docs/REFERENCE.md.
#[test]
fn the_readme_is_at_most_200_lines() {
    let lines = read(&root().join("README.md")).lines().count();
    assert!(lines <= 200, "README.md has {lines} lines");
}

/// The committed summary is what `raylab summary` computes from the committed run's files.
#[test]
fn the_committed_summary_regenerates_from_its_run() {
    let dir = root().join("results/quick");
    let summary = Summary::read(&dir).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(
        summary.markdown().trim(),
        read(&dir.join("summary.md")).trim(),
        "results/quick/summary.md: regenerate it with `raylab summary results/quick`"
    );
}
