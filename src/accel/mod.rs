//! Acceleration structures. A run builds each distinct (kind, parameters) structure once per frame
//! and only for the tracers that need it (see `experiment::plan`).

pub mod bvh;
pub mod bvh_validity;
pub mod child_pairs;
pub mod embree;
pub mod grid;
pub mod libraries;
pub mod obvhs;
pub mod presplit;
pub mod spatial_split;
#[cfg(tinybvh)]
pub mod tinybvh;
pub mod wide_bvh;
pub mod wide_tree;

use std::sync::Arc;

use crate::error::{Error, Result};
use crate::params::Params;
use crate::scene::Mesh;
#[cfg(embree4)]
use embree::Embree4;
use embree::{BuildQuality, Device, EmbreeConfig, EmbreeScene};

pub use self::obvhs::{ObvhsBvh, ObvhsQuality};
pub use bvh::{Bvh, BvhBuilder, BvhConfig, BvhNode};
pub use grid::{Grid, GridConfig};
#[cfg(tinybvh)]
pub use tinybvh::{TinyBvh, TinyBvhConfig, TinyLayout};
pub use wide_bvh::{WideBvh, WideChild, WideEntry, WideNode};
pub use wide_tree::{BvhOfWidth, WideNodes, WideTree};

/// Which structure a tracer traverses.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum AccelKind {
    /// Our binned-SAH binary BVH.
    Bvh,
    /// Our binary BVH collapsed to 4 or 8 children per node (`WideTree`).
    Wide,
    /// Embree 3's own BVH over the mesh, built by the library (`quality`, `robust`).
    Embree,
    /// Embree 4's, with the same parameters (`accel::embree::v4`).
    #[cfg(embree4)]
    Embree4,
    /// obvhs's compressed 8-wide BVH, built by obvhs's own builder.
    Obvhs,
    /// Uniform grid with macrocells, rebuilt from scratch every frame (Wald et al. 2006, §3).
    Grid,
    /// One of tinybvh's layouts, built by tinybvh's own builders (`accel::tinybvh`).
    #[cfg(tinybvh)]
    TinyBvh(TinyLayout),
}

