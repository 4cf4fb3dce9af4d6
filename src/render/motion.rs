//! Moving geometry for motion blur (Boulos et al. 2007 §4: "each frame corresponds to a continuous
//! interval of time ... As each ray has a fixed time stamp, different rays may potentially see the
//! same triangle at different positions"). A moving mesh is the scene's animation at shutter open
//! (frame time `t`) and at shutter close (`t + shutter`), every vertex moving linearly in between;
//! a ray at time τ ∈ [0, 1) meets triangle `i` at `open[i] + τ·(close[i] − open[i])`.

use crate::error::{Error, Result};
use crate::geometry::{Hit, Ray, Triangle};
use crate::render::rays::SurfacePoint;
use crate::scene::{Mesh, Scene};
use crate::tracers::{make_tracer, Params, Tracer, TracerConfig, TracerInfo};

#[derive(Clone, Debug, PartialEq)]
pub struct MovingMesh {
    /// The mesh at shutter open: triangles, and the material ids of both ends.
    pub open: Mesh,
    /// Triangles at shutter close, same count and order as `open`.
    pub close: Vec<Triangle>,
}

impl MovingMesh {
    pub fn new(open: Mesh, close: &Mesh) -> Result<MovingMesh> {
        if open.len() != close.len() {
            return Err(Error::runtime(format!(
                "a moving mesh needs the same triangles at both ends: {} at open, {} at close",
                open.len(),
                close.len()
            )));
        }
        Ok(MovingMesh {
            close: close.triangles.clone(),
            open,
        })
    }

    /// The scene's geometry over the shutter interval `[time, time + shutter]` (seconds of the
    /// scene's animation); an error for a scene without animation, which cannot blur.
    pub fn of_scene(scene: &Scene, time: f32, shutter: f32) -> Result<MovingMesh> {
        let Some(animation) = &scene.animation else {
            return Err(Error::usage(format!(
                "scene {} has no animation: nothing moves during the shutter interval",
                scene.name
            )));
        };
        if !(shutter.is_finite() && shutter > 0.0) {
            return Err(Error::usage(format!(
                "shutter must be a positive number of seconds, got {shutter}"
            )));
        }
        MovingMesh::new(animation.mesh_at(time), &animation.mesh_at(time + shutter))
    }

    pub fn len(&self) -> usize {
        self.open.len()
    }

    pub fn is_empty(&self) -> bool {
        self.open.is_empty()
    }

    pub fn material_ids(&self) -> &[u32] {
        &self.open.material_ids
    }

    /// Triangle `prim` at `time`.
    pub fn triangle(&self, prim: u32, time: f32) -> Triangle {
        let i = prim as usize;
        self.open.triangles[i].lerp(&self.close[i], time)
    }

    /// The mesh frozen at `time` (for tests and for building a static structure).
    pub fn mesh_at(&self, time: f32) -> Mesh {
        Mesh {
            triangles: (0..self.len() as u32)
                .map(|i| self.triangle(i, time))
                .collect(),
            material_ids: self.open.material_ids.clone(),
        }
    }

    /// Where `ray` hit the triangle of `hit`, as it was at the ray's time.
    pub fn surface_at(&self, ray: &Ray, hit: &Hit) -> SurfacePoint {
        SurfacePoint::on_triangle(&self.triangle(hit.prim, ray.time), ray, hit)
    }
}

