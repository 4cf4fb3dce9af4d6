//! What to run: the experiment file parsed into typed settings (`config`), checked, and turned into
//! a plan of exactly the structures, ray kinds and render workloads it needs (`plan`), with the
//! command-line overrides, the shard of a sweep, and the declared paper tables and figures.
//! Imports only `record` among the experiment rooms.
//!
//! What a run needs, and only that, derived before anything is timed: per scene, which ray kinds
//! make sense (no shadow rays without lights, no reflection or refraction rays without materials
//! that reflect or refract), which render workloads render something different on it
//! (`render_pruning`), which acceleration structures to build (one per distinct kind and
//! structure parameters among the requested tracers, plus our BVH when secondary rays must be
//! generated), and whether geometry changes per frame (rebuild) or not (build once,
//! reuse). Printed before the run and stored in meta.json.

pub mod config;
pub mod figure_spec;
pub mod overrides;
#[doc(hidden)]
pub mod quad_scenes;
pub mod render_pruning;
pub mod shard;
pub mod table_spec;

use std::fmt;
use std::path::PathBuf;

use serde::ser::SerializeMap;
use serde::{Serialize, Serializer};

use crate::error::{Error, Result};
use crate::geometry::ray_file::read_rays;
use crate::geometry::RayKind;
use crate::scene::{Material, Scene};
use crate::tracers::{Params, Role, TracerConfig, TracerInfo};

use crate::experiment::plan::config::{Experiment, RenderWorkload, SceneSpec, StructureKey};
use crate::experiment::plan::render_pruning::prune_renders;

/// Finds a scene by its experiment entry. The run uses `scene::library::load_scene`; tests hand in
/// scenes of their own.
pub type SceneLoader<'a> = &'a dyn Fn(&SceneSpec) -> Result<Scene>;

/// The tracer that traces primary rays to find where secondary rays start: our reference.
pub fn secondary_ray_tracer() -> Result<&'static TracerInfo> {
    TracerInfo::of_role(Role::Reference)
}

#[derive(Debug, Serialize)]
pub struct Plan {
    pub experiment: String,
    pub description: String,
    pub width: u32,
    pub height: u32,
    pub frames: usize,
    pub threads: Vec<usize>,
    pub warmup: usize,
    pub repeats: usize,
    pub seed: u64,
    pub instances: Vec<InstancePlan>,
    /// The render workloads (`RenderWorkload` labels), measured for every instance and scene.
    pub renders: Vec<String>,
    pub scenes: Vec<ScenePlan>,
    /// The `rays = [{ file = "…" }]` batches, read and checked now, measured on every scene and
    /// frame.
    pub ray_files: Vec<RayFilePlan>,
    /// Run-wide remarks (oversubscribed threads).
    pub notes: Vec<String>,
}

#[derive(Debug, Serialize)]
pub struct InstancePlan {
    /// `name[params]`, as in the plots.
    pub label: String,
    pub tracer: String,
    #[serde(serialize_with = "params_map")]
    pub params: Params,
    /// The structure it traverses.
    pub structure: StructureKey,
    /// Whether the tracer counts its box and triangle tests (Embree counts only rays).
    pub counts_internals: bool,
    /// The tracer's parsed parameters (`TracerInstance::config`).
    #[serde(skip)]
    pub config: TracerConfig,
}

impl InstancePlan {
    /// The configuration it runs, defaults included: the tracer's parsed configuration and its
    /// structure's (`AccelKind::resolved`), as runs.csv's `resolved` column records it.
    pub fn resolved(&self) -> String {
        let structure = self.structure.kind.resolved(&self.structure.params);
        // The parameters were checked when the plan was made.
        let structure = structure.unwrap_or_else(|e| e.to_string());
        format!("{:?}; {structure}", self.config)
    }
}

