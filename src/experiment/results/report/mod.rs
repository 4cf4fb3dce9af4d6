//! `raylab report DIR…`: what results directories hold, put in front of a reader.
//!
//! - HTML (`html`): one self-contained page — figures embedded as `data:` URIs, no script, no
//!   network — with the machine and plan of each run, its verdicts, summary, paper-vs-ours tables,
//!   figures and data, several runs side by side in columns (two machines, two commits).
//! - Markdown (`markdown`): the committed reproduction report of a paper
//!   (`results/<paper>/REPORT.md`) over its claims (`claims`, judged by `judge`) and the run of
//!   each of its experiment files (`paper`), with a generated-by header naming the command and
//!   the digest of the files it was made from, so a test can regenerate it and compare; over a
//!   directory of papers, the index of their verdict counts (`results/VERDICTS.md`).
//!
//! A results directory is read as it is: meta.json (required), runs.csv or stability.csv,
//! tables.md, summary.md and the PNG figures, each when present.

pub mod blocks;
pub mod claims;
pub mod encode;
pub mod html;
pub mod judge;
pub mod markdown;
pub mod paper;

use std::path::{Path, PathBuf};

use serde_json::Value;

use crate::error::{Error, Result};

use crate::experiment::record::digest::digest;
use crate::experiment::record::files::META_JSON;
use crate::experiment::record::files::STABILITY_CSV;
use crate::experiment::record::files::TABLES_MD;
use crate::experiment::record::files::{read_text, RUNS_CSV, SUMMARY_MD};
use crate::experiment::record::settings::RunSettings;
use blocks::Block;
use paper::{papers_under, Paper};

/// The generated reproduction report of a paper's results directory.
pub const REPORT_MD: &str = "REPORT.md";
/// The generated table of every paper's verdict counts, in the directory of the papers.
pub const VERDICTS_MD: &str = "VERDICTS.md";

/// One results directory, read.
pub struct Results {
    /// As given on the command line.
    pub dir: PathBuf,
    pub meta: Value,
    /// runs.csv, else stability.csv: (file name, contents).
    pub data: Option<(&'static str, String)>,
    pub tables: Vec<Block>,
    pub summary: Vec<Block>,
    /// PNG files by name, in name order.
    pub figures: Vec<(String, Vec<u8>)>,
    /// `digest` of every file above: what a generated report was made from.
    pub digest: String,
}

impl Results {
    pub fn read(dir: &Path) -> Result<Results> {
        if !dir.is_dir() {
            return Err(Error::usage(format!(
                "{}: not a results directory",
                dir.display()
            )));
        }
        let meta_path = dir.join(META_JSON);
        let meta_text =
            std::fs::read_to_string(&meta_path).map_err(|e| Error::io(&meta_path, e))?;
        let meta: Value = serde_json::from_str(&meta_text)
            .map_err(|e| Error::input(&meta_path, Some(e.line()), e.to_string()))?;
        let data = match read_text(&dir.join(RUNS_CSV))? {
            Some(text) => Some((RUNS_CSV, text)),
            None => read_text(&dir.join(STABILITY_CSV))?.map(|t| (STABILITY_CSV, t)),
        };
        let tables_text = read_text(&dir.join(TABLES_MD))?.unwrap_or_default();
        let summary_text = read_text(&dir.join(SUMMARY_MD))?.unwrap_or_default();
        let mut figures = Vec::new();
        for entry in std::fs::read_dir(dir).map_err(|e| Error::io(dir, e))? {
            let path = entry.map_err(|e| Error::io(dir, e))?.path();
            if path.extension().is_some_and(|e| e == "png") {
                let bytes = std::fs::read(&path).map_err(|e| Error::io(&path, e))?;
                let name = path
                    .file_name()
                    .map_or(String::new(), |n| n.to_string_lossy().into_owned());
                figures.push((name, bytes));
            }
        }
        figures.sort();
        let tables = blocks::parse(&tables_text);
        let mut parts: Vec<&[u8]> = vec![
            meta_text.as_bytes(),
            data.as_ref().map_or(&[], |(_, t)| t.as_bytes()),
            tables_text.as_bytes(),
            summary_text.as_bytes(),
        ];
        for (name, bytes) in &figures {
            parts.push(name.as_bytes());
            parts.push(bytes);
        }
        let digest = digest(parts);
        Ok(Results {
            dir: dir.to_path_buf(),
            meta,
            data,
            tables,
            summary: blocks::parse(&summary_text),
            figures,
            digest,
        })
    }

