//! Collision as the service sees it (seed 000 §5.4): the core's
//! [`Obstacle`] and depth maps ([`depth`]), the wgpu renderer
//! ([`render`], the `grade3d-render` crate) and the per-body cache of
//! obstacles ([`cache`]).

pub use grade3d_core::collide::{depth, raster, DepthRenderer, Obstacle, RenderOptions};
pub use grade3d_render as render;

pub mod cache;