#[derive(Debug, Serialize)]
pub struct ScenePlan {
    pub name: String,
    pub size: Option<u32>,
    pub source: String,
    pub triangles: usize,
    pub lights: usize,
    pub animated: bool,
    pub camera_path: bool,
    /// The requested kinds this scene can have.
    #[serde(serialize_with = "kind_names")]
    pub ray_kinds: Vec<RayKind>,
    pub structures: Vec<StructurePlan>,
    /// The render workloads measured on this scene (indices into `Plan::renders`): those that
    /// render something different here (`render_pruning`).
    pub renders: Vec<usize>,
    /// Animated geometry: every structure is rebuilt each frame. Otherwise built at frame 0 only.
    pub rebuild_per_frame: bool,
    /// Decisions worth reading: what was left out and why.
    pub notes: Vec<String>,
}

#[derive(Debug, Serialize)]
pub struct RayFilePlan {
    /// As written in the experiment: runs.csv's ray_kind is `file:<name>`.
    pub name: String,
    pub path: PathBuf,
    pub rays: usize,
}

#[derive(Debug, Serialize)]
pub struct StructurePlan {
    pub key: StructureKey,
    /// Indices of the tracer instances that traverse it.
    pub used_by: Vec<usize>,
    /// The reference tracer traces primary rays over it to generate the secondary rays.
    pub generates_secondary_rays: bool,
}

fn kind_names<S: Serializer>(kinds: &[RayKind], s: S) -> std::result::Result<S::Ok, S::Error> {
    s.collect_seq(kinds.iter().map(|k| k.name()))
}

fn params_map<S: Serializer>(params: &Params, s: S) -> std::result::Result<S::Ok, S::Error> {
    params.0.serialize(s)
}

impl Serialize for StructureKey {
    fn serialize<S: Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        let mut map = s.serialize_map(Some(2))?;
        map.serialize_entry("kind", self.kind.name())?;
        map.serialize_entry("params", &self.params.0)?;
        map.end()
    }
}

/// The structure secondary rays are generated with: the secondary-ray tracer's, with default
/// parameters.
pub fn secondary_ray_structure(tracer: &TracerInfo) -> StructureKey {
    StructureKey {
        kind: tracer.accel,
        params: Params::new(),
    }
}

impl ScenePlan {
    /// Whether structures are built at `frame` (otherwise those of frame 0 are reused).
    pub fn builds_at(&self, frame: usize) -> bool {
        frame == 0 || self.rebuild_per_frame
    }

    pub fn needs_secondary_rays(&self) -> bool {
        self.ray_kinds.iter().any(|&k| k != RayKind::Primary)
    }
}

impl Plan {
    /// The instance a row names (its `tracer` and `parameters` columns).
    pub fn instance_of(&self, tracer: &str, parameters: &str) -> Option<usize> {
        self.instances
            .iter()
            .position(|i| i.tracer == tracer && i.params.to_string() == parameters)
    }

    /// The scene a row names: by name, and where one name is planned at several sizes, by its
    /// triangle count (`None` when rows do not carry one, as histograms.csv).
    pub fn scene_of(&self, name: &str, triangles: Option<usize>) -> Option<usize> {
        let named = || (0..self.scenes.len()).filter(|&s| self.scenes[s].name == name);
        let sized = triangles.and_then(|t| named().find(|&s| self.scenes[s].triangles == t));
        sized.or_else(|| named().next())
    }