    /// A meta.json field as text (`pointer` as in RFC 6901: `/cpu/model`); empty when absent.
    pub fn text(&self, pointer: &str) -> String {
        match self.meta.pointer(pointer) {
            None | Some(Value::Null) => String::new(),
            Some(Value::String(s)) => s.clone(),
            Some(Value::Array(items)) => items
                .iter()
                .map(|v| match v {
                    Value::String(s) => s.clone(),
                    other => other.to_string(),
                })
                .collect::<Vec<_>>()
                .join(", "),
            Some(other) => other.to_string(),
        }
    }

    /// The title: the experiment's name.
    pub fn title(&self) -> String {
        format!("{}: results", self.text("/experiment"))
    }

    /// The machine and build facts, as (label, value) rows, the same labels for every run (values
    /// may be empty). A merged sweep also lists the shards: where and when each part was measured.
    pub fn facts(&self) -> Vec<(&'static str, String)> {
        let shards = match self.meta.get("merged_from") {
            Some(Value::Array(shards)) => shards
                .iter()
                .map(|s| {
                    let field = |k: &str| s.get(k).and_then(Value::as_str).unwrap_or_default();
                    format!(
                        "{} on {} ({}), {}, commit {}",
                        field("shard"),
                        field("hostname"),
                        field("cpu"),
                        field("date"),
                        field("commit")
                    )
                })
                .collect::<Vec<_>>()
                .join("; "),
            _ => String::new(),
        };
        let dirty = match self.meta.pointer("/commit/dirty") {
            Some(Value::Bool(true)) => " (uncommitted changes)",
            _ => "",
        };
        let versions = match self.meta.get("versions") {
            Some(Value::Object(map)) => map
                .iter()
                .map(|(k, v)| format!("{k} {}", v.as_str().unwrap_or_default()))
                .collect::<Vec<_>>()
                .join(", "),
            _ => String::new(),
        };
        vec![
            ("experiment", self.text("/experiment")),
            ("run", self.text("/run_id")),
            ("date (UTC)", self.text("/date")),
            ("commit", format!("{}{dirty}", self.text("/commit/hash"))),
            ("host", self.text("/hostname")),
            ("CPU", self.text("/cpu/model")),
            ("logical cores", self.text("/cpu/logical_cores")),
            ("ISA compiled for", self.text("/cpu/features_compiled")),
            ("ISA detected", self.text("/cpu/features_detected")),
            ("threads", self.text("/threads")),
            (
                "settings",
                RunSettings::of_run(&self.meta).map_or(String::new(), |s| s.shown()),
            ),
            ("versions", versions),
            ("merged from shards", shards),
        ]
    }

    /// The command that reruns the experiment with the same overrides.
    pub fn run_command(&self) -> String {
        let mut command = format!("raylab run {}", self.text("/experiment_file/path"));
        let overrides = self.meta.get("overrides");
        let get = |key: &str| overrides.and_then(|o| o.get(key)).filter(|v| !v.is_null());
        if let Some(Value::Array(threads)) = get("threads") {
            let t: Vec<String> = threads.iter().map(Value::to_string).collect();
            command += &format!(" --threads {}", t.join(" "));
        }
        if let Some(Value::Array(wh)) = get("resolution") {
            command += &format!(" --resolution {}", wh[0]);
        }
        for key in ["frames", "warmup", "repeats"] {
            if let Some(v) = get(key) {
                command += &format!(" --{key} {v}");
            }
        }
        command
    }

