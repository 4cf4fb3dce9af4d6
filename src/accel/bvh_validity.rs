//! Whether a `Bvh` is a valid tree over its triangles, whichever builder made it (ours with early
//! split clipping or spatial splits, or Embree's, `builder = "embree"`): what every traversal
//! assumes, checked in one place so a new builder is held to the same bar.

use super::bvh::Bvh;
use crate::geometry::{Aabb, Triangle};

/// The coverage check samples each triangle at barycentric (a, b) / GRID, a + b ≤ GRID: its
/// vertices, points on its edges and inside.
const GRID: usize = 4;

/// `Err` naming the first broken rule: the layout (children adjacent and after their parent, one
/// depth deeper, inside its box; leaves' ranges tiling the references; leaves no larger than
/// `leaf_size` above `max_depth`), the references (each a copy of the scene triangle its
/// `prim_ids` entry names, every triangle referenced), and coverage: every sampled point of every
/// triangle lies in the box of a leaf that references it (a split triangle's parts together cover
/// it).
pub fn check(bvh: &Bvh, triangles: &[Triangle]) -> Result<(), String> {
    let n = bvh.nodes.len();
    if bvh.depth.len() != n || bvh.pairs.len() != n {
        return Err(format!(
            "{n} nodes, {} depths, {} child pairs",
            bvh.depth.len(),
            bvh.pairs.len()
        ));
    }
    if bvh.prim_ids.len() != bvh.triangles.len() {
        return Err("prim_ids and triangles differ in length".into());
    }
    if triangles.is_empty() {
        return match bvh.is_empty() {
            true => Ok(()),
            false => Err("references in a tree over no triangles".into()),
        };
    }
    let mut ranges = Vec::new();
    let mut leaves_of: Vec<Vec<Aabb>> = vec![Vec::new(); triangles.len()];
    for (i, node) in bvh.nodes.iter().enumerate() {
        let depth = bvh.depth[i] as usize;
        if depth > bvh.config.max_depth {
            return Err(format!(
                "node {i} at depth {depth} > max_depth {}",
                bvh.config.max_depth
            ));
        }
        if node.is_leaf() {
            let (first, count) = (node.first as usize, node.count as usize);
            if count > bvh.config.max_leaf_size && depth < bvh.config.max_depth {
                return Err(format!("leaf {i} of {count} triangles above max_depth"));
            }
            if first + count > bvh.triangles.len() {
                return Err(format!("leaf {i} reaches past the references"));
            }
            ranges.push((first, count));
            for k in first..first + count {
                let id = bvh.prim_ids[k] as usize;
                match triangles.get(id) {
                    Some(t) if *t == bvh.triangles[k] => leaves_of[id].push(node.bounds),
                    _ => return Err(format!("reference {k} is not scene triangle {id}")),
                }
            }
            continue;
        }
        let first = node.first as usize;
        if first <= i || first + 1 >= n {
            return Err(format!(
                "node {i}'s children {first}, {} misplaced",
                first + 1
            ));
        }
        for c in [first, first + 1] {
            if !node.bounds.contains(&bvh.nodes[c].bounds) {
                return Err(format!("node {i}'s box does not contain child {c}'s"));
            }
            if bvh.depth[c] as usize != depth + 1 {
                return Err(format!("child {c} of node {i} not one level deeper"));
            }
        }
    }
    ranges.sort_unstable();
    let mut end = 0;
    for (first, count) in ranges {
        if first != end {
            return Err(format!("leaves' ranges leave a gap or overlap at {end}"));
        }
        end += count;
    }
    if end != bvh.triangles.len() {
        return Err(format!(
            "leaves hold {end} of {} references",
            bvh.triangles.len()
        ));
    }
    for (id, tri) in triangles.iter().enumerate() {
        if leaves_of[id].is_empty() {
            return Err(format!("triangle {id} is in no leaf"));
        }
        let whole = tri.bounds();
        for a in 0..=GRID {
            for b in 0..=(GRID - a) {
                let p = tri
                    .point(a as f32 / GRID as f32, b as f32 / GRID as f32)
                    .clamp(whole.min, whole.max);
                if !leaves_of[id].iter().any(|l| l.contains_point(p)) {
                    return Err(format!("triangle {id}: point {p:?} in no leaf of it"));
                }
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;
    use crate::accel::bvh::BvhConfig;
    use crate::random::SplitMix64;

    fn triangles(n: usize) -> Vec<Triangle> {
        let mut rng = SplitMix64::new(17);
        (0..n)
            .map(|_| {
                let p = rng.vec3(0.0, 10.0);
                Triangle::new(p, p + rng.vec3(0.0, 2.0), p + rng.vec3(0.0, 2.0))
            })
            .collect()
    }

    #[test]
    fn our_trees_pass_and_each_broken_rule_is_named() {
        let tris = triangles(600);
        for config in [
            BvhConfig::default(),
            BvhConfig {
                presplit: 0.5,
                spatial: 0.0,
                ..BvhConfig::default()
            },
        ] {
            check(&Bvh::build(&tris, config), &tris).unwrap();
        }
        let good = Bvh::build(&tris, BvhConfig::default());
        let breaks = |f: &dyn Fn(&mut Bvh), rule: &str| {
            let mut bvh = good.clone();
            f(&mut bvh);
            let err = check(&bvh, &tris).unwrap_err();
            assert!(err.contains(rule), "{err}");
        };
        // A child's box grown past its parent's.
        breaks(
            &|b| {
                let c = b.nodes[Bvh::ROOT].first as usize;
                b.nodes[c].bounds = b.nodes[c].bounds.grow(Vec3::splat(99.0));
            },
            "does not contain",
        );
        // A reference that is not the triangle its id names.
        breaks(&|b| b.prim_ids.swap(0, 1), "is not scene triangle");
        // A leaf shrunk to nothing around its triangles.
        breaks(
            &|b| {
                let leaf = b.nodes.iter().position(|n| n.is_leaf()).unwrap();
                let c = b.nodes[leaf].bounds.center();
                b.nodes[leaf].bounds = Aabb::new(c, c);
            },
            "in no leaf",
        );
        // The first leaf's range moved on by one: reference 0 is in no leaf.
        breaks(
            &|b| {
                let leaf = b
                    .nodes
                    .iter()
                    .position(|n| n.is_leaf() && n.first == 0)
                    .unwrap();
                b.nodes[leaf].first += 1;
            },
            "gap or overlap at 0",
        );
    }
}