    /// Loads every scene to learn what it needs (the tracers' parameter values were checked when
    /// the experiment was parsed, so they fail before the run, not an hour into it). Scenes are
    /// dropped again (the run reloads each in turn), so only one is ever held in memory. Ray
    /// files are read and checked the same way, so a bad one fails before anything is measured.
    pub fn derive(exp: &Experiment, load: SceneLoader) -> Result<Plan> {
        let instances = plan_instances(exp);
        let secondary = secondary_ray_tracer()?;
        let ray_files = exp
            .ray_files
            .iter()
            .map(|f| {
                Ok(RayFilePlan {
                    name: f.name.clone(),
                    path: f.path.clone(),
                    rays: read_rays(&f.path)?.len(),
                })
            })
            .collect::<Result<Vec<_>>>()?;
        let mut scenes = Vec::with_capacity(exp.scenes.len());
        for spec in &exp.scenes {
            // A bad scene name is a mistake in the experiment file: say which file and line.
            let scene = load(spec).map_err(|e| match e {
                Error::Usage(m) => {
                    Error::usage(format!("{}:{}: {m}", exp.path.display(), exp.scenes_line))
                }
                other => other,
            })?;
            let interleaved = exp.renders.iter().any(|r| {
                matches!(r, RenderWorkload::Distribution(w) if w.settings.soft_shadows.is_some())
            });
            if interleaved && scene.quad_light().is_none() {
                return Err(Error::usage(format!(
                    "{}: scene {} has no quad light for the interleaved soft shadows of render shadows = \"interleaved\" (use a *-area-light scene)",
                    exp.path.display(),
                    spec.name
                )));
            }
            scenes.push(plan_scene(exp, spec, &scene, secondary));
        }
        let mut notes = Vec::new();
        let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
        let most = exp.threads.iter().copied().max().unwrap_or(1);
        if most > cores {
            notes.push(format!("{most} threads on {cores} logical cores: thread counts above {cores} are oversubscribed"));
        }
        Ok(Plan {
            experiment: exp.name.clone(),
            description: exp.description.clone(),
            width: exp.width,
            height: exp.height,
            frames: exp.frames,
            threads: exp.threads.clone(),
            warmup: exp.warmup,
            repeats: exp.repeats,
            seed: exp.seed,
            instances,
            renders: exp.renders.iter().map(|r| r.to_string()).collect(),
            scenes,
            ray_files,
            notes,
        })
    }

    /// Timed measurements (one per scene × frame × instance × (ray kind or render workload) ×
    /// thread count): the progress bar's length.
    pub fn measurements(&self) -> usize {
        let per_kind = self.frames * self.instances.len() * self.threads.len();
        self.scenes
            .iter()
            .map(|s| (s.ray_kinds.len() + self.ray_files.len() + s.renders.len()) * per_kind)
            .sum()
    }
}

fn plan_instances(exp: &Experiment) -> Vec<InstancePlan> {
    exp.instances
        .iter()
        .map(|instance| InstancePlan {
            label: instance.to_string(),
            tracer: instance.info.name.to_string(),
            params: instance.params.clone(),
            config: instance.config,
            structure: instance.structure(),
            counts_internals: instance.info.counts_internals,
        })
        .collect()
}

