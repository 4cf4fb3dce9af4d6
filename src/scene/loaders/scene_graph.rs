//! The transform hierarchy of an AFF file and the triangles under it.
//!
//! `xs` blocks hold fixed matrices, `x name` blocks the matrix of keyframe track `name` at the
//! time asked for (identity when no track has that name, as in BART's `GetMatrix`). A block's
//! world matrix is its parent's times its own. Triangles under fixed blocks only are moved to
//! world space once; the others stay in the coordinates of their innermost block and are
//! transformed for every frame. `tpa` triangles carry keyed vertex positions and move linearly
//! between them, held at the first and last key outside their range (BART's definition of
//! `tpa`); they also follow any blocks around them.
//!
//! Triangle order is file order at every time, so primitive ids stay stable across frames.

use std::collections::HashMap;
use std::ops::Range;
use std::sync::Arc;

use glam::{DMat4, Vec3};

use super::keyframes::TransformTrack;
use crate::geometry::Triangle;
use crate::scene::{Animation, Mesh};

/// A triangle whose vertices are keyed in time (`tpa`).
#[derive(Clone, Debug, PartialEq)]
pub struct Morph {
    /// Non-decreasing key times.
    pub times: Vec<f32>,
    pub positions: Vec<[Vec3; 3]>,
}

impl Morph {
    fn at(&self, t: f64) -> [Vec3; 3] {
        let last = self.times.len() - 1;
        let i = self.times.partition_point(|&k| f64::from(k) <= t);
        if i == 0 {
            return self.positions[0];
        }
        if i > last {
            return self.positions[last];
        }
        let (t0, t1) = (f64::from(self.times[i - 1]), f64::from(self.times[i]));
        let s = ((t - t0) / (t1 - t0)) as f32;
        let (a, b) = (self.positions[i - 1], self.positions[i]);
        [a[0].lerp(b[0], s), a[1].lerp(b[1], s), a[2].lerp(b[2], s)]
    }

    fn transformed(&self, m: &DMat4) -> Morph {
        Morph {
            times: self.times.clone(),
            positions: self
                .positions
                .iter()
                .map(|p| p.map(|v| apply(m, v)))
                .collect(),
        }
    }
}

/// The BART times of the first and the last frame (`a start end frames`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Clock {
    pub start: f64,
    pub end: f64,
}

#[derive(Clone, Debug)]
enum Local<T> {
    Fixed(DMat4),
    Keyframed(T),
}

#[derive(Clone, Debug)]
struct Node<T> {
    parent: Option<usize>,
    local: Local<T>,
}

#[derive(Clone, Debug)]
enum Items {
    Rigid(Range<usize>),
    Morphing(Range<usize>),
}

impl Items {
    /// Extends this run by `next` when both are of one kind and `next` starts where this ends.
    fn join(&mut self, next: &Items) -> bool {
        match (self, next) {
            (Items::Rigid(run), Items::Rigid(next))
            | (Items::Morphing(run), Items::Morphing(next))
                if run.end == next.start =>
            {
                run.end = next.end;
                true
            }
            _ => false,
        }
    }
}

/// A run of consecutive triangles under the same block (`None`: in world space).
#[derive(Clone, Debug)]
struct Batch {
    node: Option<usize>,
    items: Items,
}

/// The hierarchy while the file is read: blocks name their track.
#[derive(Default)]
pub struct SceneGraph {
    nodes: Vec<Node<String>>,
    open: Vec<usize>,
    batches: Vec<Batch>,
    triangles: Vec<Triangle>,
    morphs: Vec<Morph>,
    material_ids: Vec<u32>,
}

impl SceneGraph {
    pub fn open_fixed(&mut self, m: DMat4) {
        self.open(Local::Fixed(m));
    }

    pub fn open_keyframed(&mut self, track: &str) {
        self.open(Local::Keyframed(track.to_string()));
    }

    fn open(&mut self, local: Local<String>) {
        self.nodes.push(Node {
            parent: self.open.last().copied(),
            local,
        });
        self.open.push(self.nodes.len() - 1);
    }

    pub fn close(&mut self) {
        self.open.pop();
    }

