//! What a run measured at (image size, samples, frames, passes, threads) against what the paper
//! used (`paper_settings = { … }` of its experiment file), and the label that follows: a run is
//! at the paper's scale only when no setting falls short of the paper's; otherwise it is
//! *reduced*, and every report and verdict reading it says so (`report --check` fails a run
//! labelled `paper` that falls short).

use serde::{Deserialize, Serialize};
use serde_json::Value;

/// The paper's settings for one experiment, each one the paper states.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PaperSettings {
    pub width: Option<u64>,
    pub height: Option<u64>,
    /// Samples per pixel of a rendered frame.
    pub spp: Option<u64>,
    /// Light samples per point of soft shadows.
    pub shadow_samples: Option<u64>,
    pub frames: Option<u64>,
}

/// The settings a run measured at, read from its meta.json.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RunSettings {
    pub width: u64,
    pub height: u64,
    /// The largest `spp` of its render workloads (1 without).
    pub spp: u64,
    /// One 32×32 tile in this many traced (`tiles=` of a render workload; 1: the whole image).
    pub tiles: u64,
    /// Light samples per point, when it traced soft shadows.
    pub shadow_samples: Option<u64>,
    pub frames: u64,
    pub repeats: u64,
    pub threads: String,
}

/// A run's scale: the paper's settings or reduced (or a smoke test, or no paper to compare with).
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Label {
    Paper,
    /// Below the paper's settings: each shortfall as "setting ours < the paper's".
    Reduced(Vec<String>),
    Quick,
    /// The experiment file declares no paper settings.
    Undeclared,
}

impl Label {
    pub fn name(&self) -> &'static str {
        match self {
            Label::Paper => "paper",
            Label::Reduced(_) => "reduced",
            Label::Quick => "quick",
            Label::Undeclared => "no paper settings declared",
        }
    }
}

impl RunSettings {
    /// From a run's meta.json: the plan's settings, the largest `spp=` of its render workloads,
    /// and the soft-shadow samples of its experiment file as recorded (`None` without a plan).
    pub fn of_run(meta: &Value) -> Option<RunSettings> {
        let plan = meta.get("plan")?;
        let number = |key: &str| plan.get(key).and_then(Value::as_u64).unwrap_or(0);
        // The largest `key=` of the render workloads.
        let render = |key: &str| match plan.get("renders") {
            Some(Value::Array(renders)) => renders
                .iter()
                .filter_map(Value::as_str)
                .flat_map(|r| r.split(';'))
                .filter_map(|kv| kv.strip_prefix(key)?.strip_prefix('='))
                .filter_map(|n| n.parse::<u64>().ok())
                .max(),
            _ => None,
        };
        let contents = meta
            .pointer("/experiment_file/contents")
            .and_then(Value::as_str)
            .unwrap_or_default();
        let file: toml::Value = toml::from_str(contents).unwrap_or(toml::Value::Boolean(false));
        let soft_shadows = contents.contains("soft_shadow");
        let shadow_samples = file
            .get("soft_shadow")
            .and_then(|s| s.get("samples"))
            .and_then(toml::Value::as_integer)
            .map(|n| n as u64)
            .or(soft_shadows.then_some(DEFAULT_SHADOW_SAMPLES));
        let threads = match plan.get("threads") {
            Some(Value::Array(t)) => t
                .iter()
                .map(Value::to_string)
                .collect::<Vec<_>>()
                .join(", "),
            _ => String::new(),
        };
        Some(RunSettings {
            width: number("width"),
            height: number("height"),
            spp: render("spp").unwrap_or(1),
            tiles: render("tiles").unwrap_or(1),
            shadow_samples,
            frames: number("frames"),
            repeats: number("repeats"),
            threads,
        })
    }

    /// "1024×1024, 64 spp, 16 shadow samples, 3 frames, 5 repeats, threads 1, 2".
    pub fn shown(&self) -> String {
        let mut parts = vec![format!("{}×{}", self.width, self.height)];
        if self.tiles > 1 {
            parts.push(format!("1 tile in {} traced", self.tiles));
        }
        parts.push(format!("{} spp", self.spp));
        if let Some(n) = self.shadow_samples {
            parts.push(format!("{n} shadow samples"));
        }
        parts.push(format!("{} frames", self.frames));
        parts.push(format!("{} repeats", self.repeats));
        parts.push(format!("threads {}", self.threads));
        parts.join(", ")
    }
}

/// `soft_shadow.samples` when the file does not say (the plan's `DEFAULT_SOFT_SHADOW_SAMPLES`).
const DEFAULT_SHADOW_SAMPLES: u64 = 16;

