//! The data flows one way (README, "Architecture"): a module of `src/` may import from its own
//! layer and the layers below it, never from a layer above. This test reads every `crate::…`
//! path in `src/` (use lines, brace groups over several lines, paths in code) and fails, naming
//! the file, line and import, when one runs back up.

use std::path::{Path, PathBuf};

/// Top to bottom; modules on one line are peers and may import each other.
const LAYERS: &[&[&str]] = &[
    &["experiment", "verify"],
    &["render"],
    &["tracers"],
    &["accel"],
    &["scene"],
    &["lanes", "geometry", "stats", "test_util"],
];

/// Modules every layer may use: errors, seeded randomness, the parameter map, the memory budget,
/// and (in unit tests) buffers against a guard page.
const UTILITIES: &[&str] = &["error", "memory", "random", "params", "guard_page"];

fn layer(module: &str) -> Option<usize> {
    LAYERS.iter().position(|peers| peers.contains(&module))
}

/// The text of a line without its `//` comment (a `//` inside a string literal is kept).
fn code_of(line: &str) -> &str {
    let mut in_string = false;
    let bytes = line.as_bytes();
    for i in 0..bytes.len() {
        match bytes[i] {
            b'"' if i == 0 || bytes[i - 1] != b'\\' => in_string = !in_string,
            b'/' if !in_string && bytes.get(i + 1) == Some(&b'/') => return &line[..i],
            _ => {}
        }
    }
    line
}

/// Every top-level module named after `crate::` in `text`, with its 1-based line: `crate::a::b`
/// gives `a`; `crate::{a::b, c}` gives `a` and `c`, wherever the group's items stand.
fn crate_imports(text: &str) -> Vec<(usize, String)> {
    let code: Vec<&str> = text.lines().map(code_of).collect();
    let joined = code.join("\n");
    let line_at = |pos: usize| joined[..pos].matches('\n').count() + 1;
    let ident = |s: &str| -> String {
        s.chars()
            .take_while(|c| c.is_alphanumeric() || *c == '_')
            .collect()
    };
    let mut found = Vec::new();
    for (pos, _) in joined.match_indices("crate::") {
        let preceded_by_ident = joined[..pos]
            .chars()
            .next_back()
            .is_some_and(|c| c.is_alphanumeric() || c == '_');
        if preceded_by_ident {
            continue; // e.g. `raylab_crate::`
        }
        let rest = &joined[pos + "crate::".len()..];
        if let Some(group) = rest.strip_prefix('{') {
            let group_start = pos + "crate::{".len();
            // Items at the group's top level: split on commas outside nested braces.
            let (mut depth, mut start) = (0usize, 0usize);
            let mut item = |start: usize, end: usize| {
                let text = &group[start..end];
                let trimmed = text.trim_start();
                let name = ident(trimmed);
                if !name.is_empty() && name != "self" {
                    let at = group_start + start + (text.len() - trimmed.len());
                    found.push((line_at(at), name));
                }
            };
            for (i, c) in group.char_indices() {
                match c {
                    '{' => depth += 1,
                    '}' if depth == 0 => {
                        item(start, i);
                        break;
                    }
                    '}' => depth -= 1,
                    ',' if depth == 0 => {
                        item(start, i);
                        start = i + 1;
                    }
                    _ => {}
                }
            }
        } else {
            let name = ident(rest);
            if !name.is_empty() {
                found.push((line_at(pos), name));
            }
        }
    }
    found
}

/// The imports of `module`'s file (`text`, shown as `file`) that run up the layers.
fn violations(file: &str, module: &str, text: &str) -> Vec<String> {
    let Some(own) = layer(module) else {
        return Vec::new();
    };
    crate_imports(text)
        .into_iter()
        .filter(|(_, target)| !UTILITIES.contains(&target.as_str()))
        .filter(|(_, target)| layer(target).is_some_and(|l| l < own))
        .map(|(line, target)| format!("{file}:{line}: {module} imports crate::{target}"))
        .collect()
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

#[test]
fn no_module_imports_from_a_layer_above_it() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    let mut found = Vec::new();
    let mut placed = 0;
    for path in &files {
        let relative = path.strip_prefix(&src).unwrap();
        let first = relative.components().next().unwrap().as_os_str();
        let module = Path::new(first).file_stem().unwrap().to_str().unwrap();
        let known = layer(module).is_some() || UTILITIES.contains(&module);
        // lib.rs and main.rs stand above every layer.
        assert!(
            known || ["lib", "main"].contains(&module),
            "{}: module {module} is in no layer: add it to LAYERS or UTILITIES",
            relative.display()
        );
        placed += layer(module).is_some() as usize;
        let text = std::fs::read_to_string(path).unwrap();
        found.extend(violations(&relative.display().to_string(), module, &text));
    }
    assert!(placed > 50, "only {placed} files checked");
    assert!(
        found.is_empty(),
        "imports that run up the layers:\n{}",
        found.join("\n")
    );
}

/// The rooms of `src/experiment/`, bottom first. A room may import its own modules and the rooms
/// below it; `run` and `results` stand side by side and import neither each other nor anything
/// above. The files beside the rooms (`experiment/mod.rs`, `merge.rs`, `reproduce.rs`) join them
/// and may import any.
const ROOMS: &[&[&str]] = &[&["record"], &["plan"], &["run", "results"]];
const PEERS: &[&str] = &["run", "results"];