impl AccelKind {
    pub fn name(self) -> &'static str {
        match self {
            AccelKind::Bvh => "bvh",
            AccelKind::Wide => "wide_bvh",
            AccelKind::Embree => "embree",
            #[cfg(embree4)]
            AccelKind::Embree4 => "embree4",
            AccelKind::Obvhs => "obvhs",
            AccelKind::Grid => "grid",
            #[cfg(tinybvh)]
            AccelKind::TinyBvh(layout) => layout.name(),
        }
    }

    /// The parameters that change how this structure is built.
    pub fn params(self) -> &'static [&'static str] {
        match self {
            AccelKind::Bvh => BvhConfig::PARAMS,
            AccelKind::Wide => &WideTree::PARAMS,
            AccelKind::Embree => EmbreeConfig::PARAMS,
            #[cfg(embree4)]
            AccelKind::Embree4 => EmbreeConfig::PARAMS,
            AccelKind::Obvhs => ObvhsQuality::PARAMS,
            AccelKind::Grid => GridConfig::PARAMS,
            #[cfg(tinybvh)]
            AccelKind::TinyBvh(_) => TinyBvhConfig::PARAMS,
        }
    }

    /// Checks the structure's parameters as `build` reads them, without building anything.
    pub fn check_params(self, params: &Params) -> Result<()> {
        match self {
            AccelKind::Bvh => BvhConfig::from_params(params).map(drop),
            AccelKind::Wide => BvhConfig::from_params(params)
                .and(WideTree::width_from_params(params))
                .map(drop),
            AccelKind::Embree => EmbreeConfig::from_params(params).map(drop),
            #[cfg(embree4)]
            AccelKind::Embree4 => EmbreeConfig::from_params(params).map(drop),
            AccelKind::Obvhs => ObvhsQuality::from_params(params).map(drop),
            AccelKind::Grid => GridConfig::from_params(params).map(drop),
            #[cfg(tinybvh)]
            AccelKind::TinyBvh(_) => TinyBvhConfig::from_params(params).map(drop),
        }
    }

    /// The configuration this structure is built with from `params`, defaults included, as
    /// runs.csv's `resolved` column records it.
    pub fn resolved(self, params: &Params) -> Result<String> {
        Ok(match self {
            AccelKind::Bvh => format!("{:?}", BvhConfig::from_params(params)?),
            AccelKind::Wide => format!(
                "{:?}, width {}",
                BvhConfig::from_params(params)?,
                WideTree::width_from_params(params)?
            ),
            AccelKind::Embree => format!("{:?}", EmbreeConfig::from_params(params)?),
            #[cfg(embree4)]
            AccelKind::Embree4 => format!("{:?}", EmbreeConfig::from_params(params)?),
            AccelKind::Obvhs => format!("{:?}", ObvhsQuality::from_params(params)?),
            AccelKind::Grid => format!("{:?}", GridConfig::from_params(params)?),
            #[cfg(tinybvh)]
            AccelKind::TinyBvh(layout) => {
                format!("{layout:?}, {:?}", TinyBvhConfig::from_params(params)?)
            }
        })
    }

    pub fn build(self, mesh: &Mesh, params: &Params) -> Result<Accel> {
        Ok(match self {
            AccelKind::Bvh => Accel::Bvh(Arc::new(Bvh::build_with(
                &mesh.triangles,
                BvhConfig::from_params(params)?,
            )?)),
            AccelKind::Wide => Accel::Wide(Arc::new(WideTree::collapse(
                Arc::new(Bvh::build_with(
                    &mesh.triangles,
                    BvhConfig::from_params(params)?,
                )?),
                WideTree::width_from_params(params)?,
            )?)),
            AccelKind::Embree => Accel::Embree(Arc::new(EmbreeScene::build(
                Device::shared()?,
                mesh,
                EmbreeConfig::from_params(params)?,
            )?)),
            #[cfg(embree4)]
            AccelKind::Embree4 => Accel::Embree4(Arc::new(EmbreeScene::build(
                Device::<Embree4>::shared()?,
                mesh,
                EmbreeConfig::from_params(params)?,
            )?)),
            AccelKind::Obvhs => Accel::Obvhs(Arc::new(ObvhsBvh::build(
                &mesh.triangles,
                ObvhsQuality::from_params(params)?,
            )?)),
            AccelKind::Grid => Accel::Grid(Arc::new(Grid::build(
                &mesh.triangles,
                GridConfig::from_params(params)?,
            ))),
            #[cfg(tinybvh)]
            AccelKind::TinyBvh(layout) => Accel::TinyBvh(Arc::new(TinyBvh::build(
                &mesh.triangles,
                layout,
                TinyBvhConfig::from_params(params)?,
            )?)),
        })
    }
}

impl AccelKind {
    /// The structure over a mesh moving linearly from `open` to `close` during the shutter
    /// interval (motion blur): our BVH (`Bvh::build_moving`) and Embree's two-time-step scene.
    /// The other structures are built for one instant and refuse.
    pub fn build_moving(self, open: &Mesh, close: &Mesh, params: &Params) -> Result<Accel> {
        if open.len() != close.len() {
            return Err(Error::runtime(format!(
                "a moving mesh needs the same triangles at both ends: {} and {}",
                open.len(),
                close.len()
            )));
        }
        match self {
            AccelKind::Bvh => Ok(Accel::Bvh(Arc::new(Bvh::build_moving(
                &open.triangles,
                &close.triangles,
                BvhConfig::from_params(params)?.for_moving()?,
            )))),
            AccelKind::Wide => Ok(Accel::Wide(Arc::new(WideTree::collapse(
                Arc::new(Bvh::build_moving(
                    &open.triangles,
                    &close.triangles,
                    BvhConfig::from_params(params)?.for_moving()?,
                )),
                WideTree::width_from_params(params)?,
            )?))),
            AccelKind::Embree => Ok(Accel::Embree(Arc::new(EmbreeScene::build_moving(
                Device::shared()?,
                open,
                close,
                EmbreeConfig::from_params(params)?,
            )?))),
            #[cfg(embree4)]
            AccelKind::Embree4 => Ok(Accel::Embree4(Arc::new(EmbreeScene::build_moving(
                Device::<Embree4>::shared()?,
                open,
                close,
                EmbreeConfig::from_params(params)?,
            )?))),
            #[cfg(tinybvh)]
            AccelKind::TinyBvh(_) => Err(Error::usage(format!(
                "the {} structure has no motion blur (moving geometry needs bvh or embree)",
                self.name()
            ))),
            AccelKind::Obvhs | AccelKind::Grid => Err(Error::usage(format!(
                "the {} structure has no motion blur (moving geometry needs bvh or embree)",
                self.name()
            ))),
        }
    }