    /// The plan's scenes, as (scene, triangles, ray kinds, notes) rows; none for a stability run.
    pub fn scenes(&self) -> Vec<[String; 4]> {
        let Some(Value::Array(scenes)) = self.meta.pointer("/plan/scenes") else {
            return Vec::new();
        };
        scenes
            .iter()
            .map(|s| {
                let list = |key: &str| match s.get(key) {
                    Some(Value::Array(a)) => a
                        .iter()
                        .map(|v| v.as_str().map_or(v.to_string(), String::from))
                        .collect::<Vec<_>>()
                        .join(", "),
                    _ => String::new(),
                };
                let size = s.get("size").and_then(Value::as_u64);
                let name = s.get("name").and_then(Value::as_str).unwrap_or_default();
                [
                    size.map_or(name.to_string(), |n| format!("{name} (size {n})")),
                    s.get("triangles").map_or(String::new(), Value::to_string),
                    list("ray_kinds"),
                    list("notes"),
                ]
            })
            .collect()
    }

    /// The plan's tracer instances (`name[params]`).
    pub fn instances(&self) -> Vec<String> {
        match self.meta.pointer("/plan/instances") {
            Some(Value::Array(a)) => a
                .iter()
                .filter_map(|i| i.get("label").and_then(Value::as_str).map(String::from))
                .collect(),
            _ => Vec::new(),
        }
    }
}

/// Reads every directory of `dirs`.
pub fn read_all(dirs: &[PathBuf]) -> Result<Vec<Results>> {
    if dirs.is_empty() {
        return Err(Error::usage("report: no results directories given"));
    }
    dirs.iter().map(|d| Results::read(d)).collect()
}

/// `raylab report [--markdown] DIR… [--output FILE]`: writes the report and returns its path. The
/// markdown report is of one paper's directory (`DIR/REPORT.md` by default), or, of a directory
/// of papers, their verdict counts (`DIR/VERDICTS.md`); the HTML page is of results directories,
/// `DIR/report.html` for one, `report.html` for several.
pub fn write(dirs: &[PathBuf], as_markdown: bool, output: Option<&Path>) -> Result<PathBuf> {
    let (text, default) = match (as_markdown, dirs) {
        (true, [dir]) if Paper::is_paper(dir) => {
            (markdown::report(&Paper::read(dir)?), dir.join(REPORT_MD))
        }
        (true, [dir]) => {
            let papers = papers_under(dir)?
                .iter()
                .map(|p| Paper::read(p))
                .collect::<Result<Vec<_>>>()?;
            if papers.is_empty() {
                return Err(Error::usage(format!(
                    "report --markdown {}: neither a paper's directory (with claims.toml) nor one holding papers",
                    dir.display()
                )));
            }
            (markdown::index(dir, &papers), dir.join(VERDICTS_MD))
        }
        (true, _) => {
            return Err(Error::usage(
                "report --markdown: one directory at a time (it writes DIR/REPORT.md or DIR/VERDICTS.md)",
            ))
        }
        (false, dirs) => {
            let runs = read_all(dirs)?;
            let names: Vec<String> = dirs.iter().map(|d| d.display().to_string()).collect();
            let page = html::page(&runs, &format!("raylab report {}", names.join(" ")));
            let default = match &runs[..] {
                [run] => run.dir.join("report.html"),
                _ => PathBuf::from("report.html"),
            };
            (page, default)
        }
    };
    let path = output.map_or(default, Path::to_path_buf);
    // Written beside, then renamed: a reader never sees half a report.
    let partial = path.with_extension("partial");
    std::fs::write(&partial, text).map_err(|e| Error::io(&partial, e))?;
    std::fs::rename(&partial, &path).map_err(|e| Error::io(&path, e))?;
    Ok(path)
}

#[cfg(test)]
mod tests {
    use std::fs;

    use super::*;

    /// A 2×1 RGB PNG (one red pixel, one blue), encoded by the `image` crate.
    fn png() -> Vec<u8> {
        let mut img = image::RgbImage::new(2, 1);
        img.put_pixel(0, 0, image::Rgb([255, 0, 0]));
        img.put_pixel(1, 0, image::Rgb([0, 0, 255]));
        let mut bytes = std::io::Cursor::new(Vec::new());
        img.write_to(&mut bytes, image::ImageFormat::Png).unwrap();
        bytes.into_inner()
    }