fn room_rank(room: &str) -> Option<usize> {
    ROOMS.iter().position(|r| r.contains(&room))
}

/// May a file of room `from` import room `to`?
fn room_allowed(from: &str, to: &str) -> bool {
    if from == to {
        return true;
    }
    if PEERS.contains(&from) && PEERS.contains(&to) {
        return false;
    }
    matches!((room_rank(from), room_rank(to)), (Some(f), Some(t)) if t < f)
}

/// Every room named after `crate::experiment::` or `super::super::` in `text`, with its line.
fn room_imports(text: &str) -> Vec<(usize, String)> {
    let code: Vec<&str> = text.lines().map(code_of).collect();
    let mut found = Vec::new();
    for (i, line) in code.iter().enumerate() {
        for prefix in ["crate::experiment::", "super::super::"] {
            for (pos, _) in line.match_indices(prefix) {
                let rest = &line[pos + prefix.len()..];
                let mut names: Vec<&str> = Vec::new();
                match rest.strip_prefix('{') {
                    Some(group) => names.extend(group.split([',', '}']).map(str::trim)),
                    None => names.push(rest),
                }
                for name in names {
                    let room: String = name
                        .chars()
                        .take_while(|c| c.is_alphanumeric() || *c == '_')
                        .collect();
                    if room_rank(&room).is_some() {
                        found.push((i + 1, room));
                    }
                }
            }
        }
    }
    found
}

fn room_violations(file: &str, room: &str, text: &str) -> Vec<String> {
    room_imports(text)
        .into_iter()
        .filter(|(_, to)| !room_allowed(room, to))
        .map(|(line, to)| format!("{file}:{line}: experiment/{room} imports experiment/{to}"))
        .collect()
}

#[test]
fn the_experiment_rooms_import_only_downwards() {
    let experiment = Path::new(env!("CARGO_MANIFEST_DIR")).join("src/experiment");
    let mut found = Vec::new();
    let mut checked = 0;
    for room in ROOMS.iter().flat_map(|r| r.iter()) {
        let mut files = Vec::new();
        rust_files(&experiment.join(room), &mut files);
        assert!(!files.is_empty(), "experiment/{room} has no files");
        for path in &files {
            let text = std::fs::read_to_string(path).unwrap();
            let relative = path
                .strip_prefix(&experiment)
                .unwrap()
                .display()
                .to_string();
            found.extend(room_violations(&relative, room, &text));
            checked += 1;
        }
    }
    // Every file of experiment/ is in a room but the two that join them.
    let mut all = Vec::new();
    rust_files(&experiment, &mut all);
    let outside: Vec<String> = all
        .iter()
        .map(|p| p.strip_prefix(&experiment).unwrap().display().to_string())
        .filter(|p| !p.contains('/'))
        .collect();
    for file in &outside {
        assert!(
            ["merge.rs", "mod.rs", "reproduce.rs"].contains(&file.as_str()),
            "experiment/{file} is in no room: move it into record/, plan/, run/ or results/"
        );
    }
    assert!(checked > 20, "only {checked} files checked");
    assert!(
        found.is_empty(),
        "imports across the experiment rooms:\n{}",
        found.join("\n")
    );
}

#[test]
fn the_room_checker_refuses_upward_and_sideways_imports() {
    let text = "use crate::experiment::record::files::RUNS_CSV;\n\
                use crate::experiment::{plan::Plan, results::plots};\n\
                use super::super::run::runner::Case;\n";
    assert_eq!(
        room_imports(text),
        [
            (1, "record".to_string()),
            (2, "plan".to_string()),
            (2, "results".to_string()),
            (3, "run".to_string()),
        ]
    );
    assert_eq!(
        room_violations("results/x.rs", "results", text),
        ["results/x.rs:3: experiment/results imports experiment/run"]
    );
    assert_eq!(room_violations("plan/x.rs", "plan", text).len(), 2);
    assert_eq!(room_violations("record/x.rs", "record", text).len(), 3);
}

#[test]
fn the_checker_finds_imports_in_paths_groups_and_code() {
    let text = "use crate::geometry::Ray;\n\
                // use crate::experiment::nothing;  (a comment)\n\
                use crate::{\n    scene::Mesh,\n    render::{a, b},\n};\n\
                fn f() { let s = \"crate::verify\"; crate::tracers::chunked::pass(); }\n";
    assert_eq!(
        crate_imports(text),
        [
            (1, "geometry".to_string()),
            (4, "scene".to_string()),
            (5, "render".to_string()),
            (7, "verify".to_string()),
            (7, "tracers".to_string()),
        ]
    );
    // From accel: render and tracers are above it; the string's "crate::verify" counts too (the
    // checker is conservative), geometry and scene are below.
    assert_eq!(
        violations("accel/x.rs", "accel", text),
        [
            "accel/x.rs:5: accel imports crate::render",
            "accel/x.rs:7: accel imports crate::verify",
            "accel/x.rs:7: accel imports crate::tracers",
        ]
    );
    assert!(violations("experiment/x.rs", "experiment", text).is_empty());
}
