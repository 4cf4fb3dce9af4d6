//! Finding scenes by name. A name resolves, in this order, to:
//!
//! 1. `builtin:<generator>` — that built-in generator;
//! 2. a path (it contains `/` or ends in `.toml` or a mesh extension) — that file;
//! 3. `<dir>/<name>.toml` for each directory of the search path: the project's `scenes/`
//!    (relative to the current directory, then the crate's own), then each directory of
//!    `$RAYLAB_SCENES` (colon-separated);
//! 4. a built-in generator of that name (so the built-ins work with no files at all).
//!
//! Mesh paths inside a scene file resolve against the file's own directory first, then each
//! `$RAYLAB_SCENES` directory (where the third-party benchmark data lives).

use std::path::{Path, PathBuf};

use crate::error::{Error, Result};
use crate::scene::scene_file::{Base, SceneFile};
use crate::scene::{builtin, loaders, Scene};

/// File extensions `loaders::load` reads.
pub const MESH_EXTENSIONS: &[&str] = &[".obj", ".ply", ".ply.gz", ".nff", ".aff"];
/// Longest `extends` chain followed before assuming a cycle.
const MAX_EXTENDS_DEPTH: usize = 16;

/// Where scenes are looked for.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SearchPath {
    /// The project's scene directories, searched first for `<name>.toml`.
    pub scene_dirs: Vec<PathBuf>,
    /// Data directories (`$RAYLAB_SCENES`): searched for `<name>.toml` after `scene_dirs`, and for
    /// the mesh files scene files name.
    pub data_dirs: Vec<PathBuf>,
}

impl SearchPath {
    /// `./scenes`, then `<crate>/scenes`; then `$RAYLAB_SCENES`, or when it is unset the
    /// project's shared data directory `<crate>/../shared/scenes` if it exists.
    pub fn from_env() -> SearchPath {
        let crate_dir = Path::new(env!("CARGO_MANIFEST_DIR"));
        let mut scene_dirs = Vec::new();
        for dir in [PathBuf::from("scenes"), crate_dir.join("scenes")] {
            let known = scene_dirs.iter().any(|d: &PathBuf| same_dir(d, &dir));
            if dir.is_dir() && !known {
                scene_dirs.push(dir);
            }
        }
        let data_dirs = match std::env::var_os("RAYLAB_SCENES") {
            Some(value) => std::env::split_paths(&value)
                .filter(|p| !p.as_os_str().is_empty())
                .collect(),
            None => {
                let shared = crate_dir.join("../shared/scenes");
                if shared.is_dir() {
                    vec![shared]
                } else {
                    Vec::new()
                }
            }
        };
        SearchPath {
            scene_dirs,
            data_dirs,
        }
    }

    /// Every directory searched for `<name>.toml`, in order.
    pub fn name_dirs(&self) -> impl Iterator<Item = &PathBuf> {
        self.scene_dirs.iter().chain(&self.data_dirs)
    }

    fn describe(dirs: &[&Path]) -> String {
        if dirs.is_empty() {
            "(no directories)".into()
        } else {
            dirs.iter()
                .map(|d| d.display().to_string())
                .collect::<Vec<_>>()
                .join(", ")
        }
    }
}

fn same_dir(a: &Path, b: &Path) -> bool {
    match (a.canonicalize(), b.canonicalize()) {
        (Ok(a), Ok(b)) => a == b,
        _ => a == b,
    }
}

/// Loads the scene `name` (see the module docs for how names resolve) with the built-in size
/// `size` (the scene's own, or the generator's default, when `None`).
pub fn load_scene(name: &str, size: Option<u32>) -> Result<Scene> {
    load_scene_in(name, size, &SearchPath::from_env())
}

/// `load_scene` over an explicit search path.
pub fn load_scene_in(name: &str, size: Option<u32>, search: &SearchPath) -> Result<Scene> {
    Resolver {
        search,
        chain: Vec::new(),
    }
    .scene(name, size)
}

/// Which mesh file `mesh` (as written in `scene_file`) names: relative to the scene file's
/// directory first, then to each data directory.
pub fn resolve_mesh(
    scene_file: &Path,
    mesh: &str,
    search: &SearchPath,
) -> std::result::Result<PathBuf, String> {
    let mesh = Path::new(mesh);
    let here = scene_file.parent().unwrap_or(Path::new("."));
    let candidates: Vec<&Path> = if mesh.is_absolute() {
        vec![Path::new("/")]
    } else {
        std::iter::once(here)
            .chain(search.data_dirs.iter().map(PathBuf::as_path))
            .collect()
    };
    candidates
        .iter()
        .map(|dir| dir.join(mesh))
        .find(|p| p.is_file())
        .ok_or_else(|| {
            format!(
                "mesh file '{}' not found; looked in: {}",
                mesh.display(),
                SearchPath::describe(&candidates)
            )
        })
}