    /// The structure for a new frame's `mesh` (same triangle count and order as the previous
    /// frame's): an Embree scene built with quality `refit` and handed back unshared as `previous`
    /// is refitted in place (`EmbreeScene::refit`: the tree keeps its topology, its boxes move);
    /// every other structure is built from scratch, as the grid is (Wald et al. 2006, §3).
    pub fn rebuild(self, previous: Option<Accel>, mesh: &Mesh, params: &Params) -> Result<Accel> {
        match previous.filter(|_| self.refits(params)) {
            Some(Accel::Embree(mut scene)) => {
                if let Some(unshared) = Arc::get_mut(&mut scene) {
                    unshared.refit(mesh)?;
                    return Ok(Accel::Embree(scene));
                }
            }
            #[cfg(embree4)]
            Some(Accel::Embree4(mut scene)) => {
                if let Some(unshared) = Arc::get_mut(&mut scene) {
                    unshared.refit(mesh)?;
                    return Ok(Accel::Embree4(scene));
                }
            }
            _ => {}
        }
        self.build(mesh, params)
    }

    /// Whether it is a scene built by an Embree library (3 or 4).
    pub fn is_embree(self) -> bool {
        match self {
            AccelKind::Embree => true,
            #[cfg(embree4)]
            AccelKind::Embree4 => true,
            AccelKind::Bvh | AccelKind::Wide | AccelKind::Obvhs | AccelKind::Grid => false,
            #[cfg(tinybvh)]
            AccelKind::TinyBvh(_) => false,
        }
    }

    /// Whether `rebuild` updates this structure in place rather than building it anew.
    pub fn refits(self, params: &Params) -> bool {
        self.is_embree()
            && EmbreeConfig::from_params(params).is_ok_and(|c| c.quality == BuildQuality::Refit)
    }
}

/// A built structure, shared by every tracer that traverses it.
#[derive(Clone, Debug)]
pub enum Accel {
    Bvh(Arc<Bvh>),
    Wide(Arc<WideTree>),
    Embree(Arc<EmbreeScene>),
    #[cfg(embree4)]
    Embree4(Arc<EmbreeScene<Embree4>>),
    Obvhs(Arc<ObvhsBvh>),
    Grid(Arc<Grid>),
    #[cfg(tinybvh)]
    TinyBvh(Arc<TinyBvh>),
}

impl Accel {
    /// Whether it holds geometry moving over the shutter interval (motion blur).
    pub fn is_moving(&self) -> bool {
        match self {
            Accel::Bvh(b) => b.motion_end.is_some(),
            Accel::Wide(w) => w.bvh.motion_end.is_some(),
            Accel::Embree(s) => s.is_moving(),
            #[cfg(embree4)]
            Accel::Embree4(s) => s.is_moving(),
            Accel::Obvhs(_) | Accel::Grid(_) => false,
            #[cfg(tinybvh)]
            Accel::TinyBvh(_) => false,
        }
    }

    /// Our binary BVH, also the one a wide tree was collapsed from.
    pub fn bvh(&self) -> Result<&Arc<Bvh>> {
        match self {
            Accel::Bvh(b) => Ok(b),
            Accel::Wide(w) => Ok(&w.bvh),
            other => Err(other.not(AccelKind::Bvh)),
        }
    }

    /// The tree a tracer over our BVH walks: the binary one, or a wide one.
    pub fn tree(&self) -> Result<BvhOfWidth> {
        match self {
            Accel::Bvh(b) => Ok(BvhOfWidth::Binary(b.clone())),
            Accel::Wide(w) => Ok(BvhOfWidth::Wide(w.clone())),
            other => Err(other.not(AccelKind::Bvh)),
        }
    }

    pub fn embree(&self) -> Result<&Arc<EmbreeScene>> {
        match self {
            Accel::Embree(s) => Ok(s),
            other => Err(other.not(AccelKind::Embree)),
        }
    }

    #[cfg(embree4)]
    pub fn embree4(&self) -> Result<&Arc<EmbreeScene<Embree4>>> {
        match self {
            Accel::Embree4(s) => Ok(s),
            other => Err(other.not(AccelKind::Embree4)),
        }
    }