    /// A results directory with every file a report reads.
    fn fixture(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("raylab-report-{name}-{}", std::process::id()));
        let _ = fs::remove_dir_all(&dir);
        run_fixture(&dir);
        dir
    }

    fn run_fixture(dir: &Path) {
        fs::create_dir_all(dir).unwrap();
        // The experiment file lays out the run's tables (`paper::computed_tables`).
        let experiment = dir.join("toy.toml");
        fs::write(
            &experiment,
            "name = \"toy\"\npaper_settings = { width = 128 }\n[[tables]]\ntitle = \"Table 1: speed\"\n\
             row_header = \"scene\"\nrows = \"scene\"\nmetric = \"seconds_min\"\n\
             columns = [{ label = \"ours\" }, { label = \"paper\", paper = { room = 3 } }]\n",
        )
        .unwrap();
        let meta = serde_json::json!({
            "experiment": "toy", "run_id": "20260101T000000Z", "date": "2026-01-01T00:00:00Z",
            "commit": { "hash": "abc123", "dirty": false }, "hostname": "node7",
            "cpu": { "model": "Some CPU", "logical_cores": 2, "features_detected": ["avx2", "avx512f"],
                     "features_compiled": ["avx2"] },
            "threads": [1, 2], "versions": { "embree": "3.13.5", "raylab": "0.1.0" },
            "experiment_file": { "path": experiment.display().to_string(), "contents": "name = \"toy\"\n" },
            "overrides": { "frames": 1, "threads": null },
            "plan": { "description": "a <toy>", "instances": [{ "label": "reference" }],
                      "width": 64, "height": 64, "frames": 1, "repeats": 5, "threads": [1, 2],
                      "scenes": [{ "name": "room", "size": 3, "triangles": 864, "ray_kinds": ["primary"], "notes": [] }] }
        });
        fs::write(dir.join(META_JSON), meta.to_string()).unwrap();
        fs::write(
            dir.join(RUNS_CSV),
            "scene,rays,seconds_min,seconds_median\nroom,1024,2.5,2.6\n",
        )
        .unwrap();
        fs::write(
            dir.join(TABLES_MD),
            "# toy: paper vs ours\n\n## Table 1: speed\n\n| scene | ours | paper |\n|---|---:|---:|\n| room | 2.50 | 3 |\n",
        )
        .unwrap();
        fs::write(dir.join(SUMMARY_MD), "# Summary\n\nAll 1 checks passed.\n").unwrap();
        fs::write(dir.join("throughput_room.png"), png()).unwrap();
    }

    /// A papers directory holding one paper, `toy2026`, with a run of `toy` and none of `other`.
    fn paper_fixture(name: &str) -> PathBuf {
        let root = std::env::temp_dir().join(format!("raylab-paper-{name}-{}", std::process::id()));
        let _ = fs::remove_dir_all(&root);
        let dir = root.join("toy2026");
        run_fixture(&dir.join("toy"));
        fs::write(
            dir.join(claims::CLAIMS_TOML),
            "title = \"Toy 2026\"\npaper = \"A. Toy. Toys. 2026.\"\npaper_text = \"toy.txt\"\nexperiments = [\"toy\", \"other\"]\n\
             [[claims]]\nitem = \"X1\"\nclaim = \"ours is as fast\"\npaper = \"3 on the room\"\nquote = \"between 2 and 4\"\nexperiment = \"toy\"\n\
             tests = [\"{{Table 1 | room | ours}} >= {{Table 1 | room | paper}}\", \"{{Table 1 | room | ours}} in [2, 4]\"]\n\
             note = \"{{Table 1 | room | ours}} against the paper's {{Table 1 | room | paper}}\"\n\
             [[claims]]\nitem = \"X2\"\nclaim = \"others agree\"\npaper = \"\"\nquote = \"more\"\nexperiment = \"other\"\ntests = [\"{{T | r | c}} > 1\"]\n\
             [[not_reproducible]]\nitem = \"X10\"\nclaim = \"the toy simulator is fast\"\npaper = \"9 MHz\"\nreason = \"no simulator here\"\n",
        )
        .unwrap();
        root
    }