/// Follows names to scenes, remembering the scene files of an `extends` chain to stop cycles.
struct Resolver<'a> {
    search: &'a SearchPath,
    chain: Vec<PathBuf>,
}

impl Resolver<'_> {
    fn scene(&mut self, name: &str, size: Option<u32>) -> Result<Scene> {
        if let Some(generator) = name.strip_prefix("builtin:") {
            return builtin::generate(generator, size);
        }
        if looks_like_path(name) {
            let path = Path::new(name);
            if path.is_dir() {
                return Err(Error::input(path, None, "a directory, not a scene file"));
            }
            if !path.is_file() {
                return Err(Error::input(path, None, "no such scene file"));
            }
            return self.file(path, size);
        }
        let file_name = format!("{name}.toml");
        if let Some(path) = self
            .search
            .name_dirs()
            .map(|d| d.join(&file_name))
            .find(|p| p.is_file())
        {
            return self.scene_file(&path, size);
        }
        if builtin::find(name).is_some() {
            return builtin::generate(name, size);
        }
        let dirs: Vec<&Path> = self.search.name_dirs().map(PathBuf::as_path).collect();
        Err(Error::usage(format!(
            "unknown scene '{name}': no {file_name} in {}, and no built-in generator of that name (built-ins: {})",
            SearchPath::describe(&dirs),
            builtin::known_names()
        )))
    }

    /// A scene file (`.toml`) or a mesh file given by path.
    fn file(&mut self, path: &Path, size: Option<u32>) -> Result<Scene> {
        if path.extension().is_some_and(|e| e == "toml") {
            return self.scene_file(path, size);
        }
        if size.is_some() {
            return Err(Error::usage(format!(
                "{}: `size` applies only to built-in scenes",
                path.display()
            )));
        }
        loaders::load(path)
    }

    fn scene_file(&mut self, path: &Path, size: Option<u32>) -> Result<Scene> {
        let file = SceneFile::read(path)?;
        let canonical = path.canonicalize().unwrap_or_else(|_| path.to_path_buf());
        if self.chain.contains(&canonical) || self.chain.len() >= MAX_EXTENDS_DEPTH {
            let span = file.spec.extends.as_ref().map_or(0..0, |e| e.span());
            let chain: Vec<String> = self
                .chain
                .iter()
                .chain([&canonical])
                .map(|p| p.display().to_string())
                .collect();
            return Err(file.error_at(span, format!("`extends` loops: {}", chain.join(" → "))));
        }
        let mut scene = match file.base()? {
            Base::Mesh(mesh) => {
                if size.is_some() {
                    return Err(Error::usage(format!(
                        "scene '{}' is a mesh file; `size` applies only to built-in scenes",
                        file.name()
                    )));
                }
                let span = file.spec.mesh.as_ref().map_or(0..0, |m| m.span());
                let mesh = resolve_mesh(path, &mesh, self.search)
                    .map_err(|message| file.error_at(span, message))?;
                loaders::load(&mesh)?
            }
            Base::Builtin(generator, own_size) => {
                let span = file.spec.builtin.as_ref().map_or(0..0, |b| b.span());
                if builtin::find(&generator).is_none() {
                    let message = format!(
                        "unknown built-in generator '{generator}' (built-ins: {})",
                        builtin::known_names()
                    );
                    return Err(file.error_at(span, message));
                }
                // A bad size is the file's fault only when the file chose it.
                let size_span = match (size, &file.spec.size) {
                    (None, Some(own)) => own.span(),
                    _ => span,
                };
                builtin::generate(&generator, size.or(own_size))
                    .map_err(|e| file.error_at(size_span, e.to_string()))?
            }
            Base::Extends(base, own_size) => {
                self.chain.push(canonical);
                let scene = self.scene(&base, size.or(own_size));
                self.chain.pop();
                scene?
            }
        };
        file.apply(&mut scene)?;
        Ok(scene)
    }
}