fn plan_scene(
    exp: &Experiment,
    spec: &SceneSpec,
    scene: &Scene,
    secondary: &TracerInfo,
) -> ScenePlan {
    let mut notes = Vec::new();
    // What the scene's triangles are made of decides which secondary rays exist.
    let mut used = vec![false; scene.materials.len()];
    for &m in &scene.mesh.material_ids {
        used[m as usize] = true;
    }
    let used = |test: fn(&Material) -> bool| {
        scene
            .materials
            .iter()
            .zip(&used)
            .any(|(m, &u)| u && test(m))
    };
    let (reflects, refracts) = (
        used(|m| m.is_reflective() || m.is_refractive()),
        used(Material::is_refractive),
    );
    let mut ray_kinds = Vec::new();
    for &kind in &exp.ray_kinds {
        let missing = match kind {
            RayKind::Shadow if scene.lights.is_empty() => Some("the scene has no lights"),
            RayKind::SoftShadow if scene.quad_light().is_none() => {
                Some("the scene has no quad light")
            }
            RayKind::Reflection if !reflects => Some("no material reflects"),
            RayKind::Refraction if !refracts => Some("no material refracts"),
            _ => None,
        };
        match missing {
            Some(why) => notes.push(format!("no {} rays: {why}", kind.name())),
            None => ray_kinds.push(kind),
        }
    }

    for instance in &exp.instances {
        let note = crate::tracers::registry::plan_note(instance.info.name, &ray_kinds);
        if let Some(note) = note.filter(|n| !notes.contains(n)) {
            notes.push(note);
        }
    }

    let mut structures: Vec<StructurePlan> = Vec::new();
    for (i, instance) in exp.instances.iter().enumerate() {
        let key = instance.structure();
        match structures.iter_mut().find(|s| s.key == key) {
            Some(s) => s.used_by.push(i),
            None => structures.push(StructurePlan {
                key,
                used_by: vec![i],
                generates_secondary_rays: false,
            }),
        }
    }
    if ray_kinds.iter().any(|&k| k != RayKind::Primary) {
        let key = secondary_ray_structure(secondary);
        let shared = structures.iter().any(|s| s.key == key);
        notes.push(format!(
            "secondary rays start at the primary hits of the {} tracer on {key}{}",
            secondary.name,
            if shared {
                " (shared with the tracers using it)"
            } else {
                ", built for that alone"
            }
        ));
        match structures.iter_mut().find(|s| s.key == key) {
            Some(s) => s.generates_secondary_rays = true,
            None => structures.push(StructurePlan {
                key,
                used_by: vec![],
                generates_secondary_rays: true,
            }),
        }
    }

    let renders = prune_renders(&exp.renders, scene);
    notes.extend(renders.notes);

    let rebuild_per_frame = scene.is_animated();
    if exp.frames > 1 {
        notes.push(if rebuild_per_frame {
            format!(
                "animated geometry: structures rebuilt for each of {} frames",
                exp.frames
            )
        } else {
            format!(
                "static geometry: structures built at frame 0, reused for {} frames",
                exp.frames
            )
        });
        if !rebuild_per_frame && scene.camera_path.is_none() {
            notes.push(format!(
                "nothing moves: the {} frames trace the same rays",
                exp.frames
            ));
        }
    }
    ScenePlan {
        name: spec.name.clone(),
        size: spec.size,
        source: scene.source.clone(),
        triangles: scene.triangle_count(),
        lights: scene.lights.len(),
        animated: scene.is_animated(),
        camera_path: scene.camera_path.is_some(),
        ray_kinds,
        structures,
        renders: renders.kept,
        rebuild_per_frame,
        notes,
    }
}

impl fmt::Display for Plan {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(f, "experiment {}: {}", self.experiment, self.description)?;
        writeln!(
            f,
            "  {}×{} pixels, {} frame(s), threads {:?}, {} warm-up + {} timed pass(es), seed {}",
            self.width,
            self.height,
            self.frames,
            self.threads,
            self.warmup,
            self.repeats,
            self.seed
        )?;
        writeln!(f, "  tracers:")?;
        for (i, instance) in self.instances.iter().enumerate() {
            let counts = if instance.counts_internals {
                ""
            } else {
                " (counts rays only)"
            };
            writeln!(
                f,
                "    [{i}] {} on {}{counts}",
                instance.label, instance.structure
            )?;
        }
        for render in &self.renders {
            writeln!(f, "  render workload: {render}")?;
        }
        for file in &self.ray_files {
            writeln!(
                f,
                "  ray file {} ({}): {} rays, closest hit, on every scene and frame",
                file.name,
                file.path.display(),
                file.rays
            )?;
        }
        for scene in &self.scenes {
            let size = scene.size.map_or(String::new(), |s| format!(" size {s}"));
            writeln!(
                f,
                "  scene {}{size} ({}): {} triangles, {} light(s), {}{}",
                scene.name,
                scene.source,
                scene.triangles,
                scene.lights,
                if scene.animated { "animated" } else { "static" },
                if scene.camera_path {
                    ", camera path"
                } else {
                    ""
                },
            )?;
            let kinds: Vec<&str> = scene.ray_kinds.iter().map(|k| k.name()).collect();
            writeln!(f, "    rays: {}", kinds.join(", "))?;
            for s in &scene.structures {
                let users: Vec<String> = s.used_by.iter().map(|i| format!("[{i}]")).collect();
                let secondary = if s.generates_secondary_rays {
                    "; generates secondary rays"
                } else {
                    ""
                };
                writeln!(
                    f,
                    "    build {}: used by {}{secondary}",
                    s.key,
                    users.join(" ")
                )?;
            }
            for note in &scene.notes {
                writeln!(f, "    note: {note}")?;
            }
        }
        write!(f, "  {} timed measurements", self.measurements())
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    pub use crate::experiment::plan::quad_scenes::{experiment, load_quads, quad_scene};