/// Tracer `info` in its configuration `config` (`info.config(params)`, parsed once by the caller)
/// over `moving`: its structure built for motion (`AccelKind::build_moving`), so rays are traced at
/// their time. Only the tracers whose entry says `motion_blur` can; the others are refused
/// (`AccelKind::build_moving`, `make_tracer`).
pub fn tracer_for_motion(
    info: &TracerInfo,
    config: &TracerConfig,
    params: &Params,
    moving: &MovingMesh,
) -> Result<Box<dyn Tracer>> {
    let close = Mesh {
        triangles: moving.close.clone(),
        material_ids: moving.open.material_ids.clone(),
    };
    let (kind, structure_params) = info.structure(config, params);
    let accel = kind.build_moving(&moving.open, &close, &structure_params)?;
    make_tracer(info, config, &accel)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{RayBatch, RayKind};
    use crate::render::rays::primary_rays;
    use crate::render::sampling::uniform;
    use crate::scene::library::load_scene;
    use crate::tracers::chunked::{trace_hits, trace_occlusion};
    use crate::tracers::{oracle_params, tracer_for_frame};

    /// `tracer_for_motion` for tracer `name` with `params`.
    fn by_name(name: &str, params: &Params, moving: &MovingMesh) -> Result<Box<dyn Tracer>> {
        let info = TracerInfo::find(name)?;
        tracer_for_motion(info, &info.config(params)?, params, moving)
    }

    /// The deforming flag over [1.0 s, 1.25 s]: every flag vertex moves.
    fn moving_flag() -> (Scene, MovingMesh) {
        let scene = load_scene("deforming", Some(22)).unwrap();
        let moving = MovingMesh::of_scene(&scene, 1.0, 0.25).unwrap();
        (scene, moving)
    }

    fn rays_at(scene: &Scene, time: Option<f32>) -> RayBatch {
        let camera_rays = primary_rays(&scene.camera, 96, 96);
        let mut batch = RayBatch::new(RayKind::Primary);
        for i in 0..camera_rays.len() {
            let t = time.unwrap_or_else(|| uniform(21, i as u64, 0));
            batch.push(camera_rays.ray(i).at_time(t), camera_rays.pixel[i]);
        }
        batch
    }

    #[test]
    fn static_scenes_and_bad_shutters_are_refused() {
        let room = load_scene("room", None).unwrap();
        assert!(MovingMesh::of_scene(&room, 0.0, 0.1).is_err());
        let flag = load_scene("deforming", Some(22)).unwrap();
        assert!(MovingMesh::of_scene(&flag, 0.0, 0.0).is_err());
        assert!(MovingMesh::of_scene(&flag, 0.0, f32::NAN).is_err());
        let (_, moving) = moving_flag();
        assert!(by_name("grid-dda", &Params::new(), &moving).is_err());
    }

    /// A ray at time 0 sees the frame-t mesh, at time 1 the frame-(t + shutter) mesh: the moving
    /// tracers give exactly the hits of static tracers built over those meshes.
    #[test]
    fn time_zero_and_one_hit_the_meshes_at_shutter_open_and_close() {
        let (scene, moving) = moving_flag();
        let animation = scene.animation.as_ref().unwrap();
        let moved = moving
            .open
            .triangles
            .iter()
            .zip(&moving.close)
            .filter(|(a, b)| a != b)
            .count();
        assert!(moved > 900, "{moved} triangles move");
        for (time, at) in [(0.0f32, 1.0f32), (1.0, 1.25)] {
            let frozen = animation.mesh_at(at);
            assert_eq!(moving.mesh_at(time), frozen);
            let frame = crate::scene::Frame {
                index: 0,
                time: at,
                mesh: std::borrow::Cow::Owned(frozen),
                camera: scene.camera,
            };
            let batch = rays_at(&scene, Some(time));
            for name in ["reference", "embree1"] {
                let still = trace_hits(
                    tracer_for_frame(name, &Params::new(), &frame)
                        .unwrap()
                        .as_ref(),
                    &batch,
                );
                let blurred = trace_hits(
                    by_name(name, &Params::new(), &moving).unwrap().as_ref(),
                    &batch,
                );
                let hits = still.iter().filter(|h| h.is_hit()).count();
                assert!(hits > batch.len() / 4, "{name}: only {hits} hits");
                for (i, (a, b)) in still.iter().zip(&blurred).enumerate() {
                    assert_eq!(a.prim, b.prim, "{name}, time {time}, ray {i}");
                    if a.is_hit() {
                        assert!((a.t - b.t).abs() <= 1e-5 * a.t, "{a:?} {b:?}");
                    }
                }
            }
        }
    }

    /// Rays at times spread over the shutter: the reference tracer and Embree agree ray by ray,
    /// up to ties at edges shared by two triangles (same distance, either triangle is right).
    #[test]
    fn reference_and_embree_agree_on_motion_blurred_rays() {
        let (scene, moving) = moving_flag();
        let batch = rays_at(&scene, None);
        assert!(batch.time.iter().any(|&t| t > 0.5) && batch.time.iter().any(|&t| t < 0.5));
        let ours = trace_hits(
            by_name("reference", &Params::new(), &moving)
                .unwrap()
                .as_ref(),
            &batch,
        );
        let embree = trace_hits(
            by_name("embree1", &oracle_params(), &moving)
                .unwrap()
                .as_ref(),
            &batch,
        );
        let mut ties = 0;
        for (i, (a, b)) in ours.iter().zip(&embree).enumerate() {
            assert_eq!(a.is_hit(), b.is_hit(), "ray {i}: {a:?} vs {b:?}");
            if a.is_hit() {
                assert!((a.t - b.t).abs() <= 1e-4 * a.t, "ray {i}: {a:?} vs {b:?}");
                ties += usize::from(a.prim != b.prim);
            }
        }
        assert!(ties * 1000 <= batch.len(), "{ties} different triangles");
        // The blur is real: rays at different times see the flag at different places.
        let hits = ours.iter().filter(|h| h.is_hit()).count();
        assert!(hits > batch.len() / 4);
    }

    /// The packet tracer on a moving BVH gives the reference tracer's hits bit for bit on rays
    /// spread over the shutter, with every traversal, with and without frustum culling (which
    /// must not cull triangles where they are not at the rays' times), and for occlusion.
    #[test]
    fn packet_tracer_agrees_with_the_reference_on_motion_blurred_rays() {
        let (scene, moving) = moving_flag();
        let batch = rays_at(&scene, None);
        let reference = by_name("reference", &Params::new(), &moving).unwrap();
        let want = trace_hits(reference.as_ref(), &batch);
        let mut shadows = batch.clone();
        shadows.kind = Some(RayKind::Shadow);
        let want_occluded = trace_occlusion(reference.as_ref(), &shadows);
        // The frozen mesh at time 0 answers differently: motion matters for these rays.
        let frame = crate::scene::Frame {
            index: 0,
            time: 1.0,
            mesh: std::borrow::Cow::Owned(moving.mesh_at(0.0)),
            camera: scene.camera,
        };
        let still = trace_hits(
            tracer_for_frame("packet", &Params::new(), &frame)
                .unwrap()
                .as_ref(),
            &batch,
        );
        let differ = still.iter().zip(&want).filter(|(a, b)| a != b).count();
        assert!(
            differ > batch.len() / 10,
            "only {differ} rays see the motion"
        );
        for traversal in ["masked", "ranged", "partition", "ia"] {
            for (frustum, lanes, packet) in [("true", "16", "8"), ("false", "4", "4")] {
                let params = Params::new()
                    .with("traversal", traversal)
                    .with("frustum", frustum)
                    .with("lanes", lanes)
                    .with("packet", packet);
                let packet = by_name("packet", &params, &moving).unwrap();
                let got = trace_hits(packet.as_ref(), &batch);
                for (i, (a, b)) in want.iter().zip(&got).enumerate() {
                    assert_eq!(a, b, "{traversal}, frustum {frustum}: ray {i}");
                }
                assert_eq!(
                    trace_occlusion(packet.as_ref(), &shadows),
                    want_occluded,
                    "{traversal}, frustum {frustum}: occlusion"
                );
            }
        }
    }

    /// Every tracer whose entry says `motion_blur` traces a moving structure; every other one
    /// refuses it.
    #[test]
    fn tracers_without_motion_blur_refuse_a_moving_structure() {
        let (_, moving) = moving_flag();
        for info in crate::tracers::TRACERS {
            let made = by_name(info.name, &Params::new(), &moving);
            assert_eq!(made.is_ok(), info.motion_blur, "{}", info.name);
        }
    }
}