fn looks_like_path(name: &str) -> bool {
    name.contains('/')
        || name.ends_with(".toml")
        || MESH_EXTENSIONS.iter().any(|e| name.ends_with(e))
}

/// One entry of `raylab scenes`.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneListing {
    pub name: String,
    pub about: String,
    /// `builtin:<generator>`, `mesh:<file as written>` or `extends:<scene>`.
    pub source: String,
    /// The scene file, or `None` for a built-in generator without one.
    pub file: Option<PathBuf>,
    /// Why the scene file cannot be used, if it cannot.
    pub problem: Option<String>,
}

/// Every scene `load_scene` can find by name: the scene files of the search path (the first of
/// each name, as lookup finds it) and the built-ins no scene file shadows.
pub fn list_scenes() -> Vec<SceneListing> {
    list_scenes_in(&SearchPath::from_env())
}

/// `list_scenes` over an explicit search path.
pub fn list_scenes_in(search: &SearchPath) -> Vec<SceneListing> {
    let mut listings: Vec<SceneListing> = Vec::new();
    for dir in search.name_dirs() {
        let Ok(entries) = std::fs::read_dir(dir) else {
            continue;
        };
        let mut files: Vec<PathBuf> = entries
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.extension().is_some_and(|e| e == "toml"))
            .collect();
        files.sort();
        for path in files {
            let name = path
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default();
            if listings.iter().any(|l| l.name == name) {
                continue;
            }
            listings.push(listing(name, path));
        }
    }
    for &(name, about) in builtin::BUILTINS {
        if !listings.iter().any(|l| l.name == name) {
            listings.push(SceneListing {
                name: name.into(),
                about: about.into(),
                source: format!("builtin:{name}"),
                file: None,
                problem: None,
            });
        }
    }
    listings
}