    /// An instance's resolved configuration names its defaults, the tracer's and the structure's,
    /// not only what the file set.
    #[test]
    fn an_instance_resolves_its_defaults() {
        let exp = experiment(
            "scenes = [\"lit\"]\ntracers = [{ name = \"packet\", params = { packet = [8] } }]\nrays = [\"primary\"]\n",
        );
        let plan = Plan::derive(&exp, &load_quads).unwrap();
        let resolved = plan.instances[0].resolved();
        assert_eq!(plan.instances[0].params.to_string(), "packet=8");
        for default in [
            "packet: 8",
            "lanes: 16",
            "traversal: Ranged",
            "robust: true",
            "BvhConfig",
        ] {
            assert!(resolved.contains(default), "{default} in {resolved}");
        }
    }

    #[test]
    fn a_scene_without_lights_gets_no_shadow_rays() {
        let exp = experiment(
            "scenes = [\"dark\", \"lit\"]\ntracers = [\"reference\"]\nrays = [\"primary\", \"shadow\", \"diffuse\", \"reflection\", \"refraction\"]\n",
        );
        let plan = Plan::derive(&exp, &load_quads).unwrap();
        assert_eq!(
            plan.scenes[0].ray_kinds,
            vec![RayKind::Primary, RayKind::Diffuse]
        );
        assert_eq!(
            plan.scenes[0].notes[..3],
            [
                "no shadow rays: the scene has no lights",
                "no reflection rays: no material reflects",
                "no refraction rays: no material refracts"
            ]
        );
        assert_eq!(
            plan.scenes[1].ray_kinds,
            [RayKind::Primary, RayKind::Shadow, RayKind::Diffuse]
        );
        // 1 frame × 1 instance × 1 thread count × (2 + 3) kinds.
        assert_eq!(plan.measurements(), 5);
        assert!(plan
            .to_string()
            .contains("note: no shadow rays: the scene has no lights"));
        // Glass reflects and refracts.
        let exp = experiment(
            "scenes = [\"glass\"]\ntracers = [\"reference\"]\nrays = [\"reflection\", \"refraction\"]\n\
             render = { renderer = \"whitted\", max_depth = [1, 2] }\nthreads = [1, 2]\n",
        );
        let plan = Plan::derive(&exp, &load_quads).unwrap();
        assert_eq!(
            plan.scenes[0].ray_kinds,
            [RayKind::Reflection, RayKind::Refraction]
        );
        assert!(plan.scenes[0].notes.iter().all(|n| !n.starts_with("no ")));
        // (2 kinds + 2 render workloads) × 2 thread counts.
        assert_eq!(plan.measurements(), 8);
    }

    #[test]
    fn static_scene_builds_once_animated_scene_every_frame() {
        let exp = experiment("scenes = [\"lit\", \"moving\"]\ntracers = [\"reference\"]\nrays = [\"primary\"]\nframes = 3\n");
        let plan = Plan::derive(&exp, &load_quads).unwrap();
        let builds = |s: &ScenePlan| {
            (0..exp.frames).filter(|&f| s.builds_at(f)).count() * s.structures.len()
        };
        assert_eq!(builds(&plan.scenes[0]), 1);
        assert!(!plan.scenes[0].rebuild_per_frame);
        assert_eq!(builds(&plan.scenes[1]), 3);
        assert!(plan.scenes[1].rebuild_per_frame && plan.scenes[1].animated);
        assert_eq!(plan.measurements(), 6);
    }

