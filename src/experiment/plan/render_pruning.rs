//! Which render workloads a scene can tell apart, as the plan prunes ray kinds: a stage that
//! cannot occur on the scene (shadow rays without lights, reflection or refraction generations
//! without materials that reflect or refract, motion blur without animation) is left out of the
//! workload's settings, and a workload that then renders exactly what an earlier one renders is
//! not measured again on that scene. A motion-blurred workload on a static scene is left out:
//! nothing moves during its shutter. Every pruned thing is one line in the plan.

use crate::render::distribution::Integrator;
use crate::scene::{Material, Scene};

use crate::experiment::plan::config::{DistributionWorkload, RenderWorkload};

/// The workloads measured on a scene (indices into the experiment's `renders`) and one note per
/// pruned stage or workload.
#[derive(Debug, Default, PartialEq)]
pub struct PrunedRenders {
    pub kept: Vec<usize>,
    pub notes: Vec<String>,
}

/// What the scene's triangles are made of, under a workload's material preset.
struct Surfaces {
    /// Spawns reflection rays: mirror, glossy, or dielectric (Fresnel reflection).
    reflects: bool,
    refracts: bool,
}

impl Surfaces {
    fn of(scene: &Scene, preset: Option<crate::scene::scene_file::Preset>) -> Surfaces {
        let mut materials = scene.materials.clone();
        if let Some(preset) = preset {
            preset.apply_to_all(&mut materials);
        }
        let mut used = vec![false; materials.len()];
        for &m in &scene.mesh.material_ids {
            used[m as usize] = true;
        }
        let any =
            |test: fn(&Material) -> bool| materials.iter().zip(&used).any(|(m, &u)| u && test(m));
        Surfaces {
            reflects: any(|m| m.is_reflective() || m.is_refractive()),
            refracts: any(Material::is_refractive),
        }
    }
}