impl PaperSettings {
    /// The `paper_settings` of an experiment file's text (`None` when it declares none or does
    /// not parse: the experiment parser reports that).
    pub fn of_experiment(text: &str) -> Option<PaperSettings> {
        let file: toml::Value = toml::from_str(text).ok()?;
        file.get("paper_settings")?.clone().try_into().ok()
    }

    /// Each setting of `run` below the paper's, as "setting ours < the paper's".
    pub fn shortfalls(&self, run: &RunSettings) -> Vec<String> {
        let mut out = Vec::new();
        let mut check = |what: &str, ours: Option<u64>, paper: Option<u64>| {
            if let Some(paper) = paper {
                match ours {
                    Some(ours) if ours >= paper => {}
                    Some(ours) => out.push(format!("{what} {ours} < {paper}")),
                    None => out.push(format!("{what} none < {paper}")),
                }
            }
        };
        check("width", Some(run.width), self.width);
        check("height", Some(run.height), self.height);
        check("spp", Some(run.spp), self.spp);
        check("shadow samples", run.shadow_samples, self.shadow_samples);
        check("frames", Some(run.frames), self.frames);
        out
    }
}

/// The label of the run whose meta.json is `meta`, against the paper settings its experiment file
/// declares (`experiment` is that file's text).
pub fn label(meta: &Value, experiment: &str) -> Label {
    if meta.pointer("/overrides/scale").and_then(Value::as_str) == Some("quick") {
        return Label::Quick;
    }
    let (Some(paper), Some(run)) = (
        PaperSettings::of_experiment(experiment),
        RunSettings::of_run(meta),
    ) else {
        return Label::Undeclared;
    };
    match paper.shortfalls(&run) {
        short if short.is_empty() => Label::Paper,
        short => Label::Reduced(short),
    }
}

/// Whether the run says it was made at the paper's scale: its recorded label (`scale` in
/// meta.json), or, in a run from before labels, `raylab reproduce --scale paper`.
pub fn labelled_paper(meta: &Value) -> bool {
    match meta.get("scale").and_then(Value::as_str) {
        Some(label) => label == "paper",
        None => meta.pointer("/overrides/scale").and_then(Value::as_str) == Some("paper"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn meta(width: u64, renders: &[&str], contents: &str) -> Value {
        serde_json::json!({
            "overrides": { "scale": "paper" },
            "experiment_file": { "contents": contents },
            "plan": { "width": width, "height": width, "frames": 1, "repeats": 5,
                      "threads": [1, 2], "renders": renders },
        })
    }

    #[test]
    fn a_run_below_any_paper_setting_is_reduced_and_says_which() {
        let paper = "paper_settings = { width = 1024, height = 1024, spp = 64 }\n";
        let m = meta(512, &["renderer=path;spp=4;max_depth=3"], "");
        assert_eq!(
            label(&m, paper),
            Label::Reduced(vec![
                "width 512 < 1024".into(),
                "height 512 < 1024".into(),
                "spp 4 < 64".into()
            ])
        );
        let full = meta(1024, &["renderer=path;spp=64"], "");
        assert_eq!(label(&full, paper), Label::Paper);
        assert_eq!(
            RunSettings::of_run(&full).unwrap().shown(),
            "1024×1024, 64 spp, 1 frames, 5 repeats, threads 1, 2"
        );
        // A stratified tile subset at the paper's resolution and samples: the paper's settings,
        // and it says so.
        let subset = meta(1024, &["renderer=path;order=passes;spp=64;tiles=16"], "");
        assert_eq!(label(&subset, paper), Label::Paper);
        assert!(RunSettings::of_run(&subset)
            .unwrap()
            .shown()
            .starts_with("1024×1024, 1 tile in 16 traced, 64 spp"));
        // Soft shadows: the file's samples, or the default when it names none.
        let shadows = "paper_settings = { shadow_samples = 64 }\n";
        let m = meta(
            1024,
            &[],
            "rays = [\"soft_shadow\"]\nsoft_shadow = { samples = 16 }\n",
        );
        assert_eq!(
            label(&m, shadows),
            Label::Reduced(vec!["shadow samples 16 < 64".into()])
        );
        let m = meta(1024, &[], "rays = [\"primary\"]\n");
        assert_eq!(
            label(&m, shadows),
            Label::Reduced(vec!["shadow samples none < 64".into()])
        );
        assert_eq!(label(&m, "name = \"x\"\n"), Label::Undeclared);
        let mut quick = m.clone();
        quick["overrides"]["scale"] = "quick".into();
        assert_eq!(label(&quick, paper), Label::Quick);
        assert!(labelled_paper(&m));
        let mut labelled = m.clone();
        labelled["scale"] = "reduced".into();
        assert!(!labelled_paper(&labelled));
    }
}