    #[test]
    fn tracers_sharing_a_structure_share_its_build() {
        // embree1 and embree16 read the same Embree scene (default quality); embree4 at high
        // quality needs its own; secondary rays need our default BVH, built for that alone.
        let exp = experiment(
            "scenes = [\"lit\"]\ntracers = [\"embree1\", \"embree16\", { name = \"embree4\", params = { quality = \"high\" } }]\n\
             rays = [\"primary\", \"shadow\"]\n",
        );
        let plan = Plan::derive(&exp, &load_quads).unwrap();
        let structures = &plan.scenes[0].structures;
        let keys: Vec<String> = structures.iter().map(|s| s.key.to_string()).collect();
        assert_eq!(keys, ["embree", "embree[quality=high]", "bvh"]);
        let users: Vec<&[usize]> = structures.iter().map(|s| s.used_by.as_slice()).collect();
        assert_eq!(users, [&[0, 1][..], &[2][..], &[][..]]);
        assert!(structures[2].generates_secondary_rays && !structures[0].generates_secondary_rays);
        assert!(plan.instances.iter().all(|i| !i.counts_internals));

        // Keys compare parameters as written: {leaf_size=4} is not the default key {} although 4
        // is the default, so the secondary-ray BVH is a third structure here.
        let exp = experiment(
            "scenes = [\"lit\"]\ntracers = [{ name = \"reference\", params = { leaf_size = [2, 4] } }]\n\
             rays = [\"primary\", \"diffuse\"]\n",
        );
        let plan = Plan::derive(&exp, &load_quads).unwrap();
        let keys: Vec<String> = plan.scenes[0]
            .structures
            .iter()
            .map(|s| s.key.to_string())
            .collect();
        assert_eq!(keys, ["bvh[leaf_size=2]", "bvh[leaf_size=4]", "bvh"]);

        // The bare reference tracer uses the default BVH: one structure, shared with secondary rays.
        let exp = experiment(
            "scenes = [\"lit\"]\ntracers = [\"reference\"]\nrays = [\"primary\", \"diffuse\"]\n",
        );
        let plan = Plan::derive(&exp, &load_quads).unwrap();
        assert_eq!(plan.scenes[0].structures.len(), 1);
        assert_eq!(plan.scenes[0].structures[0].used_by, vec![0]);
        assert!(plan.scenes[0].structures[0].generates_secondary_rays);
        assert!(plan.instances[0].counts_internals);

        // Primary rays only: no secondary-ray structure at all.
        let exp = experiment(
            "scenes = [\"lit\"]\ntracers = [{ name = \"reference\", params = { leaf_size = 2 } }]\nrays = [\"primary\"]\n",
        );
        let plan = Plan::derive(&exp, &load_quads).unwrap();
        assert_eq!(plan.scenes[0].structures.len(), 1);
    }

    #[test]
    fn bad_parameter_values_fail_before_the_run() {
        let text = "name = \"t\"\nresolution = { width = 8, height = 8 }\nscenes = [\"lit\"]\n\
                    tracers = [{ name = \"reference\", params = { leaf_size = 0 } }]\nrays = [\"primary\"]\n";
        match Experiment::parse(std::path::Path::new("t.toml"), text).unwrap_err() {
            Error::Usage(m) => assert!(
                m.starts_with("t.toml:4: tracer reference[leaf_size=0]: BVH parameters"),
                "{m}"
            ),
            e => panic!("{e:?}"),
        }
    }

    #[test]
    fn an_unknown_scene_names_the_file_and_line_of_the_scenes_entry() {
        let exp = experiment(
            "tracers = [\"reference\"]\nrays = [\"primary\"]\nscenes = [\"lit\",\n  \"nowhere\"]\n",
        );
        match Plan::derive(&exp, &load_quads).unwrap_err() {
            Error::Usage(m) => assert_eq!(m, "t.toml:5: unknown scene \"nowhere\""),
            e => panic!("{e:?}"),
        }
    }
}