    pub fn obvhs(&self) -> Result<&Arc<ObvhsBvh>> {
        match self {
            Accel::Obvhs(b) => Ok(b),
            other => Err(other.not(AccelKind::Obvhs)),
        }
    }

    pub fn grid(&self) -> Result<&Arc<Grid>> {
        match self {
            Accel::Grid(g) => Ok(g),
            other => Err(other.not(AccelKind::Grid)),
        }
    }

    /// tinybvh's structure of `layout`.
    #[cfg(tinybvh)]
    pub fn tinybvh(&self, layout: TinyLayout) -> Result<&Arc<TinyBvh>> {
        match self {
            Accel::TinyBvh(b) if b.layout == layout => Ok(b),
            other => Err(other.not(AccelKind::TinyBvh(layout))),
        }
    }

    pub fn kind(&self) -> AccelKind {
        match self {
            Accel::Bvh(_) => AccelKind::Bvh,
            Accel::Wide(_) => AccelKind::Wide,
            Accel::Embree(_) => AccelKind::Embree,
            #[cfg(embree4)]
            Accel::Embree4(_) => AccelKind::Embree4,
            Accel::Obvhs(_) => AccelKind::Obvhs,
            Accel::Grid(_) => AccelKind::Grid,
            #[cfg(tinybvh)]
            Accel::TinyBvh(b) => AccelKind::TinyBvh(b.layout),
        }
    }

    /// The error of a tracer handed this structure when it traverses `wanted`.
    fn not(&self, wanted: AccelKind) -> Error {
        Error::runtime(format!(
            "a tracer over {} was given the {} structure",
            wanted.name(),
            self.kind().name()
        ))
    }

    /// The tree's SAH cost (`Bvh::sah_cost`) for our BVH, the one structure whose nodes we hold;
    /// `None` for the others.
    pub fn sah_cost(&self) -> Option<f64> {
        match self {
            Accel::Bvh(b) => Some(b.sah_cost()),
            Accel::Wide(w) => Some(w.bvh.sah_cost()),
            _ => None,
        }
    }

    pub fn build_seconds(&self) -> f64 {
        match self {
            Accel::Bvh(b) => b.build_seconds,
            Accel::Wide(w) => w.build_seconds,
            Accel::Embree(s) => s.build_seconds,
            #[cfg(embree4)]
            Accel::Embree4(s) => s.build_seconds,
            Accel::Obvhs(b) => b.build_seconds,
            Accel::Grid(g) => g.build_seconds,
            #[cfg(tinybvh)]
            Accel::TinyBvh(b) => b.build_seconds,
        }
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;
    use crate::geometry::Triangle;

    fn mesh(z: f32) -> Mesh {
        let mut mesh = Mesh::default();
        mesh.push(
            Triangle::new(Vec3::ZERO, Vec3::X, Vec3::new(0.0, 1.0, z)),
            0,
        );
        mesh
    }

    #[test]
    fn refit_embree_scenes_are_updated_in_place_others_rebuilt() {
        let refit = Params::new().with("quality", "refit");
        let first = AccelKind::Embree.build(&mesh(0.0), &refit).unwrap();
        let Accel::Embree(scene) = &first else {
            panic!("an Embree scene")
        };
        assert_eq!(scene.refits, 0);
        let next = AccelKind::Embree
            .rebuild(Some(first), &mesh(1.0), &refit)
            .unwrap();
        let Accel::Embree(scene) = &next else {
            panic!("an Embree scene")
        };
        assert_eq!(scene.refits, 1, "refitted, not rebuilt");
        assert!(AccelKind::Embree.refits(&refit));
        assert!(!AccelKind::Embree.refits(&Params::new().with("quality", "low")));
        assert!(!AccelKind::Grid.refits(&Params::new()));
        // A scene still shared with a tracer cannot be refitted: it is built anew.
        let shared = next.clone();
        let rebuilt = AccelKind::Embree
            .rebuild(Some(next), &mesh(2.0), &refit)
            .unwrap();
        let (Accel::Embree(a), Accel::Embree(b)) = (&shared, &rebuilt) else {
            panic!("Embree scenes")
        };
        assert!(!Arc::ptr_eq(a, b));
        assert_eq!(
            (a.refits, b.refits),
            (1, 0),
            "the shared scene untouched, a new one built"
        );
    }
}
