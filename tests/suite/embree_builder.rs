//! Our BVH built by Embree's builder (`builder = "embree"`, issue 29) on real and built-in scenes:
//! a valid tree in our layout (`accel::bvh_validity`: every triangle referenced, boxes nesting,
//! leaves' boxes covering their triangles' parts), no larger than `leaf_size` and `max_depth`
//! allow, with an SAH cost near our best tree's (both builders use the same cost constants; the
//! costs are printed). Hits over it are checked in tests/suite/embree_agreement.rs.

use raylab::accel::bvh_validity;
use raylab::accel::{Accel, AccelKind, Bvh};
use raylab::params::Params;
use raylab::scene::library::load_scene;

/// Built-in scenes (rings: long slivers, where spatial splits matter) and conference, when the
/// real scenes are on RAYLAB_SCENES.
fn scenes() -> Vec<&'static str> {
    let mut scenes = vec!["room", "rings", "marbles"];
    match load_scene("conference", None) {
        Ok(_) => scenes.push("conference"),
        Err(e) => {
            eprintln!("NOTE: conference skipped ({e}); set RAYLAB_SCENES to ../shared/scenes")
        }
    }
    scenes
}

fn tree(accel: Accel) -> std::sync::Arc<Bvh> {
    accel.bvh().unwrap().clone()
}

#[test]
fn embree_built_trees_are_valid_and_close_to_our_best_in_sah_cost() {
    let ours = Params::new()
        .with("presplit", 0.0)
        .with("bins", 32)
        .with("spatial", 1e-5);
    let embree = Params::new().with("builder", "embree");
    for name in scenes() {
        let scene = load_scene(name, None).unwrap();
        let mesh = scene.frame(0, 1).mesh.into_owned();
        let (a, b) = (
            tree(AccelKind::Bvh.build(&mesh, &ours).unwrap()),
            tree(AccelKind::Bvh.build(&mesh, &embree).unwrap()),
        );
        for (who, bvh) in [("ours", &a), ("Embree's", &b)] {
            if let Err(broken) = bvh_validity::check(bvh, &mesh.triangles) {
                panic!("{name}, {who} tree: {broken}");
            }
        }
        assert!(b.nodes.iter().all(|n| !n.is_leaf() || n.count <= 4));
        assert!(b.max_depth() <= 48);
        let ratio = b.sah_cost() / a.sah_cost();
        println!(
            "{name} ({} triangles): SAH cost ours {:.3}, Embree's builder {:.3} ({ratio:.3}×); \
             references {} / {}; depth {} / {}",
            mesh.triangles.len(),
            a.sah_cost(),
            b.sah_cost(),
            a.triangles.len(),
            b.triangles.len(),
            a.max_depth(),
            b.max_depth()
        );
        // Where our spatial splits add more references than Embree's budget (1.2 per triangle)
        // allows, as on rings' slivers, Embree's tree is cut short of ours: a looser bound.
        let within_budget = a.triangles.len() as f64 <= 1.2 * mesh.triangles.len() as f64;
        let bound = if within_budget { 1.25 } else { 1.6 };
        assert!(
            (0.8..bound).contains(&ratio),
            "{name}: Embree's tree costs {ratio}× ours"
        );
        // Embree's split budget: 1.2 references per triangle at most.
        assert!(b.triangles.len() as f64 <= 1.2 * mesh.triangles.len() as f64 + 1.0);
    }
}