    #[test]
    fn the_markdown_report_computes_verdicts_and_names_its_sources() {
        let root = paper_fixture("md");
        let dir = root.join("toy2026");
        let paper = Paper::read(&dir).unwrap();
        let md = markdown::report(&paper);
        let (named, digest) = markdown::generated_by(&md).unwrap();
        assert_eq!(
            (named, digest.as_str()),
            (dir.clone(), paper.digest.as_str())
        );
        assert!(md.contains("# Toy 2026\n\nA. Toy. Toys. 2026.\n"), "{md}");
        assert!(
            md.contains("**The paper: 2 claims: 0 hold, 1 partly, 0 differ, 0 within noise, 1 not run; 0 of the 1 that differ or partly hold explained by a rule that stands; 1 not reproducible here.**"),
            "{md}"
        );
        // The item table first, in item order (X2 before X10).
        let items = md.find("| item | the paper | its numbers").unwrap();
        assert!(items < md.find("## Runs").unwrap(), "{md}");
        assert!(
            md.contains("| X1 | ours is as fast | 3 on the room | 2.5 | **partly** (reduced run: toy) |\n| X2 | others agree |  |  | **not run** |\n| X10 | the toy simulator is fast | 9 MHz | – | **not reproducible here**: no simulator here |\n"),
            "{md}"
        );
        assert!(md.contains("raylab reproduce toy2026 "), "{md}");
        assert!(
            md.contains(&format!("| toy | 20260101T000000Z | 2026-01-01T00:00:00Z | abc123 | node7 | Some CPU | avx2 | 64×64, 1 spp, 1 frames, 5 repeats, threads 1, 2 | reduced: width 64 < 128 | stale: no record of the source it measured; its experiment file changed since | `raylab run {} --frames 1` |", dir.join("toy").join("toy.toml").display())),
            "{md}"
        );
        assert!(md.contains("| other | not run |"), "{md}");
        assert!(
            md.contains("| X1 | ours is as fast | 3 on the room | **partly** (reduced run: toy) | [Table 1 · room · ours] ≥ [Table 1 · room · paper]: 2.5 ≥ 3 ✗<br>[Table 1 · room · ours] in [2, 4]: 2.5 in [2, 4] ✓ | 2.50 against the paper's 3 |"),
            "{md}"
        );
        assert!(
            md.contains("| X2 | others agree |  | **not run** | [T · r · c] > 1: not run |  |"),
            "{md}"
        );
        assert!(md.contains("#### Table 1: speed\n\n| scene | ours | paper |\n|---|---:|---:|\n| room | 2.50 | 3 |\n"), "{md}");
        assert!(md.contains("![throughput_room.png](toy/throughput_room.png)"));
        assert!(md.contains("### Summary\n\nAll 1 checks passed.\n"), "{md}");
        // Same files, same report; any change to them, another digest.
        assert_eq!(markdown::report(&Paper::read(&dir).unwrap()), md);
        fs::write(
            dir.join("toy").join(RUNS_CSV),
            "scene,rays,seconds_min,seconds_median\nroom,1025,2.5,2.6\n",
        )
        .unwrap();
        assert_ne!(Paper::read(&dir).unwrap().digest, paper.digest);
        // So is the experiment file that lays out its tables.
        let layout = dir.join("toy").join("toy.toml");
        let before = Paper::read(&dir).unwrap().digest;
        let text = fs::read_to_string(&layout).unwrap();
        fs::write(&layout, text.replace("Table 1: speed", "Table 1: speed!")).unwrap();
        assert_ne!(Paper::read(&dir).unwrap().digest, before);
        fs::write(&layout, text).unwrap();
        let written = write(std::slice::from_ref(&dir), true, None).unwrap();
        assert_eq!(written, dir.join(REPORT_MD));
        // The report itself is not among its sources.
        let again = Paper::read(&dir).unwrap();
        assert_eq!(
            fs::read_to_string(&written).unwrap(),
            markdown::report(&again)
        );
        // The index of papers counts their verdicts.
        let index = write(std::slice::from_ref(&root), true, None).unwrap();
        assert_eq!(index, root.join(VERDICTS_MD));
        let text = fs::read_to_string(&index).unwrap();
        assert!(
            text.contains("| report | claims | holds | partly | differs | within noise | not run | differs or partly: explained by a rule | not reproducible here |\n|---|---:|---:|---:|---:|---:|---:|---:|---:|\n"),
            "{text}"
        );
        assert!(
            text.contains(
                "| [Toy 2026](toy2026/REPORT.md) | 2 | 0 | 1 | 0 | 0 | 1 | 0 of 1 | 1 |\n"
            ),
            "{text}"
        );
        // A run the claims file does not list is an error.
        run_fixture(&dir.join("stray"));
        let e = Paper::read(&dir).err().unwrap();
        assert_eq!(e.exit_code(), 2);
        assert!(e.to_string().contains("stray"), "{e}");
        let _ = fs::remove_dir_all(&root);
    }