    pub fn add_triangle(&mut self, tri: Triangle, material: u32) {
        let index = self.triangles.len();
        self.file_under_open_block(Items::Rigid(index..index + 1));
        self.triangles.push(tri);
        self.material_ids.push(material);
    }

    pub fn add_morph(&mut self, morph: Morph, material: u32) {
        let index = self.morphs.len();
        self.file_under_open_block(Items::Morphing(index..index + 1));
        self.morphs.push(morph);
        self.material_ids.push(material);
    }

    /// Puts `items` under the innermost open block: onto the last batch when it is the same
    /// block's and `items` continue its run, else into a new batch.
    fn file_under_open_block(&mut self, items: Items) {
        let node = self.open.last().copied();
        let joined = self
            .batches
            .last_mut()
            .is_some_and(|last| last.node == node && last.items.join(&items));
        if !joined {
            self.batches.push(Batch { node, items });
        }
    }

    /// The geometry at the clock's start and, when anything moves, the animation over the
    /// clock's range. Without a clock the file is a still at BART time 0.
    pub fn finish(
        self,
        tracks: &HashMap<String, TransformTrack>,
        clock: Option<Clock>,
    ) -> (Mesh, Option<Arc<dyn Animation>>) {
        let mut used_tracks: Vec<TransformTrack> = Vec::new();
        let mut track_index: HashMap<&str, usize> = HashMap::new();
        let nodes: Vec<Node<usize>> = self
            .nodes
            .iter()
            .map(|node| {
                let local = match &node.local {
                    Local::Fixed(m) => Local::Fixed(*m),
                    Local::Keyframed(name) => match tracks.get_key_value(name.as_str()) {
                        Some((key, track)) => Local::Keyframed(
                            *track_index.entry(key.as_str()).or_insert_with(|| {
                                used_tracks.push(track.clone());
                                used_tracks.len() - 1
                            }),
                        ),
                        None => Local::Fixed(DMat4::IDENTITY),
                    },
                };
                Node {
                    parent: node.parent,
                    local,
                }
            })
            .collect();

        // Blocks that move: keyframed ones and everything inside them. Fixed ones get their
        // world matrix now (parents come before children).
        let mut moving = vec![false; nodes.len()];
        let mut fixed_world = vec![DMat4::IDENTITY; nodes.len()];
        for (i, node) in nodes.iter().enumerate() {
            let parent_moving = node.parent.is_some_and(|p| moving[p]);
            let parent_world = node.parent.map_or(DMat4::IDENTITY, |p| fixed_world[p]);
            match node.local {
                Local::Fixed(m) if !parent_moving => fixed_world[i] = parent_world * m,
                _ => moving[i] = true,
            }
        }
        let mut animated = KeyframedMesh {
            start: 0.0,
            duration: 0.0,
            nodes,
            tracks: used_tracks,
            batches: self.batches,
            triangles: self.triangles,
            morphs: self.morphs,
            material_ids: self.material_ids,
        };
        animated.bake_fixed(&moving, &fixed_world);

        let moves =
            animated.batches.iter().any(|b| b.node.is_some()) || !animated.morphs.is_empty();
        match clock {
            Some(clock) if moves => {
                animated.start = clock.start;
                animated.duration = (clock.end - clock.start) as f32;
                let mesh = animated.mesh_at_bart_time(clock.start);
                (mesh, Some(Arc::new(animated)))
            }
            Some(clock) => (animated.mesh_at_bart_time(clock.start), None),
            None => (animated.mesh_at_bart_time(0.0), None),
        }
    }
}

/// Triangle soup over time: rigid parts under keyframed blocks and keyed `tpa` triangles.
#[derive(Debug)]
pub struct KeyframedMesh {
    /// BART time of scene time 0.
    start: f64,
    duration: f32,
    nodes: Vec<Node<usize>>,
    tracks: Vec<TransformTrack>,
    batches: Vec<Batch>,
    triangles: Vec<Triangle>,
    morphs: Vec<Morph>,
    material_ids: Vec<u32>,
}

