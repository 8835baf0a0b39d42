//! The body as an obstacle (seed 000 §5.4): front/back depth maps and the
//! image-based inside test of Eq. (13) ([`depth`], pure data), with the
//! exact winding-number test beside them ([`crate::geom::winding`]). The
//! maps come from a [`DepthRenderer`]: the wgpu renderer outside this crate
//! (`grade3d-render`), the CPU rasteriser inside it ([`raster`], for
//! machines whose only adapter is a CPU driver), or a test's reference.

pub mod depth;
pub mod raster;

use crate::geom::mesh::TriMesh;
use crate::geom::winding::{WindingOptions, WindingTree};
use depth::{DepthMap, ViewSet};

/// Knobs of the renderer.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default)]
pub struct RenderOptions {
    /// Depth-map resolution, pixels per side. Default 1024 (at 512 the
    /// inside test agrees with the exact one on 99.88 % of points, at 1024 on 99.92 %).
    pub resolution: u32,
    /// Which views. Default front/back and left/right.
    pub views: ViewSet,
    /// Margin around the body's bounding box, mm. Default 20.
    pub padding_mm: f64,
}

impl Default for RenderOptions {
    fn default() -> Self {
        Self { resolution: 1024, views: ViewSet::FrontBackSides, padding_mm: 20.0 }
    }
}

/// What renders a body's depth maps: the one thing collision needs from a
/// GPU (issue #16: the core takes the renderer as this trait; the wgpu one
/// lives outside it).
pub trait DepthRenderer {
    /// Why rendering failed.
    type Error;

    /// The front/back depth maps of `mesh`, one per view of `opts`
    /// ([`depth::View::set`] over the mesh's bounding box padded by
    /// [`RenderOptions::padding_mm`]), `opts.resolution` pixels a side.
    ///
    /// # Errors
    /// The renderer's own.
    fn depth_maps(&self, mesh: &TriMesh, opts: &RenderOptions) -> Result<Vec<DepthMap>, Self::Error>;
}

/// The body as an obstacle: its depth maps and its exact inside test.
#[derive(Debug)]
pub struct Obstacle {
    /// Depth maps of every view (Eq. 13).
    pub maps: Vec<DepthMap>,
    /// Winding-number hierarchy (exact final pass, measurements).
    pub tree: WindingTree,
}

impl Obstacle {
    /// `mesh` as an obstacle: its maps from `renderer` while its winding
    /// tree is built beside them on rayon's pool (issue #15).
    ///
    /// # Errors
    /// The renderer's.
    pub fn build<R: DepthRenderer + Sync>(
        mesh: &TriMesh,
        renderer: &R,
        render: &RenderOptions,
        winding: &WindingOptions,
    ) -> Result<Self, R::Error>
    where
        R::Error: Send,
    {
        let (maps, tree) = rayon::join(|| renderer.depth_maps(mesh, render), || WindingTree::new(mesh, winding));
        Ok(Self { maps: maps?, tree })
    }
}