    #[test]
    fn the_html_page_embeds_everything_and_puts_runs_side_by_side() {
        let (a, b) = (fixture("html-a"), fixture("html-b"));
        let path = write(&[a.clone(), b.clone()], false, Some(&a.join("both.html"))).unwrap();
        let html = fs::read_to_string(&path).unwrap();
        // Nothing from the network, no script.
        for forbidden in ["http://", "https://", "<script", "<link", "src=\"file"] {
            assert!(!html.contains(forbidden), "{forbidden}");
        }
        assert!(html.contains("grid-template-columns:repeat(2,"));
        // Per run: the machine column, scenes, tables.md, data; text escaped.
        assert_eq!(html.matches("<td>node7</td>").count(), 2);
        assert!(html.contains("<p>a &lt;toy&gt;</p>"));
        assert_eq!(html.matches("<td class=\"num\">2.50</td>").count(), 2);
        assert_eq!(html.matches("<td>1024</td>").count(), 2);
        // The figure decodes back to the PNG's bytes.
        let uri = "src=\"data:image/png;base64,";
        let start = html.find(uri).unwrap() + uri.len();
        let end = start + html[start..].find('"').unwrap();
        assert_eq!(&html[start..end], encode::base64(&png()));
        assert_eq!(html.matches(uri).count(), 2);
        let e = write(&[a.clone(), b.clone()], true, None).unwrap_err();
        assert_eq!(e.exit_code(), 2);
        let e = write(&[a.join("nothing")], false, None).unwrap_err();
        assert!(e.to_string().contains("nothing"), "{e}");
        // A run directory is no paper: --markdown says so.
        let e = write(std::slice::from_ref(&a), true, None).unwrap_err();
        assert!(e.to_string().contains("claims.toml"), "{e}");
        for d in [a, b] {
            let _ = fs::remove_dir_all(d);
        }
    }

    #[test]
    fn a_claim_quoting_a_missing_cell_is_an_error_naming_the_file_and_line() {
        let root = paper_fixture("bad");
        let dir = root.join("toy2026");
        fs::write(
            dir.join(claims::CLAIMS_TOML),
            "title = \"t\"\npaper = \"p\"\nexperiments = [\"toy\"]\n[[targets]]\nclaim = \"c\"\npaper = \"\"\nexperiment = \"toy\"\ntests = [\"{{Table 1 | kitchen | ours}} > 1\"]\n",
        )
        .unwrap();
        let e = Paper::read(&dir).err().unwrap();
        assert_eq!(e.exit_code(), 2);
        assert!(e.to_string().contains("claims.toml:5"), "{e}");
        assert!(e.to_string().contains("kitchen"), "{e}");
        let _ = fs::remove_dir_all(&root);
    }
}