fn apply(m: &DMat4, v: Vec3) -> Vec3 {
    m.transform_point3(v.as_dvec3()).as_vec3()
}

fn transform(m: &DMat4, tri: &Triangle) -> Triangle {
    Triangle {
        v: tri.v.map(|v| apply(m, v)),
    }
}

impl KeyframedMesh {
    /// Moves everything under fixed blocks only into world space.
    fn bake_fixed(&mut self, moving: &[bool], fixed_world: &[DMat4]) {
        for batch in &mut self.batches {
            let Some(node) = batch.node.filter(|&n| !moving[n]) else {
                continue;
            };
            let m = &fixed_world[node];
            match &batch.items {
                Items::Rigid(range) => {
                    for tri in &mut self.triangles[range.clone()] {
                        *tri = transform(m, tri);
                    }
                }
                Items::Morphing(range) => {
                    for morph in &mut self.morphs[range.clone()] {
                        *morph = morph.transformed(m);
                    }
                }
            }
            batch.node = None;
        }
    }

    fn mesh_at_bart_time(&self, t: f64) -> Mesh {
        let mut world: Vec<DMat4> = Vec::with_capacity(self.nodes.len());
        for node in &self.nodes {
            let local = match node.local {
                Local::Fixed(m) => m,
                Local::Keyframed(track) => self.tracks[track].matrix(t),
            };
            world.push(node.parent.map_or(local, |p| world[p] * local));
        }
        let mut triangles = Vec::with_capacity(self.material_ids.len());
        for batch in &self.batches {
            let m = batch.node.map(|n| &world[n]);
            match &batch.items {
                Items::Rigid(range) => {
                    let tris = &self.triangles[range.clone()];
                    match m {
                        Some(m) => triangles.extend(tris.iter().map(|tri| transform(m, tri))),
                        None => triangles.extend_from_slice(tris),
                    }
                }
                Items::Morphing(range) => {
                    for morph in &self.morphs[range.clone()] {
                        let tri = Triangle { v: morph.at(t) };
                        triangles.push(m.map_or(tri, |m| transform(m, &tri)));
                    }
                }
            }
        }
        Mesh {
            triangles,
            material_ids: self.material_ids.clone(),
        }
    }
}

impl Animation for KeyframedMesh {
    fn duration(&self) -> f32 {
        self.duration
    }

    fn mesh_at(&self, time: f32) -> Mesh {
        self.mesh_at_bart_time(self.start + f64::from(time))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn morph_interpolates_linearly_and_holds_outside() {
        let m = Morph {
            times: vec![0.0, 1.0, 3.0],
            positions: vec![[Vec3::ZERO; 3], [Vec3::X; 3], [Vec3::new(3.0, 2.0, 0.0); 3]],
        };
        assert_eq!(m.at(-1.0)[0], Vec3::ZERO);
        assert_eq!(m.at(0.5)[1], Vec3::new(0.5, 0.0, 0.0));
        assert_eq!(m.at(2.0)[2], Vec3::new(2.0, 1.0, 0.0));
        assert_eq!(m.at(7.0)[0], Vec3::new(3.0, 2.0, 0.0));
    }

    #[test]
    fn fixed_blocks_are_baked_and_order_is_kept() {
        let mut g = SceneGraph::default();
        let tri = Triangle::new(Vec3::ZERO, Vec3::X, Vec3::Y);
        g.add_triangle(tri, 0);
        g.open_fixed(DMat4::from_translation(glam::DVec3::new(0.0, 0.0, 5.0)));
        g.open_keyframed("nobody");
        g.add_triangle(tri, 1);
        g.close();
        g.close();
        g.add_triangle(tri, 2);
        let (mesh, animation) = g.finish(
            &HashMap::new(),
            Some(Clock {
                start: 0.0,
                end: 1.0,
            }),
        );
        // A block without keyframes is the identity: nothing moves.
        assert!(animation.is_none());
        assert_eq!(mesh.material_ids, [0, 1, 2]);
        assert_eq!(mesh.triangles[1].v[1], Vec3::new(1.0, 0.0, 5.0));
        assert_eq!(mesh.triangles[2], tri);
    }
}
