//! The body as an obstacle (seed 000 §5.4): front/back depth maps and the
//! image-based inside test of Eq. (13) ([`depth`], pure data: the maps come
//! from a renderer outside this crate), with the exact winding-number test
//! beside them ([`crate::geom::winding`]).

pub mod depth;

use crate::geom::winding::WindingTree;
use depth::DepthMap;

/// The body as an obstacle: its depth maps and its exact inside test.
#[derive(Debug)]
pub struct Obstacle {
    /// Depth maps of every view (Eq. 13).
    pub maps: Vec<DepthMap>,
    /// Winding-number hierarchy (exact final pass, measurements).
    pub tree: WindingTree,
}
