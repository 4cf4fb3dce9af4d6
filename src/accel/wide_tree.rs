//! The wide BVH as a structure of its own: the binary SAH tree (`Bvh`) collapsed to 4 or 8
//! children per node (`WideBvh::collapse`), built once per scene, BVH parameters and width, its
//! build time (the binary build plus the collapse) in the build column, and shared by every tracer
//! that walks it: wide-single, packet and multi-frusta with `width = 4 | 8`, the stream tracer's
//! single-ray hand-off with `single_tree = 4 | 8`.

use std::sync::Arc;
use std::time::Instant;

use super::bvh::{Bvh, BvhConfig};
use super::wide_bvh::WideBvh;
use crate::error::{Error, Result};
use crate::params::{concat_keys, Params};

/// The collapsed nodes, of either width.
#[derive(Clone, Debug)]
pub enum WideNodes {
    Four(WideBvh<4>),
    Eight(WideBvh<8>),
}

impl WideNodes {
    /// Children per node.
    pub fn children(&self) -> usize {
        match self {
            WideNodes::Four(_) => 4,
            WideNodes::Eight(_) => 8,
        }
    }
}

/// A binary tree and its collapse: the leaves (and their triangles) are the binary tree's.
#[derive(Clone, Debug)]
pub struct WideTree {
    pub bvh: Arc<Bvh>,
    pub nodes: WideNodes,
    /// The binary tree's build plus the collapse.
    pub build_seconds: f64,
}

impl WideTree {
    /// Children per node a wide tree may have.
    pub const WIDTHS: [usize; 2] = [4, 8];
    /// Its parameters: the binary tree's, then `width` (which the plan sets from the tracer's
    /// tree width, `TracerConfig::tree_width`).
    pub const PARAMS: [&'static str; BvhConfig::PARAMS.len() + 1] =
        concat_keys(BvhConfig::PARAMS, &["width"]);

    /// The `width` parameter (default 8), checked.
    pub fn width_from_params(params: &Params) -> Result<usize> {
        let width = params.get_or("width", 8usize)?;
        match Self::WIDTHS.contains(&width) {
            true => Ok(width),
            false => Err(Self::bad_width(width)),
        }
    }

    fn bad_width(width: usize) -> Error {
        Error::usage(format!(
            "a wide BVH has {:?} children per node (got {width})",
            Self::WIDTHS
        ))
    }

    /// `bvh` collapsed to `width` children per node (one of `WIDTHS`).
    pub fn collapse(bvh: Arc<Bvh>, width: usize) -> Result<WideTree> {
        let start = Instant::now();
        let nodes = match width {
            4 => WideNodes::Four(WideBvh::collapse(&bvh)),
            8 => WideNodes::Eight(WideBvh::collapse(&bvh)),
            _ => return Err(Self::bad_width(width)),
        };
        let build_seconds = bvh.build_seconds + start.elapsed().as_secs_f64();
        Ok(WideTree {
            bvh,
            nodes,
            build_seconds,
        })
    }
}

/// The tree a tracer over our BVH walks: the binary tree itself, or a wide tree collapsed from it.
#[derive(Clone, Debug)]
pub enum BvhOfWidth {
    Binary(Arc<Bvh>),
    Wide(Arc<WideTree>),
}

impl BvhOfWidth {
    /// `bvh` with `width` children per node: itself for 2, else collapsed here (for a tracer made
    /// outside a run, whose structures come built: `Accel::tree`).
    pub fn of_width(bvh: Arc<Bvh>, width: usize) -> Result<BvhOfWidth> {
        match width {
            2 => Ok(BvhOfWidth::Binary(bvh)),
            _ => Ok(BvhOfWidth::Wide(Arc::new(WideTree::collapse(bvh, width)?))),
        }
    }

    /// The binary tree (the wide tree's leaves and triangles are its).
    pub fn bvh(&self) -> &Arc<Bvh> {
        match self {
            BvhOfWidth::Binary(bvh) => bvh,
            BvhOfWidth::Wide(wide) => &wide.bvh,
        }
    }

    /// The wide nodes; `None` for the binary tree.
    pub fn wide(&self) -> Option<&WideNodes> {
        match self {
            BvhOfWidth::Binary(_) => None,
            BvhOfWidth::Wide(wide) => Some(&wide.nodes),
        }
    }
}

impl From<Arc<Bvh>> for BvhOfWidth {
    fn from(bvh: Arc<Bvh>) -> Self {
        BvhOfWidth::Binary(bvh)
    }
}