/// `workload` with the stages the scene cannot have taken out, and why; `None` when it cannot be
/// rendered on the scene at all.
fn effective(
    workload: &RenderWorkload,
    scene: &Scene,
) -> std::result::Result<(RenderWorkload, Vec<&'static str>), &'static str> {
    let mut pruned = Vec::new();
    match workload {
        RenderWorkload::Whitted(settings) => {
            let mut s = *settings;
            let surfaces = Surfaces::of(scene, s.materials);
            if s.shadows && scene.lights.is_empty() {
                s.shadows = false;
                pruned.push("no shadow stage (the scene has no lights)");
            }
            let (reflects, refracts) = (
                surfaces.reflects && s.reflection_depth() > 0,
                surfaces.refracts && s.refraction_depth() > 0,
            );
            if !reflects && s.reflection_depth() > 0 {
                pruned.push("no reflection generations (no material reflects)");
            }
            if !refracts && s.refraction_depth() > 0 {
                pruned.push("no refraction generations (no material refracts)");
            }
            if !reflects && !refracts {
                // Camera rays and shadows only: the depth limits and ray-tree pruning are moot.
                s.max_depth = 0;
                s.max_reflection_depth = None;
                s.max_refraction_depth = None;
                s.pruning = None;
            } else {
                s.max_reflection_depth = Some(if reflects { s.reflection_depth() } else { 0 });
                s.max_refraction_depth = Some(if refracts { s.refraction_depth() } else { 0 });
            }
            Ok((RenderWorkload::Whitted(s), pruned))
        }
        RenderWorkload::Distribution(w) => {
            if w.shutter.is_some() && !scene.is_animated() {
                return Err("motion blur on a static scene (nothing moves during the shutter)");
            }
            let mut settings = w.settings;
            // Distribution bounces follow mirror and glossy reflection only (Boulos et al. 2007
            // §4); path tracing bounces off every surface.
            let reflects = Surfaces::of(scene, None).reflects;
            if settings.integrator == Integrator::Distribution
                && settings.max_depth > 0
                && !reflects
            {
                settings.max_depth = 0;
                pruned.push("no reflection bounces (no material reflects)");
            }
            Ok((
                RenderWorkload::Distribution(DistributionWorkload { settings, ..*w }),
                pruned,
            ))
        }
    }
}

/// The generations a workload asks for.
fn max_depth(workload: &RenderWorkload) -> u32 {
    match workload {
        RenderWorkload::Whitted(s) => s.max_depth,
        RenderWorkload::Distribution(w) => w.settings.max_depth,
    }
}

/// Prunes `renders` for `scene`.
pub fn prune_renders(renders: &[RenderWorkload], scene: &Scene) -> PrunedRenders {
    let mut out = PrunedRenders::default();
    let mut kept_effective: Vec<(usize, RenderWorkload)> = Vec::new();
    for (r, workload) in renders.iter().enumerate() {
        match effective(workload, scene) {
            Err(why) => out.notes.push(format!("left out render {workload}: {why}")),
            Ok((effective, pruned)) => {
                for stage in pruned {
                    let note = format!("render workloads: {stage}");
                    if !out.notes.contains(&note) {
                        out.notes.push(note);
                    }
                }
                match kept_effective.iter().position(|(_, e)| *e == effective) {
                    // Of two workloads rendering the same, keep the one asking for the fewest
                    // generations: its settings say what is rendered (tables select by them).
                    Some(k) if max_depth(workload) < max_depth(&renders[kept_effective[k].0]) => {
                        let replaced = kept_effective[k].0;
                        out.notes.push(format!(
                            "left out render {}: renders the same as {workload} on this scene",
                            renders[replaced]
                        ));
                        kept_effective[k].0 = r;
                        let at = out.kept.iter().position(|&i| i == replaced);
                        out.kept[at.expect("a kept workload is in the kept list")] = r;
                    }
                    Some(k) => out.notes.push(format!(
                        "left out render {workload}: renders the same as {} on this scene",
                        renders[kept_effective[k].0]
                    )),
                    None => {
                        kept_effective.push((r, effective));
                        out.kept.push(r);
                    }
                }
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::experiment::plan::tests::{experiment, load_quads, quad_scene};
    use crate::experiment::plan::Plan;
    use crate::render::distribution::DrtSettings;
    use crate::render::whitted::WhittedSettings;
    use crate::scene::scene_file::Preset;

    fn whitted(max_depth: u32, shadows: bool) -> WhittedSettings {
        WhittedSettings {
            max_depth,
            shadows,
            ..WhittedSettings::default()
        }
    }

    #[test]
    fn stages_a_scene_cannot_have_are_pruned_and_duplicates_left_out() {
        let renders = [
            RenderWorkload::Whitted(whitted(2, true)),
            RenderWorkload::Whitted(whitted(0, false)),
            RenderWorkload::Whitted(WhittedSettings {
                pruning: None,
                ..whitted(3, false)
            }),
        ];
        // Unlit and diffuse: all three are camera rays and Lambert shading.
        let dark = quad_scene("dark", false, false);
        let pruned = prune_renders(&renders, &dark);
        // The one asking for depth 0 stays: its settings say what all three render.
        assert_eq!(pruned.kept, vec![1]);
        assert_eq!(
            pruned.notes,
            vec![
                "render workloads: no shadow stage (the scene has no lights)".to_string(),
                "render workloads: no reflection generations (no material reflects)".into(),
                "render workloads: no refraction generations (no material refracts)".into(),
                format!(
                    "left out render {}: renders the same as {} on this scene",
                    renders[0], renders[1]
                ),
                format!(
                    "left out render {}: renders the same as {} on this scene",
                    renders[2], renders[1]
                ),
            ]
        );
        // Lit: shadows or not differ; the depths still do not.
        let lit = quad_scene("lit", true, false);
        let pruned = prune_renders(&renders, &lit);
        assert_eq!(pruned.kept, vec![0, 1]);
        assert_eq!(pruned.notes.len(), 3, "{:?}", pruned.notes);
        assert!(pruned.notes[2].starts_with(&format!("left out render {}:", renders[2])));
    }

    #[test]
    fn a_glass_preset_keeps_refraction_the_scene_lacks() {
        let lit = quad_scene("lit", true, false);
        let renders = [
            RenderWorkload::Whitted(whitted(2, true)),
            RenderWorkload::Whitted(WhittedSettings {
                materials: Some(Preset::Glass),
                ..whitted(2, true)
            }),
            RenderWorkload::Whitted(WhittedSettings {
                materials: Some(Preset::Glass),
                max_refraction_depth: Some(0),
                ..whitted(2, true)
            }),
            RenderWorkload::Whitted(WhittedSettings {
                materials: Some(Preset::Mirror),
                max_refraction_depth: Some(0),
                ..whitted(2, true)
            }),
            RenderWorkload::Whitted(WhittedSettings {
                materials: Some(Preset::Mirror),
                ..whitted(2, true)
            }),
        ];
        let pruned = prune_renders(&renders, &lit);
        // Glass with and without refraction differ; a mirror never refracts, so its refraction
        // limit changes nothing.
        assert_eq!(pruned.kept, vec![0, 1, 2, 3]);
        assert_eq!(
            pruned.notes.last().unwrap(),
            &format!(
                "left out render {}: renders the same as {} on this scene",
                renders[4], renders[3]
            )
        );
    }

    #[test]
    fn motion_blur_needs_an_animated_scene() {
        let blurred = RenderWorkload::Distribution(DistributionWorkload {
            settings: DrtSettings::default(),
            shutter: Some(0.5),
            rmse: false,
        });
        let renders = [blurred.clone()];
        let pruned = prune_renders(&renders, &quad_scene("lit", true, false));
        assert_eq!(pruned.kept, Vec::<usize>::new());
        assert_eq!(
            pruned.notes,
            vec![format!(
                "left out render {blurred}: motion blur on a static scene (nothing moves during the shutter)"
            )]
        );
        // On the moving quad the shutter matters; its diffuse material still has no bounces.
        let pruned = prune_renders(&renders, &quad_scene("moving", true, true));
        assert_eq!(pruned.kept, vec![0]);
        assert_eq!(
            pruned.notes,
            vec!["render workloads: no reflection bounces (no material reflects)".to_string()]
        );
    }

    #[test]
    fn the_plan_measures_only_kept_workloads_and_says_what_it_left_out() {
        let exp = experiment(
            "scenes = [\"dark\", \"lit\"]\ntracers = [\"reference\"]\nrays = [\"primary\"]\n\
             render = { renderer = \"whitted\", max_depth = [0, 2], shadows = [true, false] }\n",
        );
        let plan = Plan::derive(&exp, &load_quads).unwrap();
        assert_eq!(plan.renders.len(), 4);
        assert_eq!(plan.scenes[0].renders.len(), 1);
        assert_eq!(plan.scenes[1].renders.len(), 2);
        // One frame, one instance, one thread count: (1 ray kind + kept renders) per scene.
        assert_eq!(plan.measurements(), (1 + 1) + (1 + 2));
        let printed = plan.to_string();
        assert_eq!(
            printed.matches("note: left out render").count(),
            3 + 2,
            "{printed}"
        );
    }
}