/// What a scene file says about itself, without building it. Listed under its lookup name (the
/// file name), which is what `load_scene` takes.
fn listing(name: String, path: PathBuf) -> SceneListing {
    let parsed = SceneFile::read(&path).and_then(|file| file.base().map(|base| (file, base)));
    match parsed {
        Ok((file, base)) => SceneListing {
            name,
            about: file.spec.about.clone().unwrap_or_default(),
            source: match base {
                Base::Mesh(mesh) => format!("mesh:{mesh}"),
                Base::Builtin(generator, _) => format!("builtin:{generator}"),
                Base::Extends(scene, _) => format!("extends:{scene}"),
            },
            file: Some(path),
            problem: None,
        },
        Err(e) => SceneListing {
            name,
            about: String::new(),
            source: String::new(),
            file: Some(path),
            problem: Some(e.to_string()),
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::atomic::{AtomicUsize, Ordering};

    /// A fresh directory under the system temp dir, removed on drop.
    struct TempDir(PathBuf);

    impl TempDir {
        fn new() -> TempDir {
            static NEXT: AtomicUsize = AtomicUsize::new(0);
            let n = NEXT.fetch_add(1, Ordering::Relaxed);
            let dir =
                std::env::temp_dir().join(format!("raylab-library-{}-{n}", std::process::id()));
            std::fs::create_dir_all(&dir).unwrap();
            TempDir(dir)
        }

        fn write(&self, name: &str, text: &str) -> PathBuf {
            let path = self.0.join(name);
            std::fs::create_dir_all(path.parent().unwrap()).unwrap();
            std::fs::write(&path, text).unwrap();
            path
        }
    }

    impl Drop for TempDir {
        fn drop(&mut self) {
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }

    fn search(scene_dirs: &[&TempDir], data_dirs: &[&TempDir]) -> SearchPath {
        SearchPath {
            scene_dirs: scene_dirs.iter().map(|d| d.0.clone()).collect(),
            data_dirs: data_dirs.iter().map(|d| d.0.clone()).collect(),
        }
    }

    #[test]
    fn a_scene_file_on_the_data_path_is_found_and_scenes_dir_wins() {
        let (project, data) = (TempDir::new(), TempDir::new());
        data.write("tiny.toml", "builtin = \"room\"\nsize = 1\n");
        let only_data = search(&[], &[&data]);
        let scene = load_scene_in("tiny", None, &only_data).unwrap();
        assert_eq!((scene.name.as_str(), scene.triangle_count()), ("tiny", 96));

        // The same name in the project's scenes/ shadows the data directory's.
        project.write("tiny.toml", "builtin = \"room\"\nsize = 2\n");
        let both = search(&[&project], &[&data]);
        assert_eq!(
            load_scene_in("tiny", None, &both).unwrap().triangle_count(),
            384
        );
        // An explicit size overrides the file's.
        assert_eq!(
            load_scene_in("tiny", Some(3), &both)
                .unwrap()
                .triangle_count(),
            864
        );

        let listed = list_scenes_in(&both);
        let tiny: Vec<&SceneListing> = listed.iter().filter(|l| l.name == "tiny").collect();
        assert_eq!(tiny.len(), 1);
        assert_eq!(
            tiny[0].file.as_deref(),
            Some(project.0.join("tiny.toml").as_path())
        );
        assert_eq!(tiny[0].source, "builtin:room");
        // Every built-in is listed (none is shadowed here).
        assert_eq!(
            listed.iter().filter(|l| l.file.is_none()).count(),
            builtin::BUILTINS.len()
        );
    }

    #[test]
    fn built_ins_resolve_with_no_files_and_scene_files_can_shadow_them() {
        let nothing = SearchPath::default();
        assert_eq!(
            load_scene_in("room", None, &nothing).unwrap().source,
            "builtin:room"
        );
        assert_eq!(
            load_scene_in("builtin:deforming", Some(22), &nothing)
                .unwrap()
                .triangle_count(),
            994
        );
        let project = TempDir::new();
        project.write(
            "room.toml",
            "name = \"my room\"\nbuiltin = \"room\"\n[materials]\nall = \"mirror\"\n",
        );
        let scene = load_scene_in("room", Some(1), &search(&[&project], &[])).unwrap();
        assert_eq!(scene.name, "my room");
        assert!(scene.materials.iter().all(|m| m.mirror > 0.0));
        // The prefix bypasses scene files.
        assert_eq!(
            load_scene_in("builtin:room", Some(1), &search(&[&project], &[]))
                .unwrap()
                .name,
            "room"
        );
    }

    #[test]
    fn extends_layers_overrides_and_detects_cycles() {
        let project = TempDir::new();
        project.write(
            "base.toml",
            "builtin = \"room\"\nsize = 1\n[camera]\nfov = 70.0\n",
        );
        project.write(
            "shiny.toml",
            "extends = \"base\"\n[materials]\nall = \"glossy\"\n",
        );
        let dirs = search(&[&project], &[]);
        let scene = load_scene_in("shiny", None, &dirs).unwrap();
        assert_eq!(
            (
                scene.name.as_str(),
                scene.camera.fov_y_deg,
                scene.triangle_count()
            ),
            ("shiny", 70.0, 96)
        );
        assert!(scene.materials.iter().all(|m| m.glossy.is_some()));

        // a → b → a: reported at a.toml's `extends` line when a comes round again.
        let a = project.write("a.toml", "\nextends = \"b\"\n");
        project.write("b.toml", "extends = \"a\"\n");
        let err = load_scene_in("a", None, &dirs).unwrap_err().to_string();
        assert!(
            err.starts_with(&format!("{}:2: `extends` loops:", a.display())),
            "{err}"
        );
        assert!(err.ends_with("a.toml"), "{err}");
    }

    #[test]
    fn unknown_names_missing_meshes_and_bad_builtins_are_errors_with_places() {
        let (project, data) = (TempDir::new(), TempDir::new());
        let dirs = search(&[&project], &[&data]);
        let err = load_scene_in("atlantis", None, &dirs).unwrap_err();
        assert_eq!(err.exit_code(), 2);
        let message = err.to_string();
        assert!(
            message.contains("atlantis.toml") && message.contains(&project.0.display().to_string())
        );
        assert!(
            message.contains(&data.0.display().to_string()) && message.contains("room, rings"),
            "{message}"
        );

        let file = project.write(
            "ghost.toml",
            "# a mesh that is nowhere\nmesh = \"ghost/ghost.obj\"\n",
        );
        let message = load_scene_in("ghost", None, &dirs).unwrap_err().to_string();
        assert!(
            message.starts_with(&format!("{}:2:", file.display())),
            "{message}"
        );
        assert!(
            message.contains("ghost/ghost.obj") && message.contains(&data.0.display().to_string()),
            "{message}"
        );

        let file = project.write("odd.toml", "builtin = \"cathedral\"\n");
        let message = load_scene_in("odd", None, &dirs).unwrap_err().to_string();
        assert!(
            message.starts_with(&format!("{}:1:", file.display())) && message.contains("cathedral"),
            "{message}"
        );

        let file = project.write("big.toml", "builtin = \"balls\"\nsize = 9\n");
        let message = load_scene_in("big", None, &dirs).unwrap_err().to_string();
        assert!(
            message.starts_with(&format!("{}:2:", file.display())) && message.contains("1..=5"),
            "{message}"
        );

        let message = load_scene_in("no/such/file.toml", None, &dirs)
            .unwrap_err()
            .to_string();
        assert!(
            message.contains("no/such/file.toml") && message.contains("no such scene file"),
            "{message}"
        );
        // A directory named like a mesh file was once "no such scene file".
        let folder = project.0.join("folder.obj");
        std::fs::create_dir_all(&folder).unwrap();
        let err = load_scene_in(folder.to_str().unwrap(), None, &dirs).unwrap_err();
        assert_eq!(err.exit_code(), 2);
        assert_eq!(
            err.to_string(),
            format!("{}: a directory, not a scene file", folder.display())
        );

        // Listing survives the broken file and reports it.
        project.write("broken.toml", "mesh = \n");
        let broken = list_scenes_in(&dirs)
            .into_iter()
            .find(|l| l.name == "broken")
            .unwrap();
        assert!(broken.problem.unwrap().contains("broken.toml:1:"));
    }

    /// The project's scene files: every one parses, its overrides apply, built-in ones build, and
    /// each mesh it names exists in the benchmark data (when that data is present).
    #[test]
    fn the_repository_scene_files_are_valid_and_their_meshes_exist() {
        let crate_dir = Path::new(env!("CARGO_MANIFEST_DIR"));
        let data = std::env::var_os("RAYLAB_SCENES")
            .map_or_else(|| crate_dir.join("../shared/scenes"), PathBuf::from);
        let project = SearchPath {
            scene_dirs: vec![crate_dir.join("scenes")],
            data_dirs: vec![data.clone()],
        };
        let listed = list_scenes_in(&project);
        let files: Vec<&SceneListing> = listed.iter().filter(|l| l.file.is_some()).collect();
        assert!(files.len() >= 25, "only {} scene files", files.len());
        for listing in files {
            assert_eq!(listing.problem, None, "{}", listing.name);
            let path = listing.file.as_ref().unwrap();
            let file = SceneFile::read(path).unwrap();
            // Camera, path, lights and material presets are valid on any scene.
            file.apply(&mut builtin::generate("room", Some(1)).unwrap())
                .unwrap();
            match file.base().unwrap() {
                Base::Mesh(mesh) if data.is_dir() => {
                    assert_eq!(
                        resolve_mesh(path, &mesh, &project),
                        Ok(data.join(&mesh)),
                        "{}",
                        listing.name
                    );
                }
                Base::Mesh(_) => println!(
                    "note: {} not found, skipping {}",
                    data.display(),
                    listing.name
                ),
                Base::Builtin(..) => {
                    let scene = load_scene_in(&listing.name, Some(1), &project).unwrap();
                    assert_eq!(scene.name, listing.name);
                }
                Base::Extends(base, _) => assert!(listed.iter().any(|l| l.name == base), "{base}"),
            }
        }
        // The reflective variant of the room puts a mirror on every one of its materials.
        let room = load_scene_in("room-reflective", Some(1), &project).unwrap();
        assert_eq!(room.materials.len(), 7);
        assert!(room
            .materials
            .iter()
            .all(|m| m.mirror == crate::scene::scene_file::MIRROR_REFLECTANCE));
    }

    #[test]
    fn mesh_paths_resolve_next_to_the_scene_file_then_on_the_data_path() {
        let (project, data) = (TempDir::new(), TempDir::new());
        let dirs = search(&[&project], &[&data]);
        let scene_file = project.0.join("model.toml");
        let in_data = data.write("model/model.obj", "v 0 0 0\n");
        assert_eq!(
            resolve_mesh(&scene_file, "model/model.obj", &dirs),
            Ok(in_data)
        );
        let beside = project.write("model/model.obj", "v 0 0 0\n");
        assert_eq!(
            resolve_mesh(&scene_file, "model/model.obj", &dirs),
            Ok(beside.clone())
        );
        assert_eq!(
            resolve_mesh(&scene_file, beside.to_str().unwrap(), &dirs),
            Ok(beside)
        );
        assert!(resolve_mesh(&scene_file, "model/other.obj", &dirs)
            .unwrap_err()
            .contains("model/other.obj"));
    }
}
